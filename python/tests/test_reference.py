"""robodiff.reference against independent facts: identities between different algorithms
(RNEA and ABA invert each other, CRBA is RNEA's linear part, the regressor times the
inertial parameters is RNEA), finite differences of the placement for the Jacobian, the
compiled functions' values, and Pinocchio's golden data for the Panda when present."""

import json
import pathlib

import numpy as np
import pytest

import robodiff
from robodiff import reference as ref

from conftest import REPO

HUMANOID = REPO / "examples" / "robots" / "humanoid.urdf"
GOLDEN = pathlib.Path("/work/shared/golden/panda.json")
PANDA = pathlib.Path("/work/shared/robots/panda_arm_fixed_fingers.urdf")


@pytest.fixture(scope="module")
def humanoid(client) -> robodiff.Model:
    return client.load(HUMANOID, floating_base=True)


def state(model, seed):
    rng = np.random.default_rng(seed)
    return ref.random_configuration(model, seed), rng.uniform(-1, 1, model.nv), rng.uniform(-1, 1, model.nv)


@pytest.mark.parametrize("robot", ["arm7", "humanoid"])
def test_rnea_and_aba_invert_each_other(robot, request):
    model = request.getfixturevalue(robot)
    for seed in range(3):
        q, v, a = state(model, seed)
        tau = ref.rnea(model, q, v, a)
        assert tau.shape == (model.nv,) and tau.dtype == np.float64
        np.testing.assert_allclose(ref.aba(model, q, v, tau), a, rtol=1e-8, atol=1e-9)


@pytest.mark.parametrize("robot", ["arm7", "humanoid"])
def test_crba_is_the_linear_part_of_rnea(robot, request):
    model = request.getfixturevalue(robot)
    q, v, a = state(model, 1)
    m = ref.crba(model, q)
    assert m.shape == (model.nv, model.nv) and m.flags.c_contiguous
    np.testing.assert_allclose(m, m.T, atol=1e-12)
    zero = np.zeros(model.nv)
    np.testing.assert_allclose(m @ a, ref.rnea(model, q, zero, a) - ref.rnea(model, q, zero, zero), atol=1e-10)
    np.testing.assert_allclose(ref.minv(model, q) @ m, np.eye(model.nv), atol=1e-8)
    np.testing.assert_allclose(ref.gravity(model, q), ref.rnea(model, q, zero, zero), atol=1e-12)
    np.testing.assert_allclose(ref.nle(model, q, v), ref.rnea(model, q, v, zero), atol=1e-12)


def test_regressor_times_the_inertial_parameters_is_rnea(arm7):
    q, v, a = state(arm7, 2)
    y = ref.regressor(arm7, q, v, a)
    pi = ref.inertial_parameters(arm7)
    assert y.shape == (arm7.nv, pi.size) and pi.size % 10 == 0
    np.testing.assert_allclose(y @ pi, ref.rnea(arm7, q, v, a), rtol=1e-10, atol=1e-10)


def test_frame_jacobian_matches_finite_differences_of_the_placement(arm7):
    q, _, _ = state(arm7, 3)
    frame = arm7.frame_names[-1]
    jacobian = ref.frame_jacobian(arm7, q, frame)
    assert jacobian.shape == (6, arm7.nv)
    rotation = ref.fk(arm7, q, frame)[:, :3]
    h = 1e-6
    for j in range(arm7.nv):
        step = np.zeros(arm7.nv)
        step[j] = h
        plus, minus = ref.fk(arm7, q + step, frame), ref.fk(arm7, q - step, frame)
        np.testing.assert_allclose(jacobian[:3, j], (plus[:, 3] - minus[:, 3]) / (2 * h), atol=1e-7)
        w = (plus[:, :3] - minus[:, :3]) / (2 * h) @ rotation.T  # [omega]x
        np.testing.assert_allclose(jacobian[3:, j], [w[2, 1], w[0, 2], w[1, 0]], atol=1e-7)
    local = ref.frame_jacobian(arm7, q, frame, "LOCAL")
    np.testing.assert_allclose(local[3:], rotation.T @ jacobian[3:], atol=1e-12)


