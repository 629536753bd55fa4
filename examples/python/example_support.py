"""What the Python examples share: the repository's paths, the client options on the
command line, and one readable message (with the warmup command) when a function cannot
be had.

Not an example itself; mpc_horizon.py, identify_from_csv.py and plot_torques.py import it.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import shlex
import sys
from typing import Callable, Sequence

REPO = pathlib.Path(__file__).resolve().parents[2]
HERE = pathlib.Path(__file__).resolve().parent
ARM7 = REPO / "examples" / "robots" / "arm7.urdf"
SPECS = REPO / "examples" / "specs"
PY_SPECS = HERE / "specs"

try:
    import robodiff
except ImportError as error:  # the module is built, not installed, in a plain build tree
    sys.exit(f"robodiff is not importable ({error}): build the module (docs/python.md) and run "
             "with PYTHONPATH=build/python, or pip install ./python")


def add_client_arguments(parser: argparse.ArgumentParser) -> None:
    """--urdf (default: the project's arm7), --server and --cache-dir, as robodiff.Client takes them."""
    parser.add_argument("--urdf", type=pathlib.Path, default=ARM7,
                        help="the robot (default: examples/robots/arm7.urdf)")
    parser.add_argument("--server", default=None,
                        help="auto | local | shm | dds ... (default: $ROBODIFF_SERVER, else auto)")
    parser.add_argument("--cache-dir", type=pathlib.Path, default=None,
                        help="local mode's cache (default: $ROBODIFF_CACHE_DIR, else robodiff's default)")
    parser.add_argument("--warmup", action="store_true",
                        help="first build the example's functions into that cache (robodiff.warmup)")


def connect(args: argparse.Namespace) -> "robodiff.Client":
    """A Client with the command line's server and cache."""
    return robodiff.Client(args.server, cache_dir=args.cache_dir)


def warmup_command(urdf: os.PathLike, specs: Sequence[os.PathLike], cache_dir=None) -> str:
    """The `robodiff warmup` command that puts these functions in the cache."""
    words = ["build/bin/robodiff", "warmup", "--urdf", os.fspath(urdf)]
    for spec in specs:
        words += ["--spec", os.fspath(spec)]
    if cache_dir is not None:
        words += ["--cache", os.fspath(cache_dir)]
    return shlex.join(words)


def warm(args: argparse.Namespace, specs: Sequence[os.PathLike]) -> None:
    """--warmup: builds the functions into the cache with robodiff.warmup (those already
    there are reported as cached), one line each on stderr."""
    warmup = getattr(robodiff, "warmup", None)
    if warmup is None:
        raise SystemExit("--warmup: this build of the module has no robodiff.warmup; run instead:\n  "
                         + warmup_command(args.urdf, specs, args.cache_dir))

    def report(result) -> None:
        print(f"warmup: {result.function} {result.state} in {result.seconds:.1f} s", file=sys.stderr)

    summary = warmup(args.urdf, list(specs), cache_dir=args.cache_dir, progress=report)
    if not summary.ok:
        raise SystemExit("warmup failed: " + "; ".join(f"{r.spec}: {r.message}" for r in summary.failed))


def run(main: Callable[[argparse.Namespace], int], args: argparse.Namespace,
        specs: Sequence[os.PathLike]) -> None:
    """Runs main(args) and exits with its status; a robodiff.Error is printed in one
    message, with the warmup command for `specs` when a function was not in the cache.
    With --warmup the functions are built first."""
    try:
        if args.warmup:
            warm(args, specs)
        sys.exit(main(args))
    except robodiff.Error as error:
        print(f"robodiff: {error}", file=sys.stderr)
        if error.code == "FAILED_PRECONDITION":
            print("fill the cache first (or start robodiffd):\n  "
                  + warmup_command(args.urdf, specs, args.cache_dir), file=sys.stderr)
        sys.exit(1)
