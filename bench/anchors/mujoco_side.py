"""The MuJoCo side of bench/anchors' Euler step rows (euler_step_value, euler_step_jacobian):
builds the robot's MuJoCo model (mujoco_model.py), runs mujoco_bench at the anchors' check
states, maps its outputs to Pinocchio's joint order, checks them against Pinocchio's step
(anchors_bench's euler_step rows), and merges
the figures into compare.py's result as the side "mujoco".

MuJoCo's Jacobian comes from finite differences (mjd_transitionFD): forward differences
are the table's figure, centered ones are measured and checked too (JSON: centered_us).
Fixed-base robots only (the step's q is then plain joint angles in both)."""
import json
import os
import subprocess
import sys

import numpy as np

import mujoco_model

VALUE_LIMIT = 1e-9     # relative error of the next state
JACOBIAN_LIMIT = 1e-5  # relative error of finite-difference Jacobians
ROWS = ("euler_step_value", "euler_step_jacobian")


def bench_path(anchors_bench):
    """mujoco_bench is built beside anchors_bench."""
    return os.path.join(os.path.dirname(os.path.abspath(anchors_bench)), "mujoco_bench")


def set_note(result, note):
    for row in ROWS:
        slot = result["rows"].setdefault(row, {}).setdefault("mujoco", {})
        slot.setdefault("us", None)
        slot["note"] = note


def pinocchio_joint_names(urdf):
    import pinocchio as pin

    model = pin.buildModelFromUrdf(urdf)
    if model.nq != model.nv:  # continuous joints: (cos, sin) in Pinocchio, an angle in MuJoCo
        raise ValueError(f"Pinocchio's model has nq {model.nq} != nv {model.nv}: only angle joints are mapped")
    return [model.names[i] for i in range(1, model.njoints)]


def write_states(path, states, order, names):
    """The check states in MuJoCo's joint order (u = each state's tau, in Pinocchio's
    order: the actuators were added in that order)."""
    perm = [names.index(n) for n in order]  # Pinocchio index of MuJoCo joint k
    n = len(names)
    with open(path, "w") as f:
        f.write(f"{len(states)} {n} {n} {n}\n")
        for s in states:
            q, v = np.array(s["q"])[perm], np.array(s["v"])[perm]
            f.write(" ".join(repr(float(x)) for x in [*q, *v, *s["tau"]]) + "\n")


def in_pinocchio_order(output, order, names):
    """mujoco_bench's outputs (value [qpos; qvel], [A B] forward and centered) with rows
    and state columns in Pinocchio's order."""
    nv = len(names)
    p = [order.index(n) for n in names]  # MuJoCo index of Pinocchio joint k
    rows = p + [nv + i for i in p]
    cols = rows + list(range(2 * nv, 3 * nv))
    value = np.array(output["value"])[rows]
    mapped = {key: np.array(output[key])[np.ix_(rows, cols)] for key in ("forward", "centered")}
    return value, mapped


def reference_outputs(anchors, robot, dt):
    """Pinocchio's euler_step outputs at the check states, and where they come from."""
    rows = {r["name"]: r for r in anchors["sides"]["pinocchio"]}
    if "euler_step_jacobian" in rows and rows["euler_step_jacobian"].get("outputs"):
        return rows["euler_step_jacobian"]["outputs"], "anchors_bench's Pinocchio"
    return [], "no Pinocchio step rows (nothing to check against)"


def check(data, anchors, robot, order, names):
    """Max relative errors {value, forward, centered} against Pinocchio's step."""
    from compare import rel_err

    reference, source = reference_outputs(anchors, robot, data["dt"])
    err = {"value": 0.0, "forward": 0.0, "centered": 0.0}
    for output, ref in zip(data["outputs"], reference):
        value, jacobians = in_pinocchio_order(output, order, names)
        err["value"] = max(err["value"], rel_err(value, ref["value"]))
        for key in ("forward", "centered"):
            err[key] = max(err[key], rel_err(jacobians[key], ref["jacobian"]))
    if len(data["outputs"]) != len(reference):
        err = {k: float("inf") for k in err}
    return err, source


def merge(result, data, err):
    us = {r["name"]: r["us_per_call"] for r in data["rows"]}
    ok = {"euler_step_value": err["value"] <= VALUE_LIMIT,
          "euler_step_jacobian": err["value"] <= VALUE_LIMIT and err["forward"] <= JACOBIAN_LIMIT}
    for row in ROWS:
        slot = result["rows"].setdefault(row, {}).setdefault("mujoco", {})
        if not ok[row] or slot.get("wrong"):
            worst = err["value"] if row == "euler_step_value" else max(err["value"], err["forward"])
            slot.update(us=None, wrong=True, status="wrong", note=f"WRONG: max err {worst:.3g}")
            continue
        slot["status"] = "ok"
        if slot.get("us") is None or us[row] < slot["us"]:
            slot["us"] = us[row]
    jac = result["rows"]["euler_step_jacobian"]["mujoco"]
    if err["centered"] <= JACOBIAN_LIMIT and not jac.get("wrong"):
        jac["centered_us"] = min(jac.get("centered_us", float("inf")), us["euler_step_jacobian_centered"])


def measure_round(anchors_bench, robot, work, anchors, quick, result):
    """One round of the MuJoCo side for `robot` into `result` (compare.py's)."""
    bench = bench_path(anchors_bench)
    if robot.floating_base:
        return set_note(result, "fixed base only")
    if not os.access(bench, os.X_OK):
        return set_note(result, "mujoco_bench not built")
    print(f"anchors: {robot.title}: MuJoCo ...", file=sys.stderr)
    mj_dir = os.path.join(work, "mujoco")
    try:
        names = pinocchio_joint_names(robot.urdf)
        model, order = mujoco_model.build(robot.urdf, mj_dir, names)
    except ValueError as e:
        print(f"anchors: {robot.title}: MuJoCo model: {e}", file=sys.stderr)
        return set_note(result, "no model")
    states, out = os.path.join(mj_dir, "states.txt"), os.path.join(mj_dir, "mujoco.json")
    write_states(states, anchors["states"], order, names)
    cmd = [bench, "--model", model, "--states", states, "--out", out] + (["--quick"] if quick else [])
    if subprocess.run(cmd).returncode != 0:
        return set_note(result, "failed")
    with open(out) as f:
        data = json.load(f)
    err, source = check(data, anchors, robot, order, names)
    merge(result, data, err)
    result["mujoco_version"] = data["mujoco_version"]
    result["checks"]["MuJoCo euler_step"] = (
        f"value {err['value']:.1e} (limit {VALUE_LIMIT:g}), forward-difference J {err['forward']:.1e}, "
        f"centered J {err['centered']:.1e} (limit {JACOBIAN_LIMIT:g}; eps {data['eps']:g}; against {source})")


def title():
    """The side in the tables' header."""
    try:
        import mujoco
        version = mujoco.__version__
    except ImportError:
        version = "(not installed)"
    return f"MuJoCo {version} (mj_step / mjd_transitionFD forward differences)"
