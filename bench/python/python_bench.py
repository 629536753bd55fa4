"""Python against C++ and against the anchors' Python sides (issue 22's targets), one run.

    PYTHONPATH=build/python build/anchors/venv/bin/python bench/python/python_bench.py [--robot URDF]

Times the RNEA value + Jacobian of the Panda (/work/shared's copy when present, else the
project's arm7) in local mode:
  - one knot: the same robodiff Function called from C++ (a loop in the module, same
    library and inputs) and from Python (new output arrays; preallocated out=);
  - 1,000 knots: one batched call from C++ and from Python (new arrays; out=);
  - the anchors, when their Python packages import (bench/anchors/run installs them in
    build/anchors/venv): pinocchio.computeRNEADerivatives and a CasADi Function of the
    same derivatives (pinocchio.casadi), one knot and a Python loop over 1,000 knots.
Prints one table with the Python overhead per call and the ratios the issue asks for.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import subprocess
import sys
import time
import timeit

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # numpy's BLAS threads would spin beside the timed loops
import numpy as np  # noqa: E402

import robodiff  # noqa: E402
from robodiff import _robodiff  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))  # casadi_rnea

REPO = pathlib.Path(__file__).resolve().parents[2]
PANDA = REPO.parent / "shared" / "robots" / "panda_arm_fixed_fingers.urdf"
SPEC = REPO / "examples" / "specs" / "rnea_jacobian.json"
KNOTS = 1000


def median_statement_seconds(statement: str, names: dict, calls: int, rounds: int = 7) -> float:
    """As median_seconds, for a statement timed in timeit's own loop (no lambda or indexing
    per call: what a user's loop pays is the call itself)."""
    timer = timeit.Timer(statement, globals=names)
    timer.timeit(calls)
    return float(np.median([timer.timeit(calls) / calls for _ in range(rounds)]))


def median_seconds(call, calls: int, rounds: int = 5) -> float:
    """Median over rounds of the mean time of `calls` calls, after one warm-up round."""
    results = []
    for r in range(rounds + 1):
        start = time.perf_counter()
        for _ in range(calls):
            call()
        took = (time.perf_counter() - start) / calls
        if r > 0:
            results.append(took)
    return float(np.median(results))


def robodiff_function(urdf: pathlib.Path, cache: pathlib.Path, cli: pathlib.Path):
    """The compiled RNEA + Jacobian in local mode (warmed into `cache` by the CLI first)."""
    subprocess.run([str(cli), "warmup", "--urdf", str(urdf), "--cache", str(cache), "--spec", str(SPEC)],
                   check=True, stdout=subprocess.DEVNULL)
    client = robodiff.Client("local", cache_dir=cache)
    model = client.load(urdf)
    return model, model.function(SPEC)


def robodiff_rows(fn, states):
    q, v, a = states
    rows = {}
    one = np.concatenate([q[0], v[0], a[0]])
    rows["C++ single"] = _robodiff._native_seconds_per_call(fn, one, 0, 100000, 7)
    names = {"fn": fn, "q": q[0].copy(), "v": v[0].copy(), "a": a[0].copy(),
             "out": {name: np.empty(shape) for name, shape in fn.outputs.items()}}
    rows["Python single"] = median_statement_seconds("fn(q=q, v=v, a=a)", names, 100000)
    rows["Python single, out="] = median_statement_seconds("fn(q=q, v=v, a=a, out=out)", names, 100000)
    knots = np.ascontiguousarray(np.concatenate([q, v, a], axis=1))
    rows["C++ batch"] = _robodiff._native_seconds_per_call(fn, knots, KNOTS, 20)
    rows["Python batch"] = median_seconds(lambda: fn(q=q, v=v, a=a), 20)
    batch_out = {name: np.empty((KNOTS,) + shape) for name, shape in fn.outputs.items()}
    rows["Python batch, out="] = median_seconds(lambda: fn(q=q, v=v, a=a, out=batch_out), 20)
    return rows


def pinocchio_model(urdf):
    """(pinocchio, its Model of `urdf`), or (None, why) when pinocchio does not import."""
    try:
        import pinocchio
    except ImportError as e:
        return None, f"pinocchio: not importable ({e}); bench/anchors/run installs it in build/anchors/venv"
    return pinocchio, pinocchio.buildModelFromUrdf(str(urdf))


def pinocchio_derivatives(pinocchio, model, data, q, v, a):
    """tau and d tau / d[q, v, a] by Pinocchio's analytic derivatives, as Python calls them."""
    pinocchio.computeRNEADerivatives(model, data, q, v, a)
    return data.tau, data.dtau_dq, data.dtau_dv, data.M