def test_integrate_and_difference_invert_each_other_on_a_floating_base(humanoid):
    q0, q1 = ref.random_configuration(humanoid, 4), ref.random_configuration(humanoid, 5)
    assert q0.shape == (humanoid.nq,) and np.allclose(np.linalg.norm(q0[3:7]), 1.0)
    np.testing.assert_array_equal(q0, ref.random_configuration(humanoid, 4))  # same seed, same q
    d = ref.difference(humanoid, q0, q1)
    assert d.shape == (humanoid.nv,)
    moved = ref.integrate(humanoid, q0, d)
    np.testing.assert_allclose(np.delete(moved, range(3, 7)), np.delete(q1, range(3, 7)), atol=1e-10)
    sign = np.sign(moved[3:7] @ q1[3:7])  # q and -q are the same rotation
    np.testing.assert_allclose(sign * moved[3:7], q1[3:7], atol=1e-10)
    np.testing.assert_allclose(ref.neutral(humanoid)[3:7], [0, 0, 0, 1])


def test_values_agree_with_the_compiled_functions(arm7, rnea, crba):
    q, v, a = state(arm7, 6)
    np.testing.assert_allclose(ref.rnea(arm7, q, v, a), rnea(q=q, v=v, a=a)["value"], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(ref.crba(arm7, q), crba(q=q)["value"], rtol=1e-10, atol=1e-12)


def test_values_agree_with_pinocchio_golden_data(client):
    if not GOLDEN.exists() or not PANDA.exists():
        pytest.skip(f"golden data absent ({GOLDEN}, {PANDA}): /work/shared is not on this machine")
    golden = json.loads(GOLDEN.read_text())
    panda = client.load(PANDA)
    ee = golden["ee_frames"][0]

    def close(actual, expected):
        expected = np.asarray(expected, dtype=float)
        np.testing.assert_allclose(actual, expected, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(expected).max()))

    close(ref.inertial_parameters(panda), golden["inertial_parameters"])
    for sample in golden["samples"][:5]:
        q, v, a = (np.asarray(sample[k], dtype=float) for k in ("q", "v", "a"))
        close(ref.rnea(panda, q, v, a), sample["tau"])
        close(ref.aba(panda, q, v, np.asarray(sample["tau"], dtype=float)), sample["ddq"])
        close(ref.crba(panda, q), sample["M"])
        close(ref.nle(panda, q, v), sample["nle"])
        close(ref.regressor(panda, q, v, a), sample["regressor"])
        placement = ref.fk(panda, q, ee)
        close(placement[:, :3], sample["frame_placements"][ee]["R"])
        close(placement[:, 3], sample["frame_placements"][ee]["p"])
        close(ref.frame_jacobian(panda, q, ee), sample["ee_jacobian_local_world_aligned"][ee])


def test_wrong_inputs_are_refused_naming_the_argument(arm7):
    q, v, a = state(arm7, 7)
    with pytest.raises(ValueError, match=r"input 'v': shape \(6,\) given; \(7,\) is needed"):
        ref.rnea(arm7, q, v[:6], a)
    with pytest.raises(TypeError, match="input 'q': dtype float32"):
        ref.crba(arm7, q.astype(np.float32))
    bad = a.copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match="input 'a': entry 2 is nan"):
        ref.rnea(arm7, q, v, bad)
    with pytest.raises(ValueError, match="input 'q': shape \\(7, 1\\) given"):
        ref.crba(arm7, q.reshape(7, 1))
    with pytest.raises(ValueError, match="'no_such_frame' is not a frame"):
        ref.fk(arm7, q, "no_such_frame")
    with pytest.raises(ValueError, match="reference frame 'SIDEWAYS'"):
        ref.frame_jacobian(arm7, q, arm7.frame_names[-1], "SIDEWAYS")
    with pytest.raises(TypeError, match="robodiff.Model"):
        ref.rnea("arm7", q, v, a)
