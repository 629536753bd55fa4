"""A CasADi Function of RNEA and its Jacobian, written with CasADi's SX from a Pinocchio
model (the pin wheel ships no pinocchio.casadi): the CasADi side of bench/python.

Revolute joints (about x, y, z or any axis) on a fixed base, which is what the Panda and
arm-like robots have; anything else is refused by name. Recursive Newton-Euler with
spatial vectors in each joint's frame, linear part first, as Pinocchio writes them.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

AXES = {"JointModelRX": (1.0, 0.0, 0.0), "JointModelRY": (0.0, 1.0, 0.0), "JointModelRZ": (0.0, 0.0, 1.0)}


def joint_axis(joint) -> np.ndarray:
    name = joint.shortname()
    if name in AXES:
        return np.array(AXES[name])
    if name == "JointModelRevoluteUnaligned":
        return np.asarray(joint.extract().axis).reshape(3)
    raise ValueError(f"casadi_rnea: joint type {name} is not supported (revolute joints only)")


def rotation(axis: np.ndarray, angle) -> ca.SX:
    """Rodrigues' formula: the rotation by `angle` about the unit `axis`."""
    k = ca.skew(ca.DM(axis))
    return ca.DM.eye(3) + ca.sin(angle) * k + (1 - ca.cos(angle)) * (k @ k)


def inverse_motion(R, p, lin, ang):
    """A motion (lin, ang) of the parent frame, expressed in the child frame at (R, p)."""
    return R.T @ (lin + ca.cross(ang, p)), R.T @ ang


def rnea_expression(model, q, v, a):
    """tau = RNEA(q, v, a) as an SX column, for the pinocchio.Model `model`."""
    n = model.njoints
    lin_v, ang_v, lin_a, ang_a = [None] * n, [None] * n, [None] * n, [None] * n
    zero = ca.SX.zeros(3, 1)
    lin_v[0], ang_v[0] = zero, zero
    lin_a[0], ang_a[0] = -ca.DM(model.gravity.linear), zero
    frames, forces, torques, axes = [None] * n, [None] * n, [None] * n, [None] * n
    for i in range(1, n):
        joint, parent = model.joints[i], model.parents[i]
        u = joint_axis(joint)
        k = joint.idx_v
        placement = model.jointPlacements[i]
        R = ca.DM(placement.rotation) @ rotation(u, q[k])
        p = ca.DM(placement.translation)
        frames[i], axes[i] = (R, p), ca.DM(u)
        lv, av = inverse_motion(R, p, lin_v[parent], ang_v[parent])
        la, aa = inverse_motion(R, p, lin_a[parent], ang_a[parent])
        av = av + axes[i] * v[k]
        # a_i = X a_parent + S qdd + v_i x (S qd): the cross of (lv, av) with (0, u qd).
        lin_a[i] = la + ca.cross(lv, axes[i] * v[k])
        ang_a[i] = aa + axes[i] * a[k] + ca.cross(av, axes[i] * v[k])
        lin_v[i], ang_v[i] = lv, av
        inertia = model.inertias[i]
        m, c, Ic = inertia.mass, ca.DM(inertia.lever), ca.DM(inertia.inertia)
        f_a = m * (lin_a[i] - ca.cross(c, ang_a[i]))
        t_a = Ic @ ang_a[i] + ca.cross(c, f_a)
        f_v = m * (lv - ca.cross(c, av))
        t_v = Ic @ av + ca.cross(c, f_v)
        forces[i] = f_a + ca.cross(av, f_v)
        torques[i] = t_a + ca.cross(av, t_v) + ca.cross(lv, f_v)
    tau = [None] * model.nv
    for i in range(n - 1, 0, -1):
        tau[model.joints[i].idx_v] = ca.dot(axes[i], torques[i])
        parent = model.parents[i]
        if parent > 0:
            R, p = frames[i]
            f = R @ forces[i]
            forces[parent] = forces[parent] + f
            torques[parent] = torques[parent] + R @ torques[i] + ca.cross(p, f)
    return ca.vertcat(*tau)


def rnea_jacobian_function(model) -> ca.Function:
    """(q, v, a) -> (tau, d tau / d[q, v, a]) as a CasADi Function (SX, called as Python calls it)."""
    q, v, a = (ca.SX.sym(name, model.nv) for name in ("q", "v", "a"))
    tau = rnea_expression(model, q, v, a)
    return ca.Function("rnea_jacobian", [q, v, a], [tau, ca.jacobian(tau, ca.vertcat(q, v, a))])
