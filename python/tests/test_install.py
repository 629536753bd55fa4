"""The build folder's virtual environment imports the build tree's robodiff with no
PYTHONPATH (python/setup-venv.sh installs it there as a .pth file), so the README's
`build/venv/bin/python -c "import robodiff"` works after its test command."""

import os
import pathlib
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
BUILD_VENV = REPO / "build" / "venv"


def test_the_build_venv_imports_the_build_trees_module_without_pythonpath(tmp_path):
    if pathlib.Path(sys.prefix).resolve() != BUILD_VENV.resolve():
        pytest.skip(f"run by {sys.prefix}, not by {BUILD_VENV} (the environment python/setup-venv.sh makes)")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    probe = "import robodiff, robodiff._robodiff as m; print(robodiff.__file__); print(m.__file__)"
    done = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    package, module = (pathlib.Path(line).resolve() for line in done.stdout.split())
    assert package.parent == (REPO / "build" / "python" / "robodiff").resolve()
    assert module.parent == package.parent and module.suffix == ".so"