def pinocchio_rows(pinocchio, model, states):
    data = model.createData()
    q, v, a = states

    def one(k=0):
        return pinocchio_derivatives(pinocchio, model, data, q[k], v[k], a[k])

    return {"Pinocchio single": median_seconds(one, 20000),
            "Pinocchio loop": median_seconds(lambda: [one(k) for k in range(KNOTS)], 5)}


def casadi_rows(pinocchio, model, states):
    try:
        from casadi_rnea import rnea_jacobian_function
    except ImportError as e:
        return {}, f"CasADi: not importable ({e})"
    f = rnea_jacobian_function(model)
    q, v, a = states

    def one(k=0):
        t, j = f(q[k], v[k], a[k])
        return np.asarray(t), np.asarray(j)

    _, jac = one(2)
    tau, dq, dv, M = pinocchio_derivatives(pinocchio, model, model.createData(), q[2], v[2], a[2])
    if not close(jac, np.hstack([dq, dv, M])):
        return {}, "CasADi: its Jacobian disagrees with Pinocchio's: no figure"
    return {"CasADi single": median_seconds(one, 5000),
            "CasADi loop": median_seconds(lambda: [one(k) for k in range(KNOTS)], 3)}, None


def close(got, want):
    return np.max(np.abs(got - want)) <= 1e-9 * max(1.0, np.max(np.abs(want)))


def check_values(fn, pinocchio, model, states):
    """robodiff's Python result against Pinocchio's: no figure for a side that disagrees."""
    q, v, a = states
    out = fn(q=q[1], v=v[1], a=a[1])
    tau, dq, dv, M = pinocchio_derivatives(pinocchio, model, model.createData(), q[1], v[1], a[1])
    if not (close(out["value"], tau) and close(out["jacobian"], np.hstack([dq, dv, M]))):
        sys.exit("robodiff disagrees with Pinocchio: no figures printed")


def print_table(rows, notes):
    """One table: each row's µs per call, and beside the Python rows what Python adds to C++."""
    us = {k: v * 1e6 for k, v in rows.items()}
    base = {"Python single": "C++ single", "Python single, out=": "C++ single",
            "Python batch": "C++ batch", "Python batch, out=": "C++ batch"}
    print("| what | µs per call | Python adds (µs) | / C++ |\n|---|---|---|---|")
    for name, value in us.items():
        extra = f"{value - us[base[name]]:+.3f} | {value / us[base[name]]:.3f}" if name in base else " | "
        print(f"| {name} | {value:.3f} | {extra} |")
    print()
    single = us["Python single"] - us["C++ single"]
    single_out = us["Python single, out="] - us["C++ single"]
    print(f"Python overhead, one knot: {single:.3f} µs (new arrays), {single_out:.3f} µs (out=); target <= 1 µs")
    print(f"Python / C++, 1,000 knots: {us['Python batch'] / us['C++ batch']:.3f} (new arrays), "
          f"{us['Python batch, out='] / us['C++ batch']:.3f} (out=); target <= 1.1")
    for anchor in ("Pinocchio", "CasADi"):
        if f"{anchor} single" in us:
            print(f"{anchor} / robodiff from Python: one knot {us[anchor + ' single'] / us['Python single']:.1f}x "
                  f"(target >= 3), 1,000 knots {us[anchor + ' loop'] / us['Python batch']:.1f}x (target >= 5)")
    for note in notes:
        print("note:", note)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robot", type=pathlib.Path, default=PANDA if PANDA.exists() else REPO / "examples/robots/arm7.urdf")
    parser.add_argument("--build", type=pathlib.Path, default=REPO / "build")
    args = parser.parse_args()
    cache = args.build / "bench-python-cache"
    model, fn = robodiff_function(args.robot, cache, args.build / "bin" / "robodiff")
    rng = np.random.default_rng(7)
    states = tuple(np.ascontiguousarray(rng.uniform(-1, 1, (KNOTS, model.nv))) for _ in range(3))
    pinocchio, pin_model = pinocchio_model(args.robot)
    if pinocchio is not None:
        check_values(fn, pinocchio, pin_model, states)
    print(f"# robodiff from Python: {args.robot.name} (nv {model.nv}), RNEA value + Jacobian, local mode\n")
    rows = robodiff_rows(fn, states)
    notes = []
    if pinocchio is None:
        notes.append(pin_model)
    else:
        rows.update(pinocchio_rows(pinocchio, pin_model, states))
        extra, note = casadi_rows(pinocchio, pin_model, states)
        rows.update(extra)
        if note:
            notes.append(note)
    print_table(rows, notes)


if __name__ == "__main__":
    main()
