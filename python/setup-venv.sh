#!/usr/bin/env bash
# Creates BUILD_DIR/venv (default build/venv) with python/requirements-dev.txt installed:
# nanobind for the module's CMake build, scikit-build-core for `pip install ./python`,
# numpy, scipy and pytest for python/tests. Reused as long as the requirements' SHA-256
# matches the stamp written after the last successful install. The package robodiff is
# installed into it as the build tree's copy (a .pth file naming BUILD_DIR/python, where
# the CMake build puts the module), so `BUILD_DIR/venv/bin/python -c "import robodiff"`
# works once the module is built, and every rebuild is what it imports.
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir="${1:-build}"
venv="$build_dir/venv"
requirements="python/requirements-dev.txt"
stamp="$venv/.requirements.sha256"
wanted="$(sha256sum "$requirements" | cut -d' ' -f1)"

# The build tree's robodiff on the environment's path (rewritten each time: cheap, and
# right after the build folder moved).
link_build_tree() {
  local site
  site="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
  realpath -m "$build_dir/python" > "$site/robodiff-build-tree.pth"
}

if [ -x "$venv/bin/python" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$wanted" ]; then
  link_build_tree
  echo "setup-venv: $venv is up to date"
  exit 0
fi

echo "setup-venv: creating $venv from $requirements"
mkdir -p "$build_dir"
rm -f "$stamp"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$requirements"
link_build_tree
echo "$wanted" > "$stamp"
