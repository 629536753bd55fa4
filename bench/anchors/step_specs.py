"""The step rows on robodiff's side: the user-function specs of specs/ (euler_step.json,
step_cost.json) with the robot's frame filled in, the names `robodiff bench --spec` gives
their rows, and the check of robodiff's outputs against Pinocchio's (anchors_bench's
step rows) through `robodiff compute --backend generated` on the libraries robodiff bench
kept (kept_compute.py)."""
import json
import os
import subprocess

import numpy as np

import kept_compute

HERE = os.path.dirname(os.path.abspath(__file__))
SPECS = ["euler_step", "step_cost"]
# table row -> robodiff bench's row (the spec's name; NAME_value: its value outputs alone)
BENCH_ROWS = {"euler_step_value": "euler_step_value", "euler_step_jacobian": "euler_step",
              "step_cost_value": "step_cost_value", "step_cost_derivatives": "step_cost"}
# robodiff's exact Hessian against central differences of Pinocchio's analytic gradient
# (h = 1e-5: truncation ~1e-10, rounding ~1e-11 relative)
FD_HESSIAN_LIMIT = 1e-6


def crocoddyl_version():
    try:
        from importlib.metadata import version
        return version("crocoddyl")
    except Exception:  # noqa: BLE001 (not installed: the header says so)
        return "(not installed)"


def write_specs(frame, work, names=SPECS):
    """specs/NAME.json of each name (default: the step rows') with @FRAME@ replaced by
    `frame`, into work/; returns their paths."""
    paths = []
    for name in names:
        with open(os.path.join(HERE, "specs", f"{name}.json")) as f:
            text = f.read().replace("@FRAME@", frame)
        path = os.path.join(work, f"{name}.json")
        with open(path, "w") as f:
            f.write(text)
        paths.append(path)
    return paths


def value_only_spec(work, name):
    """The spec's value outputs alone (what robodiff bench times as NAME_value), written beside it."""
    with open(os.path.join(work, f"{name}.json")) as f:
        spec = json.load(f)
    spec["outputs"] = [o for o in spec["outputs"] if o["kind"] == "value"]
    spec["name"] = f"{name}_value"
    path = os.path.join(work, f"{name}_value.json")
    with open(path, "w") as f:
        json.dump(spec, f)
    return path


def flat(x):
    return np.asarray(x, dtype=float).reshape(-1)


def step_outputs(out, cost):
    """robodiff compute's JSON in the anchors' terms: value, and jacobian, gradient, hessian when there."""
    value = [flat(out["q_next"]), flat(out["v_next"])] + ([flat(out["l"])] if cost else [])
    o = {"value": np.concatenate(value)}
    if "dq_next" in out:
        o["jacobian"] = np.vstack([np.asarray(out["dq_next"]), np.asarray(out["dv_next"])])
    if "l_gradient" in out:
        o["gradient"], o["hessian"] = flat(out["l_gradient"]), np.asarray(out["l_hessian"])
    return o


def check_robodiff(robodiff, robot, anchors, work, rel_err, run):
    """{row: max relative error} of robodiff's step rows against Pinocchio's (values, the
    step's Jacobian, the cost's gradient), and the error of its exact Hessian against
    central differences of Pinocchio's gradient."""
    reference = {r["name"]: r["outputs"] for r in anchors["sides"]["pinocchio"]}
    specs = {"euler_step_value": value_only_spec(work, "euler_step"),
             "euler_step_jacobian": os.path.join(work, "euler_step.json"),
             "step_cost_value": value_only_spec(work, "step_cost"),
             "step_cost_derivatives": os.path.join(work, "step_cost.json")}
    errors, hessian_err = {}, 0.0
    for row, spec in specs.items():
        err = 0.0
        for k, state in enumerate(anchors["states"]):
            path = os.path.join(work, f"step_state{k}.json")
            with open(path, "w") as f:
                json.dump({"q": state["q"], "v": state["v"], "u": state["tau"]}, f)
            cmd = kept_compute.command(robodiff, robot, spec, work, BENCH_ROWS[row], path)
            out = step_outputs(json.loads(run(cmd, stderr=subprocess.DEVNULL)), row.startswith("step_cost"))
            ref = reference[row][k]
            for key in ("value", "jacobian", "gradient"):
                if key in ref or key in out:
                    err = max(err, rel_err(out.get(key, []), ref.get(key, [])))
            if "hessian" in out:
                hessian_err = max(hessian_err, rel_err(out["hessian"], ref["exact_hessian"]))
        errors[row] = err
    return errors, hessian_err
