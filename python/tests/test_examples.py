"""examples/python/: each example run as a user runs it (a subprocess, local mode on a
warmed cache, arm7), its results checked against what they claim and against the C++
side: the MPC's cost goes down and the tool reaches the target; the identification
recovers the URDF's base parameters within their standard errors and fits the torques
exactly as `robodiff identify` does on the same CSV; the torque plot's values match
`robodiff compute --backend reference`, a PNG is written where matplotlib imports and a
clear message replaces it where it does not."""

import argparse
import json
import os
import pathlib
import shlex
import shutil
import subprocess
import sys

import numpy as np
import pytest

import robodiff
from conftest import ARM7, REPO, SPECS, robodiff_cli

EXAMPLES = REPO / "examples" / "python"
EXTRA_SPECS = [EXAMPLES / "specs" / "euler_step.json", EXAMPLES / "specs" / "arm7_reach_residual.json",
               SPECS / "regressor.json"]
MODULE_PATH = pathlib.Path(robodiff.__file__).resolve().parents[1]  # build/python

sys.path.insert(0, str(EXAMPLES))
import example_support  # noqa: E402  (the examples' own helpers)
from base_parameters import base_parameters  # noqa: E402
from urdf_parameters import inertial_parameters  # noqa: E402


@pytest.fixture(scope="module")
def examples_cache(cache_dir, tmp_path_factory) -> pathlib.Path:
    """A copy of the session cache (RNEA's Jacobian, compiled once) plus the examples'
    other arm7 functions; a copy, so that the session cache keeps what other tests expect."""
    directory = tmp_path_factory.mktemp("examples") / "robodiff"
    shutil.copytree(cache_dir, directory)
    command = [str(robodiff_cli()), "warmup", "--urdf", str(ARM7), "--cache", str(directory)]
    for spec in EXTRA_SPECS:
        command += ["--spec", str(spec)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    return directory


def run_example(script: str, cache: pathlib.Path, *arguments, python=sys.executable, pythonpath=()):
    """Runs an example in local mode; returns the finished process (not checked)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([*map(str, pythonpath), str(MODULE_PATH), env.get("PYTHONPATH", "")])
    command = [str(python), str(EXAMPLES / script), "--server", "local", "--cache-dir", str(cache),
               *map(str, arguments)]
    return subprocess.run(command, capture_output=True, text=True, timeout=120, env=env, cwd=REPO)


def run_json(script: str, cache: pathlib.Path, *arguments, **options) -> dict:
    done = run_example(script, cache, *arguments, "--json", **options)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_mpc_horizon_lowers_the_cost_and_reaches_the_target(examples_cache):
    result = run_json("mpc_horizon.py", examples_cache, "--iterations", "5")
    costs = result["costs"]
    assert result["knots"] == 20 and result["mode"] == "local" and len(costs) == 6
    assert all(later <= earlier for earlier, later in zip(costs, costs[1:])), costs
    assert costs[-1] < 0.2 * costs[0], costs  # Gauss-Newton on a reaching task: a large drop
    assert result["final_distance"] < 0.02 < result["start_distance"]
    assert np.all(np.isfinite(result["torque_first_knot"])) and np.abs(result["torque_first_knot"]).max() > 1.0


def test_a_missing_function_is_reported_with_a_warmup_command_that_works(tmp_path, capsys):
    # In process: a running robodiffd (another test's) would compile a missing function
    # for a subprocess even in local mode, so the error is raised here as the client does.
    args = argparse.Namespace(urdf=ARM7, cache_dir=tmp_path / "robodiff", warmup=False)

    def main(_):
        raise robodiff.Error("FAILED_PRECONDITION", "function crba is not in the local cache")

    with pytest.raises(SystemExit) as exited:
        example_support.run(main, args, [SPECS / "crba.json"])
    assert exited.value.code == 1
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "robodiff: FAILED_PRECONDITION: function crba is not in the local cache"
    command = shlex.split(lines[-1])
    assert command[:2] == ["build/bin/robodiff", "warmup"] and "Traceback" not in lines
    # The printed command fills that cache: a local Client then finds the function there.
    subprocess.run([str(robodiff_cli()), *command[1:]], check=True, capture_output=True, timeout=120, cwd=REPO)
    model = robodiff.Client("local", cache_dir=args.cache_dir).load(ARM7)
    assert model.function(SPECS / "crba.json")(q=np.zeros(7))["value"].shape == (7, 7)


def test_the_warmup_option_builds_into_the_cache_first(examples_cache):
    if not hasattr(robodiff, "warmup"):
        pytest.skip("this build of the module has no robodiff.warmup")
    done = run_example("plot_torques.py", examples_cache, "--warmup", "--knots", "10", "--json")
    assert done.returncode == 0, done.stderr
    assert "warmup: rnea cached" in done.stderr  # compiled by the fixture: found, not rebuilt
    assert json.loads(done.stdout.strip().splitlines()[-1])["joints"][0]["joint"] == "joint1"


def test_identification_recovers_the_base_parameters_and_matches_the_cli(examples_cache, tmp_path):
    samples = tmp_path / "samples.csv"
    noise = 0.02
    result = run_json("identify_from_csv.py", examples_cache, "--samples", "300", "--noise", noise,
                      "--seed", "3", "--write-csv", samples)
    truth, estimate, stderr = (np.array(result[k]) for k in ("truth", "estimate", "stderr"))
    assert len(truth) == len(estimate) == len(result["names"]) < result["standard_parameters"] == 70
    assert np.all(np.abs(estimate - truth) < 5 * stderr), (estimate - truth) / stderr
    assert np.linalg.norm(estimate - truth) < 1e-2 * np.linalg.norm(truth)
    np.testing.assert_allclose(result["residual_rms"], noise, rtol=0.25)

    # The C++ fit of the same CSV: the same number of base parameters and the same fitted torques
    # (OLS's residual does not depend on which base is chosen).
    done = subprocess.run([str(robodiff_cli()), "identify", "--urdf", str(ARM7), "--data", str(samples),
                           "--cache", str(examples_cache), "--json"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    cli = json.loads(done.stdout)
    assert len(cli["base_parameters"]) == len(estimate)
    np.testing.assert_allclose(result["residual_rms"], cli["residual_rms"]["fit"], rtol=1e-6)

    # The URDF as the example reads it (plain Python) against the C++ model: the CLI's
    # priors are its base mapping applied to the C++ model's parameters.
    standard = inertial_parameters(ARM7, [f"joint{i}" for i in range(1, 8)])
    mapping = cli["base_mapping"]
    ours = standard[mapping["independent"]] + np.array(mapping["K"]) @ standard[mapping["dependent"]]
    np.testing.assert_allclose(ours, [b["prior"] for b in cli["base_parameters"]], rtol=1e-9, atol=1e-12)

    # Reading the CSV back gives the same fit as the samples it was written from.
    again = run_json("identify_from_csv.py", examples_cache, "--csv", samples)
    np.testing.assert_allclose(again["estimate"], estimate, rtol=1e-9, atol=1e-12)


def test_base_parameters_fold_a_known_dependency():
    # Column 2 = 2 * column 0 + column 1: two base parameters, pi_2 folded into both.
    rng = np.random.default_rng(1)
    w = rng.normal(size=(20, 2))
    w = np.column_stack([w, 2 * w[:, 0] + w[:, 1]])
    base = base_parameters(w)
    assert len(base.independent) == 2 and len(base.dependent) == 1
    pi = np.array([0.3, -0.7, 1.1])
    np.testing.assert_allclose(w[:, base.independent] @ base.of(pi), w @ pi, atol=1e-12)


def reference_torque(q, v, a, tmp_path) -> dict:
    """RNEA and its Jacobian from `robodiff compute --backend reference` (no generated code)."""
    state = tmp_path / "state.json"
    state.write_text(json.dumps({"q": list(q), "v": list(v), "a": list(a)}))
    done = subprocess.run([str(robodiff_cli()), "compute", "--urdf", str(ARM7),
                           "--spec", str(SPECS / "rnea_jacobian.json"),
                           "--backend", "reference", "--state", str(state), "--derivatives"],
                          check=True, capture_output=True, text=True, timeout=120)
    return json.loads(done.stdout)


def test_plot_without_matplotlib_says_so_and_its_values_match_the_reference(examples_cache, tmp_path):
    hidden = tmp_path / "hide"
    (hidden / "matplotlib").mkdir(parents=True)
    (hidden / "matplotlib" / "__init__.py").write_text("raise ImportError('hidden by the test')\n")
    table, png = tmp_path / "knots.csv", tmp_path / "torques.png"
    done = run_example("plot_torques.py", examples_cache, "--knots", "50", "--out", png, "--csv", table,
                       "--json", pythonpath=[hidden])
    assert done.returncode == 0, done.stderr
    assert "matplotlib is not importable (hidden by the test): no plot written" in done.stdout
    assert not png.exists()
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    assert summary["plotted"] is False and len(summary["joints"]) == 7

    header = table.read_text().splitlines()[0].split(",")
    rows = np.loadtxt(table, delimiter=",", skiprows=1)
    assert rows.shape == (50, len(header))
    column = lambda name, k: rows[k, [header.index(f"{name}_joint{i}") for i in range(1, 8)]]
    for k in (0, 31):
        expected = reference_torque(column("q", k), column("v", k), column("a", k), tmp_path)
        jacobian = np.array(expected["jacobian"])
        np.testing.assert_allclose(column("tau", k), expected["value"], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(column("dq_norm", k), np.linalg.norm(jacobian[:, :7], axis=1), rtol=1e-9)
        np.testing.assert_allclose(column("dv_norm", k), np.linalg.norm(jacobian[:, 7:14], axis=1), rtol=1e-9)
    peaks = np.abs(rows[:, [header.index(f"tau_joint{i}") for i in range(1, 8)]]).max(axis=0)
    np.testing.assert_allclose([abs(j["peak_tau"]) for j in summary["joints"]], peaks, rtol=1e-12)


def python_with_matplotlib():
    """This interpreter when it has matplotlib, else Debian's python3 when it has matplotlib
    and can import the built module (the same CPython minor version), else None."""
    candidates = [sys.executable, shutil.which("python3", path="/usr/bin")]
    probe = "import matplotlib, numpy, robodiff"
    for python in filter(None, candidates):
        env = dict(os.environ, PYTHONPATH=str(MODULE_PATH))
        if subprocess.run([python, "-c", probe], env=env, capture_output=True, timeout=60).returncode == 0:
            return python
    return None


def test_plot_writes_a_png_where_matplotlib_imports(examples_cache, tmp_path):
    python = python_with_matplotlib()
    if python is None:
        pytest.skip("no interpreter here imports matplotlib with robodiff "
                    "(Debian: apt-get install python3-matplotlib)")
    png = tmp_path / "torques.png"
    summary = run_json("plot_torques.py", examples_cache, "--knots", "60", "--out", png, python=python)
    assert summary["plotted"] is True and summary["out"] == str(png)
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert (width, height) == (800, 900)  # figsize (8, 9) at 100 dpi
    assert len(data) > 20_000  # three panels of curves, not an empty canvas
