"""bench/anchors' build phase: every library the timed rounds load is built first, for
every robot at once, several at a time (--build-jobs, default the machine's cores), so
that the rounds time with nothing else running and the run's wall time is not the sum of
every build:

CppADCodeGen's and CasADi's libraries, one `anchors_bench --build-only` per library (each
built in a child process of its own that records its cold build time and the compiler's
peak memory; the rounds then load them with --reuse). The longest go first: every robot's
Jacobians, the robots with the most degrees of freedom first, then the values.

robodiff's libraries are not here: robodiff bench's first round builds them, alone (its
cold build figures), and keeps them for the second round and for the checks."""
import concurrent.futures
import json
import os
import subprocess
import sys
import time


def base_flags(robot):
    return ["--floating-base"] if robot.floating_base else []


def generated_rows(bench, robot, work):
    """anchors_bench --list-rows: {"cppadcodegen": [rows], "casadi": [rows], "frame": name}."""
    out = os.path.join(work, "rows.json")
    cmd = [bench, "--urdf", robot.urdf, "--out", out, "--workdir", os.path.join(work, "cppadcodegen"), "--list-rows"]
    subprocess.run(cmd + base_flags(robot), check=True, stdout=subprocess.DEVNULL)
    with open(out) as f:
        return json.load(f)


def anchor_jobs(args, robot, work, rows):
    """(label, [command]) of each generated anchor's library; CasADi's builds have a cap of
    their own (--casadi-cap: their times are not what robodiff's builds are held to)."""
    os.makedirs(os.path.join(work, "builds"), exist_ok=True)
    base = [args.bench, "--urdf", robot.urdf, "--workdir", os.path.join(work, "cppadcodegen"), "--build-only"]
    base += base_flags(robot)
    jobs = []
    for side, other, cap in (("cppadcodegen", "--no-casadi", args.cap), ("casadi", "--no-codegen", args.casadi_cap)):
        for row in rows[side]:
            out = os.path.join(work, "builds", f"{side}_{row}.json")
            jobs.append((f"{robot.title}: {side} {row}", [base + ["--cap", str(cap), other, "--codegen-rows", row, "--out", out]]))
    return jobs


def longest_first(jobs_by_size):
    """[(nv, jobs)] -> one list: the Jacobians (robots by nv, descending), then the values."""
    ordered = [job for _, jobs in sorted(jobs_by_size, key=lambda pair: -pair[0]) for job in jobs]
    return sorted(ordered, key=lambda job: job[0].endswith("_value"))  # stable


def run_job(job):
    label, commands = job
    t0 = time.monotonic()
    for cmd in commands:
        proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if proc.returncode != 0:
            tail = proc.stderr.strip().splitlines()[-3:]
            return label, time.monotonic() - t0, f"failed ({proc.returncode}): {' '.join(cmd)}: {' / '.join(tail)}"
    return label, time.monotonic() - t0, None


def build_all(jobs, workers):
    """Runs the jobs, `workers` at a time; an anchor build that fails stops the run (a
    build over the cap or refused by its compiler is not a failure: anchors_bench records
    it and the table shows it)."""
    print(f"anchors: building {len(jobs)} libraries, {workers} at a time ...", file=sys.stderr)
    t0 = time.monotonic()
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
        for done in concurrent.futures.as_completed([pool.submit(run_job, job) for job in jobs]):
            label, seconds, problem = done.result()
            print(f"anchors:   {label}: {seconds:.1f} s{' ' + problem if problem else ''}", file=sys.stderr)
            if problem:
                raise SystemExit(f"anchors: building {label} {problem}")
    print(f"anchors: the build phase took {(time.monotonic() - t0) / 60:.1f} min", file=sys.stderr)
