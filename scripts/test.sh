#!/usr/bin/env bash
# The test command, from a fresh Debian 12 machine: install what is missing, build
# everything (the Python module too, with nanobind from build/venv), run every test with
# ctest, then the Python module's tests with pytest (build/venv imports the build tree's
# module: python/setup-venv.sh links it). Benchmarks are built but not run (bench/).
set -euo pipefail
cd "$(dirname "$0")/.."

deploy/install-deps.sh
python/setup-venv.sh build  # build/venv: nanobind, numpy, pytest (python/requirements-dev.txt)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE="$PWD/build/venv/bin/python"
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" --timeout 600
PYTHONDONTWRITEBYTECODE=1 build/venv/bin/python -m pytest python/tests -q -p no:cacheprovider
