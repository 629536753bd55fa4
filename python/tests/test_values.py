"""Values against an independent reference: `robodiff compute --backend reference` (the
double-precision dynamics and the builder's graph evaluated node by node, no generated
code), and finite differences of the value."""

import json
import subprocess

import numpy as np
import pytest

from conftest import ARM7, SPECS, robodiff_cli

RNG = np.random.default_rng(7)
STATE = {name: RNG.uniform(-1.0, 1.0, 7) for name in ("q", "v", "a")}


def reference(spec: str, tmp_path, derivatives: bool) -> dict:
    state_file = tmp_path / "state.json"
    state_file.write_text(json.dumps({k: v.tolist() for k, v in STATE.items()}))
    command = [str(robodiff_cli()), "compute", "--urdf", str(ARM7), "--spec", str(SPECS / spec),
               "--backend", "reference", "--state", str(state_file)]
    if derivatives:
        command.append("--derivatives")
    done = subprocess.run(command, check=True, capture_output=True, text=True, timeout=120)
    return json.loads(done.stdout)


def test_rnea_value_and_jacobian_match_the_reference(rnea, tmp_path):
    expected = reference("rnea_jacobian.json", tmp_path, derivatives=True)
    got = rnea(**STATE)
    assert got["value"].shape == (7,) and got["jacobian"].shape == (7, 21)
    np.testing.assert_allclose(got["value"], expected["value"], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(got["jacobian"], np.array(expected["jacobian"]), rtol=1e-10, atol=1e-12)


def test_crba_matches_the_reference_as_a_symmetric_matrix(crba, tmp_path):
    expected = np.array(reference("crba.json", tmp_path, derivatives=False)["value"])
    got = crba(q=STATE["q"])["value"]
    assert got.shape == (7, 7)
    np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(got, got.T, atol=1e-12)


def test_rnea_jacobian_matches_central_finite_differences_of_the_value(rnea):
    x = np.concatenate([STATE["q"], STATE["v"], STATE["a"]])
    jacobian = rnea(q=x[:7], v=x[7:14], a=x[14:])["jacobian"]
    h = 1e-6
    for column in range(21):
        plus, minus = x.copy(), x.copy()
        plus[column] += h
        minus[column] -= h
        tau_plus = rnea(q=plus[:7], v=plus[7:14], a=plus[14:])["value"]
        tau_minus = rnea(q=minus[:7], v=minus[7:14], a=minus[14:])["value"]
        np.testing.assert_allclose(jacobian[:, column], (tau_plus - tau_minus) / (2 * h), rtol=1e-6, atol=1e-6)


def test_sparse_jacobian_equals_the_dense_one(rnea, rnea_sparse):
    dense = rnea(**STATE)["jacobian"]
    sparse = rnea_sparse(**STATE)["jacobian"]
    scipy_sparse = pytest.importorskip("scipy.sparse")
    assert isinstance(sparse, scipy_sparse.csr_matrix)
    assert sparse.shape == (7, 21)
    np.testing.assert_allclose(sparse.toarray(), dense, rtol=1e-12, atol=1e-14)
    assert sparse.nnz < 7 * 21  # structural zeros are not stored
