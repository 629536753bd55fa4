"""bench/anchors driver: after a build phase that builds every robot's anchor libraries
several at once (build_phase.py), for each robot alternately runs
anchors_bench (Pinocchio, CppADCodeGen and CasADi, the step rows of Pinocchio and
crocoddyl, and of the generated sides on a fixed base) and `robodiff bench --json` (with
the CRBA and frame-Jacobian specs, builtin_rows.py, and the step rows' specs,
step_specs.py; all in specs/), two rounds, keeps
the minimum per cell, checks robodiff's values and derivatives (`robodiff compute
--backend generated --kept`: the libraries robodiff bench timed, kept_compute.py) against
Pinocchio's at the anchors' check states, and prints one table per robot.

Run through bench/anchors/run (it builds anchors_bench and passes the paths)."""
import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import build_phase  # noqa: E402
import report  # noqa: E402
import robots  # noqa: E402
import step_specs  # noqa: E402
import builtin_rows  # noqa: E402
import kept_compute  # noqa: E402
import mujoco_side  # noqa: E402

LIMIT = 1e-9  # relative error (scaled by max(1, |reference|)) a side may have


def parse_args():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--robots", default=robots.DEFAULT_ROBOTS, help="comma-separated: " + ", ".join(robots.CATALOGUE))
    p.add_argument("--json", help="write the merged results as JSON to FILE")
    p.add_argument("--plot", help="write µs per call against DoF as a PNG to FILE")
    p.add_argument("--quick", action="store_true", help="shorter timing on every side (noisier)")
    p.add_argument("--rounds", type=int, default=2, help="alternating rounds; the minimum per cell is kept")
    p.add_argument("--cap", type=float, default=120, help="seconds a CppADCodeGen library may take to build")
    p.add_argument("--casadi-cap", type=float, default=60, help="seconds a CasADi library may take to build")
    p.add_argument("--build-jobs", type=int, default=os.cpu_count() or 1,
                   help="libraries built at once in the build phase (default: the cores; 1: each build alone)")
    p.add_argument("--bench", required=True, help="anchors_bench executable")
    p.add_argument("--robodiff", required=True, help="robodiff CLI executable")
    p.add_argument("--work", required=True, help="working directory (libraries, outputs)")
    return p.parse_args()


def run(cmd, **kw):
    """Runs cmd; its stderr goes through (progress), a failure stops with its message."""
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, text=True, **kw)
    if proc.returncode != 0:
        raise SystemExit(f"anchors: failed ({proc.returncode}): {' '.join(cmd)}")
    return proc.stdout


def anchors_round(args, robot, work, round_number):
    """anchors_bench on the libraries of the build phase (--reuse)."""
    out = os.path.join(work, f"anchors_round{round_number}.json")
    cmd = [args.bench, "--urdf", robot.urdf, "--out", out, "--workdir", os.path.join(work, "cppadcodegen"),
           "--cap", str(args.cap), "--reuse"]
    cmd += ["--floating-base"] if robot.floating_base else []
    cmd += ["--quick"] if args.quick else []
    run(cmd)
    with open(out) as f:
        return json.load(f)


def robodiff_round(args, robot, specs, work, reuse):
    """robodiff bench: the first round builds cold (its build rows), later ones reuse those
    libraries; built with "batch": false, single-knot code alone, as the anchors build theirs.
    The cold round compiles through measured_cc, as the anchors do: (bench's JSON, each
    row's largest compiler peak in KiB from measured_cc's log)."""
    keep = os.path.join(work, "robodiff_bench")
    cmd = [args.robodiff, "bench", "--urdf", robot.urdf, "--json", "--no-batch", "--keep", keep]
    cmd += ["--reuse"] if reuse else []
    cmd += ["--floating-base"] if robot.floating_base else []
    cmd += ["--quick"] if args.quick else []
    for path in specs:
        cmd += ["--spec", path]
    log = os.path.join(work, "robodiff_compilers.log")
    if os.path.exists(log):
        os.remove(log)
    env = dict(os.environ, CC=os.environ["ANCHORS_MEASURED_CC"], ANCHORS_CC_LOG=log)
    return json.loads(run(cmd, env=env)), logged_peaks(log, keep)


def logged_peaks(log, keep):
    """measured_cc's "<KiB> <output>" lines, the largest per folder under `keep` (a row's)."""
    peaks = {}
    if not os.path.exists(log):
        return peaks
    with open(log) as f:
        for line in f:
            kib, _, output = line.rstrip("\n").partition(" ")
            rel = os.path.relpath(os.path.abspath(output), keep)
            if rel.startswith(".."):
                continue  # not a row's (a probe of the compiler)
            row = rel.split(os.sep)[0]
            peaks[row] = max(peaks.get(row, 0), int(kib))
    return peaks


def keep_min(slot, us):
    if us is not None and (slot.get("us") is None or us < slot["us"]):
        slot["us"] = us


