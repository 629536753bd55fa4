"""Inertial parameter identification in Python: measured (q, v, a, tau) samples, the
joint-torque regressor Y(q, v, a) at every sample in ONE batched call
(examples/specs/regressor.json), the base parameters and their least-squares estimate with
numpy, printed against the URDF's values (the truth when the data came from that URDF).

The CSV is what `robodiff identify --data` reads (docs/jobs.md): a header, then one sample
per row, columns q_<joint>, v_<joint>, a_<joint>, tau_<joint> for every joint (any order,
other columns ignored). Without --csv the example makes its own: random states, their
torques from RNEA (examples/specs/rnea_jacobian.json, one batched call) plus Gaussian noise
(--noise N m, --samples, --seed); --write-csv FILE keeps them.

Run from the repository root, after building the module (docs/python.md):

    build/bin/robodiff warmup --urdf examples/robots/arm7.urdf \\
        --spec examples/specs/regressor.json --spec examples/specs/rnea_jacobian.json
    PYTHONPATH=build/python build/venv/bin/python examples/python/identify_from_csv.py --write-csv samples.csv
    PYTHONPATH=build/python build/venv/bin/python examples/python/identify_from_csv.py --csv samples.csv
    build/bin/robodiff identify --urdf examples/robots/arm7.urdf --data samples.csv   # the C++ fit, same data

Options: --urdf (a fixed-base robot), --json (the result as JSON), --server, --cache-dir,
--warmup (build the functions into the cache first, with robodiff.warmup, instead of the
warmup command above).
"""

from __future__ import annotations

import argparse
import csv
import json
import pathlib

import numpy as np

from base_parameters import base_parameters
from example_support import SPECS, add_client_arguments, connect, run
from urdf_parameters import inertial_parameters

BLOCKS = ("q", "v", "a", "tau")


def read_samples(path: pathlib.Path, joints: list[str]) -> dict[str, np.ndarray]:
    """The q, v, a, tau blocks of a samples CSV, each (N, joints), in the model's joint order."""
    with open(path, newline="") as stream:
        rows = list(csv.reader(stream))
    if len(rows) < 2:
        raise SystemExit(f"{path}: no samples (a header and at least one row are needed)")
    header = rows[0]
    data = np.array([[float(x) for x in row] for row in rows[1:] if row], dtype=float)
    blocks = {}
    for block in BLOCKS:
        names = [f"{block}_{joint}" for joint in joints]
        missing = [name for name in names if name not in header]
        if missing:
            raise SystemExit(f"{path}: no column {missing[0]} (columns {block}_<joint> for the joints "
                             f"{', '.join(joints)} are needed)")
        blocks[block] = np.ascontiguousarray(data[:, [header.index(name) for name in names]])
    return blocks


def write_samples(path: pathlib.Path, joints: list[str], samples: dict[str, np.ndarray]) -> None:
    """Writes samples in the CSV form read_samples and `robodiff identify` read."""
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow([f"{block}_{joint}" for block in BLOCKS for joint in joints])
        for row in np.hstack([samples[block] for block in BLOCKS]):
            writer.writerow([repr(float(x)) for x in row])


