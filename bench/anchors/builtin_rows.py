"""The CRBA and frame-Jacobian rows on robodiff's side: robodiff bench has no built-in row
for them, so they come in as the built-in function specs specs/crba_value.json and
specs/frame_jacobian_value.json (`robodiff bench --spec`; the row is the file's stem), the
frame Jacobian's frame being the anchors' (the model's last frame, LOCAL_WORLD_ALIGNED).
Checked against Pinocchio's outputs through `robodiff compute --backend generated` on the
libraries robodiff bench kept (kept_compute.py).
Fixed and floating base alike."""
import json
import os
import subprocess

import kept_compute
import step_specs

ROWS = ["crba_value", "frame_jacobian_value"]  # the table's rows, robodiff bench's rows, the specs' stems


def write_specs(frame, work):
    """The two specs, the frame Jacobian's at `frame`, into work/; returns their paths."""
    return step_specs.write_specs(frame, work, ROWS)


def check_robodiff(robodiff, robot, anchors, work, rel_err, run):
    """{row: max relative error} of robodiff's compiled M(q) and frame Jacobian against
    Pinocchio's (anchors_bench puts the matrix in its outputs' "jacobian") at the anchors'
    check states."""
    reference = {r["name"]: r["outputs"] for r in anchors["sides"]["pinocchio"]}
    errors = {}
    for row in ROWS:
        err = 0.0
        for k, state in enumerate(anchors["states"]):
            path = os.path.join(work, f"q_state{k}.json")
            with open(path, "w") as f:
                json.dump({"q": state["q"]}, f)
            cmd = kept_compute.command(robodiff, robot, os.path.join(work, f"{row}.json"), work, row, path)
            out = json.loads(run(cmd, stderr=subprocess.DEVNULL))
            err = max(err, rel_err(out["value"], reference[row][k]["jacobian"]))
        errors[row] = err
    return errors
