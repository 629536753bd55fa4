"""robodiff.reference: the double-precision reference dynamics on numpy arrays.

The same C++ code (core/dynamics, evaluated directly in double: no tracing, no code
generation) that ``robodiff check`` and :func:`robodiff.check` compare compiled functions
with. Use it to validate a spec's outputs, or a Function's values, at your own states::

    model = client.load("examples/robots/arm7.urdf")
    tau = robodiff.reference.rnea(model, q, v, a)
    assert np.allclose(robodiff.reference.aba(model, q, v, tau), a)

``model`` is a :class:`robodiff.Model` from ``Client.load``; it parses its URDF in this
process on first use (once). Every function returns what the spec of the same name
returns as its ``value`` (a vector as shape (n,), a matrix as (rows, cols)). Inputs are
1-D C-contiguous float64 numpy arrays of the model's sizes (q: nq, v/a/tau: nv) holding
finite numbers; anything else raises TypeError or ValueError naming the argument, what
was given and what is needed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from . import _robodiff

if TYPE_CHECKING:
    from .client import Model

__all__ = ["rnea", "aba", "crba", "gravity", "nle", "fk", "frame_jacobian", "com", "regressor", "minv",
           "neutral", "random_configuration", "integrate", "difference", "inertial_parameters"]


def _parsed(model: "Model") -> _robodiff.ReferenceModel:
    reference = getattr(model, "_reference_model", None)
    if reference is None:
        raise TypeError(f"model: {type(model).__name__} given; a robodiff.Model (from Client.load) is needed")
    return reference()


def rnea(model: "Model", q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Inverse dynamics tau = RNEA(q, v, a), shape (nv,) (gravity included)."""
    return _parsed(model).evaluate("rnea", [q, v, a])


def aba(model: "Model", q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Forward dynamics ddq = ABA(q, v, tau), shape (nv,)."""
    return _parsed(model).evaluate("aba", [q, v, tau])


def crba(model: "Model", q: np.ndarray) -> np.ndarray:
    """The joint-space mass matrix M(q), (nv, nv), full and symmetric."""
    return _parsed(model).evaluate("crba", [q])


def gravity(model: "Model", q: np.ndarray) -> np.ndarray:
    """The generalised gravity g(q) = RNEA(q, 0, 0), shape (nv,)."""
    return _parsed(model).evaluate("gravity", [q])


def nle(model: "Model", q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The nonlinear effects C(q, v) v + g(q) = RNEA(q, v, 0), shape (nv,)."""
    return _parsed(model).evaluate("nle", [q, v])


def fk(model: "Model", q: np.ndarray, frame: str) -> np.ndarray:
    """The placement of frame ``frame`` (a name of ``model.frame_names``) in the world, (3, 4).

    ``[R | p]``: columns 0-2 the rotation matrix, column 3 the translation, as the ``fk``
    spec's value. An unknown frame raises ValueError (with the closest name, or the list).
    """
    return _parsed(model).evaluate("fk", [q], frame)


def frame_jacobian(model: "Model", q: np.ndarray, frame: str, reference: str = "LOCAL_WORLD_ALIGNED") -> np.ndarray:
    """The (6, nv) Jacobian of frame ``frame``: its spatial velocity is J @ v.

    Rows [linear x y z, angular x y z]. reference: ``"LOCAL_WORLD_ALIGNED"`` (the
    velocity of the frame's origin in world axes, the spec's default), ``"LOCAL"`` (in the
    frame itself) or ``"WORLD"`` (at the world origin), as Pinocchio's.
    """
    return _parsed(model).evaluate("frame_jacobian", [q], frame, reference)


def com(model: "Model", q: np.ndarray) -> np.ndarray:
    """The centre of mass in the world, shape (3,)."""
    return _parsed(model).evaluate("com", [q])


def regressor(model: "Model", q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The joint-torque regressor Y(q, v, a), (nv, 10 njoints): Y @ inertial_parameters(model) == rnea."""
    return _parsed(model).evaluate("regressor", [q, v, a])


def minv(model: "Model", q: np.ndarray) -> np.ndarray:
    """The inverse of the mass matrix, (nv, nv)."""
    return _parsed(model).evaluate("minv", [q])


def neutral(model: "Model") -> np.ndarray:
    """The neutral configuration, shape (nq,): zeros (a free-flyer: the identity quaternion)."""
    return _parsed(model).neutral()


def random_configuration(model: "Model", seed: int) -> np.ndarray:
    """A random configuration within the joint limits, shape (nq,); the same seed, the same q.

    Drawn as ``robodiff check`` draws the configuration of its states (unbounded angles in
    [-pi, pi], a uniformly random unit quaternion for a free-flyer).
    """
    return _parsed(model).random_configuration(int(seed))


def integrate(model: "Model", q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """q (+) v: q moved by the tangent vector v (nv) on the configuration manifold, shape (nq,).

    Plain addition for revolute and prismatic joints; for a free-flyer the SE(3)
    exponential in the base frame (the convention of the q-derivatives robodiff builds).
    """
    return _parsed(model).integrate(q, v)


def difference(model: "Model", q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """q1 (-) q0: the tangent vector d, shape (nv,), with integrate(model, q0, d) == q1."""
    return _parsed(model).difference(q0, q1)


def inertial_parameters(model: "Model") -> np.ndarray:
    """The inertial parameters pi, shape (10 njoints,): per joint [m, m c, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz].

    c the centre of mass and I the rotational inertia about the joint frame's origin, in
    the joint frame: regressor(model, q, v, a) @ pi == rnea(model, q, v, a).
    """
    return _parsed(model).inertial_parameters()