def random_states(count: int, nv: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """States spread enough to excite every parameter: q in +-2 rad, v in +-2 rad/s, a in +-4 rad/s^2."""
    return {"q": rng.uniform(-2, 2, (count, nv)), "v": rng.uniform(-2, 2, (count, nv)),
            "a": rng.uniform(-4, 4, (count, nv))}


def simulate(model, args: argparse.Namespace) -> dict[str, np.ndarray]:
    """Samples from the robot itself: RNEA torques at random states, plus noise."""
    rng = np.random.default_rng(args.seed)
    samples = random_states(args.samples, model.nv, rng)
    rnea = model.function(SPECS / "rnea_jacobian.json")
    tau = rnea(**samples)["value"]
    samples["tau"] = tau + rng.normal(0.0, args.noise, tau.shape)
    return samples


def identify(model, samples: dict[str, np.ndarray], truth: np.ndarray) -> dict:
    """The base parameters' least-squares estimate, standard errors, fit residuals and truth."""
    regressor = model.function(SPECS / "regressor.json")
    nv = model.nv
    # Which parameter combinations are identifiable: decided once per robot, from random states.
    probe = random_states(50, nv, np.random.default_rng(0))
    base = base_parameters(regressor(**probe)["value"].reshape(50 * nv, -1))
    w = regressor(q=samples["q"], v=samples["v"], a=samples["a"])["value"]  # (N, nv, 10 nv): one call
    w_base = w.reshape(-1, w.shape[2])[:, base.independent]
    tau = samples["tau"].reshape(-1)
    if w_base.shape[0] < w_base.shape[1]:
        raise SystemExit(f"{w_base.shape[0]} torque rows for {w_base.shape[1]} base parameters: "
                         "more samples are needed")
    estimate, *_ = np.linalg.lstsq(w_base, tau, rcond=None)
    residual = (tau - w_base @ estimate).reshape(-1, nv)
    dof = max(w_base.shape[0] - w_base.shape[1], 1)
    variance = residual.ravel() @ residual.ravel() / dof
    stderr = np.sqrt(variance * np.diag(np.linalg.inv(w_base.T @ w_base)))
    return {"names": base.names(model.joint_names), "truth": base.of(truth).tolist(),
            "estimate": estimate.tolist(), "stderr": stderr.tolist(),
            "residual_rms": np.sqrt(np.mean(residual ** 2, axis=0)).tolist(),
            "samples": int(samples["q"].shape[0]), "standard_parameters": int(w.shape[2])}


def print_report(result: dict, joints: list[str]) -> None:
    """The estimate beside the truth, one base parameter a line."""
    print(f"{result['samples']} samples, {result['standard_parameters']} standard parameters, "
          f"{len(result['names'])} base parameters ('+': others fold into it)")
    print(f"{'base parameter':<18}{'URDF':>14}{'identified':>14}{'std err':>11}{'z':>7}")
    for name, true, got, err in zip(result["names"], result["truth"], result["estimate"], result["stderr"]):
        z = (got - true) / err if err > 0 else 0.0
        print(f"{name:<18}{true:>14.6f}{got:>14.6f}{err:>11.2e}{z:>7.2f}")
    truth, estimate = np.array(result["truth"]), np.array(result["estimate"])
    print(f"relative error |estimate - truth| / |truth| = "
          f"{np.linalg.norm(estimate - truth) / np.linalg.norm(truth):.2e}")
    print("residual torque RMS per joint [N m]: "
          + ", ".join(f"{j} {r:.4f}" for j, r in zip(joints, result["residual_rms"])))


def main(args: argparse.Namespace) -> int:
    model = connect(args).load(args.urdf)
    if model.nq != model.nv:
        raise SystemExit("identify_from_csv.py handles fixed-base robots (nq == nv)")
    joints = model.joint_names
    samples = read_samples(args.csv, joints) if args.csv else simulate(model, args)
    if args.write_csv:
        write_samples(args.write_csv, joints, samples)
    truth = inertial_parameters(args.urdf, joints)
    result = identify(model, samples, truth)
    result["source"] = str(args.csv) if args.csv else f"simulated, noise {args.noise} N m"
    if args.json:
        print(json.dumps(result))
    else:
        print(f"{model!r}: {result['source']}")
        print_report(result, joints)
    return 0


def parse_arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_client_arguments(parser)
    parser.add_argument("--csv", type=pathlib.Path, help="the samples (default: simulate them)")
    parser.add_argument("--write-csv", type=pathlib.Path, help="write the samples used to this CSV")
    parser.add_argument("--samples", type=int, default=400, help="simulated samples (default 400)")
    parser.add_argument("--noise", type=float, default=0.05, help="simulated torque noise, N m (default 0.05)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    return parser.parse_args()


if __name__ == "__main__":
    arguments = parse_arguments()
    run(main, arguments, [SPECS / "regressor.json", SPECS / "rnea_jacobian.json"])
