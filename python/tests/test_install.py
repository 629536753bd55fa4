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


def test_the_type_stubs_describe_the_module():
    """_robodiff.pyi (nanobind's stubgen at build time) parses and names what the module
    offers, with Function's call as users write it (stub_patterns.txt)."""
    import ast

    import robodiff._robodiff as native

    stub = pathlib.Path(native.__file__).with_name("_robodiff.pyi")
    tree = ast.parse(stub.read_text())
    classes = {node.name: node for node in tree.body if isinstance(node, ast.ClassDef)}
    for name in ("Client", "Function", "ModelInfo"):
        assert name in classes and hasattr(native, name)
    call = next(f for f in classes["Function"].body if isinstance(f, ast.FunctionDef) and f.name == "__call__")
    assert [a.arg for a in call.args.kwonlyargs] == ["out"] and call.args.kwarg.arg == "inputs"
    assert (pathlib.Path(native.__file__).parent / "py.typed").exists()
