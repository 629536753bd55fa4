#!/usr/bin/env bash
# Creates BUILD_DIR/venv (default build/venv) with python/requirements-dev.txt installed:
# nanobind for the module's CMake build, scikit-build-core for `pip install ./python`,
# numpy, scipy and pytest for python/tests. Reused as long as the requirements' SHA-256
# matches the stamp written after the last successful install.
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir="${1:-build}"
venv="$build_dir/venv"
requirements="python/requirements-dev.txt"
stamp="$venv/.requirements.sha256"
wanted="$(sha256sum "$requirements" | cut -d' ' -f1)"

if [ -x "$venv/bin/python" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$wanted" ]; then
  echo "setup-venv: $venv is up to date"
  exit 0
fi

echo "setup-venv: creating $venv from $requirements"
mkdir -p "$build_dir"
rm -f "$stamp"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$requirements"
echo "$wanted" > "$stamp"
