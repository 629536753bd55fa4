"""Batches (inputs of shape (N, n), through the C++ evaluateBatch) and out= arrays
written in place."""

import numpy as np

KNOTS = 37  # not a multiple of the SIMD batch width: the tail knots are covered too
RNG = np.random.default_rng(11)


def random_knots(n: int = KNOTS) -> dict:
    return {name: RNG.uniform(-1.0, 1.0, (n, 7)) for name in ("q", "v", "a")}


def test_a_batch_equals_single_calls_knot_by_knot(rnea):
    inputs = random_knots()
    batch = rnea(**inputs)
    assert batch["value"].shape == (KNOTS, 7)
    assert batch["jacobian"].shape == (KNOTS, 7, 21)
    for k in range(KNOTS):
        single = rnea(**{name: x[k] for name, x in inputs.items()})
        np.testing.assert_allclose(batch["value"][k], single["value"], rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(batch["jacobian"][k], single["jacobian"], rtol=1e-12, atol=1e-14)


def test_a_sparse_batch_gives_the_csr_values_per_knot(rnea, rnea_sparse):
    inputs = random_knots(5)
    data, indices, indptr, shape = rnea_sparse(**inputs)["jacobian"]
    assert shape == (7, 21) and data.shape == (5, len(indices)) and len(indptr) == 8
    dense = rnea(**inputs)["jacobian"]
    for k in range(5):
        rebuilt = np.zeros(shape)
        for row in range(7):
            rebuilt[row, indices[indptr[row]:indptr[row + 1]]] = data[k, indptr[row]:indptr[row + 1]]
        np.testing.assert_allclose(rebuilt, dense[k], rtol=1e-12, atol=1e-14)


def test_out_arrays_are_written_in_place_and_returned_as_they_are(rnea):
    inputs = {name: x[0] for name, x in random_knots(1).items()}
    out = {"value": np.full(7, -1.0), "jacobian": np.full((7, 21), -1.0)}
    value_address = out["value"].__array_interface__["data"][0]
    result = rnea(**inputs, out=out)
    assert result["value"] is out["value"] and result["jacobian"] is out["jacobian"]
    assert out["value"].__array_interface__["data"][0] == value_address
    np.testing.assert_array_equal(out["jacobian"], rnea(**inputs)["jacobian"])


def test_batch_out_arrays_are_written_in_place(rnea):
    inputs = random_knots()
    out = {"jacobian": np.zeros((KNOTS, 7, 21))}
    result = rnea(**inputs, out=out)
    assert result["jacobian"] is out["jacobian"]
    assert result["value"].shape == (KNOTS, 7)  # not in out=: allocated
    np.testing.assert_array_equal(out["jacobian"], rnea(**inputs)["jacobian"])


def test_sparse_out_is_the_nnz_values_array(rnea_sparse):
    inputs = {name: x[0] for name, x in random_knots(1).items()}
    expected = rnea_sparse(**inputs)["jacobian"]
    data = np.zeros(expected.nnz)
    result = rnea_sparse(**inputs, out={"jacobian": data})
    assert np.shares_memory(result["jacobian"].data, data)
    np.testing.assert_array_equal(data, expected.data)


def test_an_empty_batch_gives_empty_outputs(rnea):
    empty = {name: np.zeros((0, 7)) for name in ("q", "v", "a")}
    result = rnea(**empty)
    assert result["value"].shape == (0, 7) and result["jacobian"].shape == (0, 7, 21)