def merge_anchors(result, data):
    for side in ("pinocchio", "cppadcodegen", "casadi", "crocoddyl"):
        for row in data["sides"].get(side, []):
            slot = result["rows"].setdefault(row["name"], {}).setdefault(side, {})
            slot["status"] = row["status"]
            if row["note"]:
                slot["note"] = row["note"]
            if row["status"] == "wrong":
                slot["us"] = None
                slot["wrong"] = True
            elif not slot.get("wrong"):
                keep_min(slot, row["us_per_call"])
            if side in ("cppadcodegen", "casadi") and row["status"] in ("ok", "over_cap"):
                b = result["builds"].setdefault(row["name"], {}).setdefault(side, {})
                b.setdefault("seconds", row["build_seconds"])
                b.setdefault("mib", row["compiler_mib"])
                if row["note"]:
                    b["note"] = row["note"]


def merge_robodiff(result, round_output):
    data, peaks = round_output
    rows = {r["name"]: r for r in data["rows"]}
    for name, _ in report.ROWS:
        bench_name = step_specs.BENCH_ROWS.get(name, name)  # robodiff bench's name of the row
        if bench_name in rows and "us_per_call" in rows[bench_name]:
            keep_min(result["rows"].setdefault(name, {}).setdefault("robodiff", {}), rows[bench_name]["us_per_call"])
        total = rows.get(f"build.{bench_name}.total")
        mem = rows.get(f"build.{bench_name}.compiler_peak_memory")
        if total is not None:
            b = result["builds"].setdefault(name, {}).setdefault("robodiff", {})
            b["seconds"] = min(b.get("seconds", float("inf")), total["seconds"])
            mib = peaks[bench_name] / 1024 if bench_name in peaks else mem["bytes"] / 2**20
            b["mib"] = min(b.get("mib", float("inf")), mib)


def rel_err(actual, expected):
    import numpy as np
    a, e = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    if a.shape != e.shape:
        return float("inf")
    if e.size == 0:
        return 0.0
    err = float(np.max(np.abs(a - e)) / max(1.0, float(np.max(np.abs(e)))))
    return err if err == err else float("inf")


# robodiff's built-in rows as the specs its checks build and load (with "batch": false, as
# robodiff bench --no-batch builds them): row -> (function, the inputs of its Jacobian or None)
CHECKED_ROWS = {"rnea_value": ("rnea", None), "rnea_jacobian_dense": ("rnea", ["q", "v", "a"]),
                "aba_value": ("aba", None), "aba_jacobian": ("aba", ["q", "v", "tau"])}


def write_check_specs(work):
    """{row: spec file} of CHECKED_ROWS, written into work/."""
    paths = {}
    for row, (function, wrt) in CHECKED_ROWS.items():
        outputs = [{"kind": "value"}] + ([{"kind": "jacobian", "wrt": wrt}] if wrt else [])
        paths[row] = os.path.join(work, f"check_{row}.json")
        with open(paths[row], "w") as f:
            json.dump({"function": function, "outputs": outputs, "build": {"batch": False}}, f)
    return paths


def check_robodiff(args, robot, anchors, work):
    """robodiff's generated libraries at the anchors' check states against Pinocchio's
    outputs; returns {row: max relative error}."""
    reference = {r["name"]: r["outputs"] for r in anchors["sides"]["pinocchio"]}
    errors = {}
    for row, spec in write_check_specs(work).items():
        derivatives = CHECKED_ROWS[row][1] is not None
        err = 0.0
        for k, state in enumerate(anchors["states"]):
            path = os.path.join(work, f"state{k}.json")
            with open(path, "w") as f:
                json.dump(state, f)
            cmd = kept_compute.command(args.robodiff, robot, spec, work, row, path)
            cmd += ["--derivatives"] if derivatives else []
            out = json.loads(run(cmd, stderr=subprocess.DEVNULL))
            ref = reference[row][k]
            err = max(err, rel_err(out["value"], ref["value"]))
            if derivatives:
                err = max(err, rel_err(out["jacobian"], ref["jacobian"]))
        errors[row] = err
    return errors


class Prepared:
    """A robot's work folder, the --spec files of its robodiff bench rounds (CRBA, frame J
    and the step rows; the frame: the anchors' last) and its anchors' build jobs."""

    def __init__(self, args, robot):
        self.robot, self.work = robot, os.path.join(args.work, robot.key)
        os.makedirs(self.work, exist_ok=True)
        generated = build_phase.generated_rows(args.bench, robot, self.work)
        self.nv = generated["nv"]
        self.specs = builtin_rows.write_specs(generated["frame"], self.work) + \
            step_specs.write_specs(generated["frame"], self.work)
        self.anchor_jobs = build_phase.anchor_jobs(args, robot, self.work, generated)


def build_everything(args, prepared):
    """The build phase of every robot at once: the anchors' libraries, longest first."""
    build_phase.build_all(build_phase.longest_first([(p.nv, p.anchor_jobs) for p in prepared]), args.build_jobs)


