"""Fixtures: a temporary cache warmed by the real `robodiff warmup` (no server), and a
local-mode Client on it. The robodiff CLI is build/bin/robodiff unless $ROBODIFF_CLI says."""

import os
import pathlib
import subprocess

import pytest

import robodiff

REPO = pathlib.Path(__file__).resolve().parents[2]
ARM7 = REPO / "examples" / "robots" / "arm7.urdf"
SPECS = REPO / "examples" / "specs"
WARMED_SPECS = ["rnea_jacobian.json", "rnea_jacobian_sparse.json", "crba.json"]


def robodiff_cli() -> pathlib.Path:
    return pathlib.Path(os.environ.get("ROBODIFF_CLI", REPO / "build" / "bin" / "robodiff"))


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory) -> pathlib.Path:
    """A cache holding arm7's RNEA with its Jacobian (dense and sparse) and CRBA."""
    directory = tmp_path_factory.mktemp("cache") / "robodiff"
    command = [str(robodiff_cli()), "warmup", "--urdf", str(ARM7), "--cache", str(directory)]
    for spec in WARMED_SPECS:
        command += ["--spec", str(SPECS / spec)]
    subprocess.run(command, check=True, capture_output=True, text=True, timeout=300)
    return directory


@pytest.fixture(scope="session")
def client(cache_dir) -> robodiff.Client:
    return robodiff.Client("local", cache_dir=cache_dir)


@pytest.fixture(scope="session")
def arm7(client) -> robodiff.Model:
    return client.load(ARM7)


@pytest.fixture(scope="session")
def rnea(arm7) -> robodiff.Function:
    return arm7.function(SPECS / "rnea_jacobian.json")


@pytest.fixture(scope="session")
def rnea_sparse(arm7) -> robodiff.Function:
    return arm7.function(SPECS / "rnea_jacobian_sparse.json")


@pytest.fixture(scope="session")
def crba(arm7) -> robodiff.Function:
    return arm7.function(SPECS / "crba.json")
