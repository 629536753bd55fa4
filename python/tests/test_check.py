"""robodiff.check: the compiled functions pass the CLI's three-way check with the CLI's
rows, a function that computes something else fails it, and bad arguments are refused."""

import json
import subprocess

import pytest

import robodiff
from robodiff import _robodiff

from conftest import ARM7, SPECS, robodiff_cli


def test_the_compiled_rnea_jacobian_passes_every_comparison(arm7):
    result = robodiff.check(arm7, SPECS / "rnea_jacobian.json", samples=2, seed=3)
    assert result and result.passed and not result.failures
    rows = [(c.output, c.against) for c in result.comparisons]
    assert rows == [("value", "reference (core/dynamics)"), ("value", "interpreted"),
                    ("jacobian", "finite differences"), ("jacobian", "interpreted")]
    for c in result.comparisons:
        assert c.state in (0, 1) and c.seed in (3, 4)
        assert 0 <= c.worst_rel_error <= c.tolerance
    assert "all 4 comparisons pass" in str(result)


def test_rows_and_tolerances_are_those_of_the_cli(arm7):
    done = subprocess.run([str(robodiff_cli()), "check", "--urdf", str(ARM7), "--spec", str(SPECS / "crba.json"),
                           "--samples", "2", "--json"], capture_output=True, text=True, timeout=120, check=True)
    cli = json.loads(done.stdout)
    result = robodiff.check(arm7, json.loads((SPECS / "crba.json").read_text()), samples=2)
    assert result.function == cli["function"] and result.passed == cli["pass"]
    assert [(c.output, c.against, c.tolerance) for c in result.comparisons] == \
        [(r["output"], r["against"], r["tolerance"]) for r in cli["comparisons"]]
    # Same states, so errors of the same size; not where the worst one falls: at 1e-15 that
    # depends on the last bits of the reference, which the CLI and this module (each built
    # with -march=native, inlined differently) may round apart.
    for ours, theirs in zip(result.comparisons, cli["comparisons"]):
        assert ours.worst_rel_error <= max(10 * theirs["worst_rel_error"], 1e-14)
        assert ours.seed in (1, 2) and theirs["seed"] in (1, 2)


def test_a_function_that_computes_something_else_fails(arm7, crba):
    # The CRBA's Function checked as the spec of M^-1: same blocks, other values.
    minv_spec = (SPECS / "minv.json").read_text()
    found = _robodiff.check_spec(arm7._reference_model(), minv_spec, crba, 2, 1)
    by_against = {row["against"]: row for row in found["comparisons"]}
    assert not by_against["reference (core/dynamics)"]["passed"]
    assert not by_against["interpreted"]["passed"]
    assert by_against["interpreted"]["worst_rel_error"] > 1e-3


def test_the_interpreter_alone_needs_no_compiled_function(arm7):
    # ABA with its Jacobian is not in the test cache: only the interpreter is checked.
    result = robodiff.check(arm7, SPECS / "aba_jacobian.json", samples=1, backend="interpreted")
    assert result.passed
    assert {c.against for c in result.comparisons} == {"reference (core/dynamics)", "finite differences"}


def test_a_user_function_is_checked_against_its_double_evaluation(arm7):
    result = robodiff.check(arm7, SPECS / "arm7_mpc_knot.json", samples=1, backend="interpreted")
    assert result.passed, str(result)
    assert "double evaluation" in {c.against for c in result.comparisons}


def test_bad_arguments_are_refused(arm7, rnea):
    with pytest.raises(ValueError, match="samples: 0 given"):
        robodiff.check(arm7, SPECS / "crba.json", samples=0)
    with pytest.raises(ValueError, match="backend: 'compiled' given"):
        robodiff.check(arm7, SPECS / "crba.json", backend="compiled")
    with pytest.raises(robodiff.Error) as error:
        robodiff.check(arm7, {"function": "no_such_function"}, backend="interpreted")
    assert error.value.code == "INVALID_ARGUMENT"
    with pytest.raises(ValueError, match="is not the spec's function"):
        _robodiff.check_spec(arm7._reference_model(), (SPECS / "crba.json").read_text(), rnea, 1, 1)
