"""A trajectory's joint torques and their sensitivity, plotted: inverse dynamics with its
Jacobian (examples/specs/rnea_jacobian.json) at every knot of a smooth swing in ONE
batched call, then per joint i the torque tau_i(t) and the norms of its Jacobian's rows,
|d tau_i / d q| and |d tau_i / d v| (how much a small error in the joint angles or
velocities moves that torque).

The plot needs matplotlib (Debian: apt-get install python3-matplotlib; in a venv: pip
install matplotlib) and is written with the Agg backend to --out (a PNG). Without
matplotlib the example says so and prints the same information as a table.

Run from the repository root, after building the module (docs/python.md):

    build/bin/robodiff warmup --urdf examples/robots/arm7.urdf --spec examples/specs/rnea_jacobian.json
    PYTHONPATH=build/python build/venv/bin/python examples/python/plot_torques.py --out torques.png

Options: --knots, --duration, --csv FILE (t, q, v, a, tau and the row norms per knot),
--json (the summary as JSON), --urdf, --server, --cache-dir, --warmup (build the
functions into the cache first, with robodiff.warmup, instead of the command above).
"""

from __future__ import annotations

import argparse
import csv
import importlib
import json
import pathlib

import numpy as np

from example_support import SPECS, add_client_arguments, connect, run


def swing(nv: int, knots: int, duration: float) -> dict[str, np.ndarray]:
    """q_i(t) = A_i sin(w_i t + phi_i) with its exact v and a, (knots, nv) each."""
    t = np.linspace(0.0, duration, knots)[:, None]
    joint = np.arange(nv)[None, :]
    amplitude, omega, phase = 0.8 / (1 + 0.2 * joint), 2 * np.pi * (1 + 0.3 * joint) / duration, 0.7 * joint
    angle = omega * t + phase
    return {"t": t[:, 0], "q": amplitude * np.sin(angle), "v": amplitude * omega * np.cos(angle),
            "a": -amplitude * omega ** 2 * np.sin(angle)}


def torques_and_sensitivity(rnea, trajectory: dict, nv: int) -> dict[str, np.ndarray]:
    """tau (knots, nv) and the row norms of d tau / d q and d tau / d v, from one batched call."""
    out = rnea(q=trajectory["q"], v=trajectory["v"], a=trajectory["a"])
    jacobian = out["jacobian"]  # (knots, nv, 3 nv): columns q, v, a
    return {"tau": out["value"], "dq": np.linalg.norm(jacobian[:, :, :nv], axis=2),
            "dv": np.linalg.norm(jacobian[:, :, nv:2 * nv], axis=2)}


def summary(trajectory: dict, result: dict, joints: list[str]) -> list[dict]:
    """Per joint: the peak |tau| and when, the RMS torque, the peak row norms."""
    rows = []
    for i, joint in enumerate(joints):
        peak = int(np.argmax(np.abs(result["tau"][:, i])))
        rows.append({"joint": joint, "peak_tau": float(result["tau"][peak, i]),
                     "peak_t": float(trajectory["t"][peak]),
                     "rms_tau": float(np.sqrt(np.mean(result["tau"][:, i] ** 2))),
                     "max_dtau_dq": float(result["dq"][:, i].max()),
                     "max_dtau_dv": float(result["dv"][:, i].max())})
    return rows


def print_summary(rows: list[dict]) -> None:
    print(f"{'joint':<12}{'peak tau':>12}{'at t':>8}{'RMS tau':>10}{'max|dtau/dq|':>14}{'max|dtau/dv|':>14}")
    for r in rows:
        print(f"{r['joint']:<12}{r['peak_tau']:>12.3f}{r['peak_t']:>8.3f}{r['rms_tau']:>10.3f}"
              f"{r['max_dtau_dq']:>14.3f}{r['max_dtau_dv']:>14.3f}")


def plot(path: pathlib.Path, trajectory: dict, result: dict, joints: list[str]) -> None:
    """Three panels sharing t: torques, |d tau_i / d q|, |d tau_i / d v|."""
    import matplotlib
    matplotlib.use("Agg")  # files only, no display needed
    import matplotlib.pyplot as plt

    panels = [("tau", "torque [N m]"), ("dq", "|d tau_i / d q| [N m / rad]"),
              ("dv", "|d tau_i / d v| [N m s / rad]")]
    figure, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(8, 9))
    for axis, (key, label) in zip(axes, panels):
        for i, joint in enumerate(joints):
            axis.plot(trajectory["t"], result[key][:, i], label=joint)
        axis.set_ylabel(label)
        axis.grid(True, alpha=0.3)
    axes[0].legend(ncol=4, fontsize="small")
    axes[-1].set_xlabel("t [s]")
    figure.suptitle("joint torques along the swing and their sensitivity (RNEA and its Jacobian)")
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)


def write_csv(path: pathlib.Path, trajectory: dict, result: dict, joints: list[str]) -> None:
    """t, q_, v_, a_, tau_, dq_norm_, dv_norm_ per joint, one knot a row."""
    blocks = [("q", trajectory["q"]), ("v", trajectory["v"]), ("a", trajectory["a"]), ("tau", result["tau"]),
              ("dq_norm", result["dq"]), ("dv_norm", result["dv"])]
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["t"] + [f"{name}_{joint}" for name, _ in blocks for joint in joints])
        for k, t in enumerate(trajectory["t"]):
            writer.writerow([repr(float(t))] + [repr(float(x)) for _, block in blocks for x in block[k]])


def main(args: argparse.Namespace) -> int:
    model = connect(args).load(args.urdf)
    if model.nq != model.nv:
        raise SystemExit("plot_torques.py handles fixed-base robots (nq == nv)")
    joints = model.joint_names
    trajectory = swing(model.nv, args.knots, args.duration)
    result = torques_and_sensitivity(model.function(SPECS / "rnea_jacobian.json"), trajectory, model.nv)
    rows = summary(trajectory, result, joints)
    if args.csv:
        write_csv(args.csv, trajectory, result, joints)
    try:
        importlib.import_module("matplotlib")  # only to know whether the plot can be made
        plotted = True
    except ImportError as error:
        plotted = False
        print(f"matplotlib is not importable ({error}): no plot written. Install it (Debian: "
              "apt-get install python3-matplotlib; in a venv: pip install matplotlib) for the PNG; "
              "the summary follows.")
    if plotted:
        plot(args.out, trajectory, result, joints)
        print(f"wrote {args.out}: torques and |d tau / d q|, |d tau / d v| of {len(joints)} joints "
              f"at {args.knots} knots")
    if args.json:
        print(json.dumps({"plotted": plotted, "out": str(args.out) if plotted else None, "joints": rows}))
    else:
        print_summary(rows)
    return 0


def parse_arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_client_arguments(parser)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("torques.png"),
                        help="the PNG to write (default torques.png)")
    parser.add_argument("--knots", type=int, default=400)
    parser.add_argument("--duration", type=float, default=4.0, help="seconds (default 4)")
    parser.add_argument("--csv", type=pathlib.Path, help="also write the knots' values to this CSV")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON (last line)")
    args = parser.parse_args()
    if args.knots < 2 or args.duration <= 0:
        parser.error("--knots must be >= 2 and --duration > 0")
    return args


if __name__ == "__main__":
    arguments = parse_arguments()
    run(main, arguments, [SPECS / "rnea_jacobian.json"])
