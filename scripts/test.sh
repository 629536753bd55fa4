#!/usr/bin/env bash
# The test command, from a fresh Debian 12 machine: install what is missing, build
# everything, run every test with ctest. Benchmarks are built but not run (bench/).
set -euo pipefail
cd "$(dirname "$0")/.."

deploy/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" --timeout 600
