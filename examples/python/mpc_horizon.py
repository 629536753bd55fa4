"""An MPC horizon in Python: a few iLQR (Gauss-Newton) iterations of a reaching task over
20 knots, each iteration's linearisation from ONE batched call of the step function
(the Euler step and its Jacobians at all 20 knots) and ONE of the cost function (the
reaching residual and its Jacobian at the 20 knots and the terminal one).

    x_{k+1} = step(x_k, u_k),  x = (q, v),   cost = sum_k |r(x_k, u_k)|^2 + W_T |r(x_N, 0)|^2

with step = examples/python/specs/euler_step.json (v_next = v + dt ABA(q, v, u),
q_next = q + dt v_next, dt = 0.01 s) and r = examples/python/specs/<robot>_reach_residual.json
(the tool's distance from a target, the velocity and the torque, weighted). The target is
where the tool is at q0 + 0.15 rad per joint. Each iteration prints the cost, which goes
down (a backtracking line search only takes steps that lower it).

Run from the repository root, after building the module (docs/python.md):

    build/bin/robodiff warmup --urdf examples/robots/arm7.urdf \\
        --spec examples/python/specs/euler_step.json --spec examples/python/specs/arm7_reach_residual.json
    PYTHONPATH=build/python build/venv/bin/python examples/python/mpc_horizon.py

or with a robodiffd running, no warmup (it compiles them): `--server shm`. The Panda, not part of
the project (its URDF is in ../shared): `--urdf /work/shared/robots/panda_arm_fixed_fingers.urdf`
(the cost spec then defaults to panda_reach_residual.json, frame panda_hand). Options:
--knots, --iterations, --json (the costs as JSON), --cache-dir, --server, --warmup (build
the functions into the cache first, with robodiff.warmup, instead of the command above).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from example_support import PY_SPECS, add_client_arguments, connect, run

TERMINAL_WEIGHT = 10.0


class Horizon:
    """The step and cost Functions and the batched evaluation of a trajectory."""

    def __init__(self, step, cost, nv: int, knots: int, target: np.ndarray) -> None:
        self.step, self.cost, self.nv, self.knots = step, cost, nv, knots
        self.targets = np.ascontiguousarray(np.tile(target, (knots + 1, 1)))
        self.weights = np.ones(knots + 1)
        self.weights[-1] = TERMINAL_WEIGHT
        # Output buffers, written in place by every linearisation (out=).
        self.step_out = {name: np.empty((knots,) + shape) for name, shape in step.outputs.items()}
        self.cost_out = {name: np.empty((knots + 1,) + shape) for name, shape in cost.outputs.items()}

    def costs(self, qs, vs, us) -> np.ndarray:
        """The cost of the N+1 knots (u = 0 at the last one), one batched call."""
        u_all = np.vstack([us, np.zeros((1, self.nv))])
        residual = self.cost(q=qs, v=vs, u=u_all, target=self.targets, out=self.cost_out)["residual"]
        return self.weights * np.einsum("ki,ki->k", residual, residual)

    def rollout(self, q0, v0, us, gains=None) -> tuple:
        """States from (q0, v0) under the controls (a feedback gains(k, q, v) -> u when given)."""
        qs, vs = np.empty((self.knots + 1, self.nv)), np.empty((self.knots + 1, self.nv))
        qs[0], vs[0] = q0, v0
        applied = np.empty_like(us)
        for k in range(self.knots):
            applied[k] = us[k] if gains is None else gains(k, qs[k], vs[k])
            out = self.step(q=qs[k], v=vs[k], u=applied[k])
            qs[k + 1], vs[k + 1] = out["q_next"], out["v_next"]
        return qs, vs, applied

    def linearise(self, qs, vs, us) -> tuple:
        """fx (N, 2nv, 2nv), fu (N, 2nv, nv) of the step and the cost's gradient and
        Gauss-Newton Hessian at every knot, from one batched call of each function."""
        n = self.nv
        out = self.step(q=qs[:-1], v=vs[:-1], u=us, out=self.step_out)
        jac = np.concatenate([out["dq_next"], out["dv_next"]], axis=1)  # (N, 2nv, 3nv)
        self.costs(qs, vs, us)  # fills cost_out
        r, dr = self.cost_out["residual"], self.cost_out["residual_jacobian"]
        w = 2.0 * self.weights[:, None, None]
        grad = w[:, :, 0] * np.einsum("kri,kr->ki", dr, r)  # (N+1, 3nv)
        hess = w * np.einsum("kri,krj->kij", dr, dr)  # (N+1, 3nv, 3nv)
        return jac[:, :, :2 * n], jac[:, :, 2 * n:], grad, hess


def backward_pass(fx, fu, grad, hess, nv: int, mu: float):
    """iLQR's Riccati recursion: feedforward k and gains K per knot (None when the
    regularised Quu is not positive definite)."""
    nx, knots = 2 * nv, fx.shape[0]
    vx, vxx = grad[-1, :nx].copy(), hess[-1, :nx, :nx].copy()
    ff, fb = np.empty((knots, nv)), np.empty((knots, nv, nx))
    for k in reversed(range(knots)):
        qx = grad[k, :nx] + fx[k].T @ vx
        qu = grad[k, nx:] + fu[k].T @ vx
        qxx = hess[k, :nx, :nx] + fx[k].T @ vxx @ fx[k]
        quu = hess[k, nx:, nx:] + fu[k].T @ vxx @ fu[k] + mu * np.eye(nv)
        qux = hess[k, nx:, :nx] + fu[k].T @ vxx @ fx[k]
        try:
            factor = np.linalg.cholesky(quu)
        except np.linalg.LinAlgError:
            return None
        ff[k] = -np.linalg.solve(factor.T, np.linalg.solve(factor, qu))
        fb[k] = -np.linalg.solve(factor.T, np.linalg.solve(factor, qux))
        vx = qx + fb[k].T @ quu @ ff[k] + fb[k].T @ qu + qux.T @ ff[k]
        vxx = qxx + fb[k].T @ quu @ fb[k] + fb[k].T @ qux + qux.T @ fb[k]
        vxx = 0.5 * (vxx + vxx.T)
    return ff, fb


def ilqr_iteration(horizon: Horizon, qs, vs, us, cost: float, mu: float):
    """One iteration: linearise (batched), backward pass, line search on the real
    dynamics. Returns the new trajectory, cost and step length (0: no decrease found)."""
    nv = horizon.nv
    linear = horizon.linearise(qs, vs, us)
    gains = backward_pass(*linear, nv, mu)
    if gains is None:
        return qs, vs, us, cost, 0.0
    ff, fb = gains
    for alpha in (1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125):
        def policy(k, q, v, alpha=alpha):
            dx = np.concatenate([q - qs[k], v - vs[k]])  # a fixed base: q's tangent is q's difference
            return us[k] + alpha * ff[k] + fb[k] @ dx
        new_qs, new_vs, new_us = horizon.rollout(qs[0], vs[0], us, policy)
        new_cost = float(horizon.costs(new_qs, new_vs, new_us).sum())
        if new_cost < cost:
            return new_qs, new_vs, new_us, new_cost, alpha
    return qs, vs, us, cost, 0.0


def main(args: argparse.Namespace) -> int:
    client = connect(args)
    model = client.load(args.urdf)
    if model.nq != model.nv:
        raise SystemExit("mpc_horizon.py handles fixed-base robots (nq == nv); this one has a floating base")
    step, cost = model.function(args.step_spec), model.function(args.cost_spec)
    nv = model.nv
    q0 = 0.3 * np.where(np.arange(nv) % 2 == 0, 1.0, -1.0)
    v0 = np.zeros(nv)
    zero = np.zeros(nv)
    target = cost(q=q0 + 0.15, v=zero, u=zero, target=np.zeros(3))["position"].copy()
    horizon = Horizon(step, cost, nv, args.knots, target)

    us = np.zeros((args.knots, nv))  # the first guess: no torque at all
    qs, vs, _ = horizon.rollout(q0, v0, us)
    total = float(horizon.costs(qs, vs, us).sum())
    start_distance = float(np.linalg.norm(horizon.cost_out["position"][-1] - target))
    costs, mu = [total], 1e-6
    if not args.json:
        print(f"{model!r}, {client.mode} mode, {args.knots} knots, target {np.round(target, 3)}")
        print(f"iteration 0: cost {total:.6g} (no torque), tool {start_distance:.4f} m from the target at the end")
    for iteration in range(1, args.iterations + 1):
        qs, vs, us, total, alpha = ilqr_iteration(horizon, qs, vs, us, total, mu)
        mu = mu / 10 if alpha > 0 else mu * 100
        costs.append(total)
        if not args.json:
            print(f"iteration {iteration}: cost {total:.6g}  step {alpha:g}")

    horizon.costs(qs, vs, us)
    distance = float(np.linalg.norm(horizon.cost_out["position"][-1] - target))
    seconds = timed_linearisation(horizon, qs, vs, us)
    summary = {"robot": model.id, "mode": client.mode, "knots": args.knots, "costs": costs,
               "start_distance": start_distance, "final_distance": distance,
               "linearise_seconds": seconds, "torque_first_knot": us[0].tolist()}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"tool {distance:.4f} m from the target at the end (was {start_distance:.4f} m); "
              f"u_0 = {np.round(us[0], 2)} N m")
        print(f"one linearisation of the {args.knots}-knot horizon (2 batched calls): {1e6 * seconds:.0f} us")
    return 0


def timed_linearisation(horizon: Horizon, qs, vs, us, repeats: int = 20) -> float:
    """The best time of the two batched calls (step and cost Jacobians), in seconds."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        horizon.step(q=qs[:-1], v=vs[:-1], u=us, out=horizon.step_out)
        horizon.costs(qs, vs, us)
        best = min(best, time.perf_counter() - start)
    return best


def parse_arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_client_arguments(parser)
    parser.add_argument("--step-spec", default=PY_SPECS / "euler_step.json")
    parser.add_argument("--cost-spec", default=None,
                        help="default: specs/panda_reach_residual.json for a URDF named panda*, else arm7's")
    parser.add_argument("--knots", type=int, default=20)
    parser.add_argument("--iterations", type=int, default=8)
    parser.add_argument("--json", action="store_true", help="print one JSON summary instead of text")
    args = parser.parse_args()
    if args.cost_spec is None:
        robot = "panda" if args.urdf.name.startswith("panda") else "arm7"
        args.cost_spec = PY_SPECS / f"{robot}_reach_residual.json"
    if args.knots < 1 or args.iterations < 0:
        parser.error("--knots must be >= 1 and --iterations >= 0")
    return args


if __name__ == "__main__":
    arguments = parse_arguments()
    run(main, arguments, [arguments.step_spec, arguments.cost_spec])
