"""Every wrong argument is refused with a message saying what was given and what is
needed: nothing is converted or copied silently."""

import numpy as np
import pytest

GOOD = {name: np.zeros(7) for name in ("q", "v", "a")}


def call_with(rnea, **changes):
    return rnea(**{**GOOD, **changes})


@pytest.mark.parametrize("given, error, message", [
    (np.zeros(7, dtype=np.float32), TypeError, r"input 'q': dtype float32 given; a C-contiguous numpy.ndarray of float64"),
    (np.zeros(7, dtype=np.int64), TypeError, r"input 'q': dtype int64 given"),
    (np.zeros(7, dtype=">f8"), TypeError, r"input 'q': dtype >f8 given"),
    ([0.0] * 7, TypeError, r"input 'q': list given; a C-contiguous numpy.ndarray of float64 is needed"),
    (0.5, TypeError, r"input 'q': float given"),
    (np.zeros(14)[::2], ValueError, r"input 'q': a non-contiguous array given \(shape \(7,\), strides \(16,\) bytes"),
    (np.asfortranarray(np.zeros((3, 7))), ValueError, r"input 'q': a non-contiguous array given \(shape \(3, 7\)"),
    (np.zeros(6), ValueError, r"input 'q': shape \(6,\) given; \(7,\) for one knot or \(N, 7\) for N knots"),
    (np.zeros((2, 3, 7)), ValueError, r"input 'q': shape \(2, 3, 7\) given"),
])
def test_a_wrong_input_array_is_refused(rnea, given, error, message):
    with pytest.raises(error, match=message):
        call_with(rnea, q=given)


def test_a_read_only_input_is_accepted(rnea):
    q = np.zeros(7)
    q.flags.writeable = False
    assert call_with(rnea, q=q)["value"].shape == (7,)


def test_one_knot_and_a_batch_cannot_be_mixed(rnea):
    with pytest.raises(ValueError, match=r"input 'v': shape \(3, 7\) given.*like the first input 'q' \(7,\)"):
        call_with(rnea, v=np.zeros((3, 7)))


def test_batches_of_different_lengths_are_refused(rnea):
    with pytest.raises(ValueError, match=r"input 'a': shape \(4, 7\) given.*like the first input 'q' \(5, 7\)"):
        rnea(q=np.zeros((5, 7)), v=np.zeros((5, 7)), a=np.zeros((4, 7)))


def test_an_unknown_input_name_suggests_the_closest(rnea):
    with pytest.raises(TypeError, match=r"unknown input 'qq' \(did you mean 'q'\?\); the inputs are q \(7,\), v \(7,\), a \(7,\)"):
        rnea(qq=np.zeros(7), v=np.zeros(7), a=np.zeros(7))


def test_positional_inputs_are_refused_by_name(rnea):
    with pytest.raises(TypeError, match=r"robodiff.Function takes its inputs by name: fn\(q=..., v=..., ...\)"):
        rnea(np.zeros(7), np.zeros(7), np.zeros(7))


def test_no_inputs_at_all_names_them(rnea):
    with pytest.raises(TypeError, match=r"the inputs are q \(7,\), v \(7,\), a \(7,\)"):
        rnea()


def test_a_missing_input_is_named(rnea):
    with pytest.raises(TypeError, match=r"missing input 'a'; the inputs are q \(7,\), v \(7,\), a \(7,\)"):
        rnea(q=np.zeros(7), v=np.zeros(7))


def test_an_extra_input_is_refused(rnea):
    with pytest.raises(TypeError, match=r"unknown input 'tau' \(did you mean 'a'\?\)"):
        call_with(rnea, tau=np.zeros(7))


@pytest.mark.parametrize("out, error, message", [
    ([np.zeros(7)], TypeError, r"out: list given; a dict of numpy arrays by output name is needed"),
    ({"valu": np.zeros(7)}, TypeError, r"out: unknown output 'valu' \(did you mean 'value'\?\)"),
    ({"value": np.zeros(6)}, ValueError, r"out\['value'\]: shape \(6,\) given; \(7,\) is needed"),
    ({"jacobian": np.zeros((21, 7))}, ValueError, r"out\['jacobian'\]: shape \(21, 7\) given; \(7, 21\) is needed"),
    ({"jacobian": np.zeros((7, 21)).T.copy().T}, ValueError, r"out\['jacobian'\]: a non-contiguous array given"),
    ({"value": np.zeros(7, dtype=np.float32)}, TypeError, r"out\['value'\]: dtype float32 given"),
])
def test_a_wrong_out_array_is_refused(rnea, out, error, message):
    with pytest.raises(error, match=message):
        call_with(rnea, out=out)


def test_a_read_only_out_array_is_refused(rnea):
    value = np.zeros(7)
    value.flags.writeable = False
    with pytest.raises(ValueError, match=r"out\['value'\]: a read-only array given; a writable one is needed"):
        call_with(rnea, out={"value": value})


def test_a_batch_out_array_needs_the_knot_axis(rnea):
    batch = {name: np.zeros((3, 7)) for name in GOOD}
    with pytest.raises(ValueError, match=r"out\['value'\]: shape \(7,\) given; \(3, 7\) is needed"):
        rnea(**batch, out={"value": np.zeros(7)})


def test_a_refused_call_leaves_out_arrays_untouched(rnea):
    value = np.full(7, 3.0)
    with pytest.raises(TypeError):
        call_with(rnea, q=np.zeros(7, dtype=np.float32), out={"value": value})
    np.testing.assert_array_equal(value, np.full(7, 3.0))