def record_checks(args, robot, first, work, result):
    """Every side's errors against Pinocchio's in result["checks"]; a robodiff row that
    disagrees loses its figure."""
    for side, title in (("cppadcodegen", "CppADCodeGen"), ("casadi", "CasADi"), ("crocoddyl", "crocoddyl")):
        for row in first["sides"].get(side, []):
            if row["status"] == "ok":
                result["checks"][f"{title} {row['name']}"] = f"{row['max_err']:.1e}"
    print(f"anchors: {robot.title}: checking robodiff's values and Jacobians ...", file=sys.stderr)
    errors = check_robodiff(args, robot, first, work)
    errors.update(builtin_rows.check_robodiff(args.robodiff, robot, first, work, rel_err, run))
    step_errors, hessian_err = step_specs.check_robodiff(args.robodiff, robot, first, work, rel_err, run)
    errors.update(step_errors)
    for row, err in errors.items():
        result["checks"][f"robodiff {row}"] = f"{err:.1e}"
        if not err <= LIMIT:
            slot = result["rows"][row].setdefault("robodiff", {})
            slot["us"], slot["note"] = None, f"WRONG: max err {err:.3g}"
    result["checks"]["robodiff step_cost exact Hessian vs central differences of Pinocchio's gradient "
                     f"(limit {step_specs.FD_HESSIAN_LIMIT:g})"] = f"{hessian_err:.1e}"
    if not hessian_err <= step_specs.FD_HESSIAN_LIMIT:
        slot = result["rows"]["step_cost_derivatives"].setdefault("robodiff", {})
        slot["us"], slot["note"] = None, f"WRONG: Hessian vs FD {hessian_err:.3g}"


def measure(args, prepared):
    robot, work = prepared.robot, prepared.work
    result = {"key": robot.key, "title": robot.title, "urdf": robot.urdf, "floating_base": robot.floating_base,
              "rows": {}, "builds": {}, "checks": {}}
    first = None
    for r in range(args.rounds):
        print(f"anchors: {robot.title}: round {r + 1}/{args.rounds}: Pinocchio, CppADCodeGen, CasADi ...",
              file=sys.stderr)
        data = anchors_round(args, robot, work, r + 1)
        first = first or data
        merge_anchors(result, data)
        print(f"anchors: {robot.title}: round {r + 1}/{args.rounds}: robodiff bench ...", file=sys.stderr)
        merge_robodiff(result, robodiff_round(args, robot, prepared.specs, work, reuse=r > 0))
        mujoco_side.measure_round(args.bench, robot, work, first, args.quick, result)
    result["nq"], result["nv"] = first["nq"], first["nv"]
    result["casadi_version"] = first.get("casadi_version")
    record_checks(args, robot, first, work, result)
    return result


def machine():
    try:
        out = subprocess.run(["lscpu"], stdout=subprocess.PIPE, text=True).stdout
        model = next(line.split(":", 1)[1].strip() for line in out.splitlines() if line.startswith("Model name"))
    except (OSError, StopIteration):
        model = platform.processor() or "unknown CPU"
    return f"{model}, {os.cpu_count()} hardware threads"


def use_measured_cc(args):
    """Both sides' cold builds run the compiler through measured_cc (measured_cc.cpp): its
    peak memory, not that of the process that started it."""
    measured = os.path.join(os.path.dirname(os.path.abspath(args.bench)), "measured_cc")
    if not os.access(measured, os.X_OK):
        raise SystemExit(f"anchors: {measured} is missing: build anchors_bench's project (bench/anchors/run does)")
    os.environ["ANCHORS_MEASURED_CC"] = measured
    os.environ["ANCHORS_REAL_CC"] = shutil.which("gcc") or "/usr/bin/gcc"


def main():
    args = parse_args()
    use_measured_cc(args)
    t0 = time.monotonic()
    selected = robots.resolve([k for k in args.robots.split(",") if k], args.work)
    prepared = [Prepared(args, robot) for robot in selected]
    build_everything(args, prepared)
    results = [measure(args, p) for p in prepared]
    casadi = next((r["casadi_version"] for r in results if r.get("casadi_version")), "?")
    minutes = (time.monotonic() - t0) / 60
    header = (f"bench/anchors, {time.strftime('%Y-%m-%d', time.gmtime())}, {machine()}; Pinocchio 3.7.0 (pin wheel), "
              f"CppADCodeGen 2.4.3 (gcc -O2 -march=native), CasADi {casadi} (SX, gcc -O3 -march=native), "
              f"crocoddyl {step_specs.crocoddyl_version()} "
              f"(calc / calc + calcDiff), {mujoco_side.title()}, robodiff bench; µs per call, minimum of {args.rounds} "
              f"alternating rounds{' (--quick)' if args.quick else ''}; ratio = robodiff / the best anchor; "
              f"run took {minutes:.1f} min")
    report.print_tables(results, header)
    if args.json:
        report.write_json(args.json, results, header)
    if args.plot:
        report.plot(args.plot, results)
        print(f"\nplot: {args.plot}")


if __name__ == "__main__":
    main()
