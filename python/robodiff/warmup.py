"""robodiff.warmup: build functions into the cache ahead of time, as ``robodiff warmup`` does.

The C++ warmup (robodiff._robodiff.warmup) builds every (robot, spec) pair in a pool of
``robodiff-worker`` processes, each cache key once across every process sharing the
cache; the GIL is released meanwhile. A local-mode Client on the same cache then finds
the functions compiled.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable, List, Mapping, Optional, Union

from . import _robodiff

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True)
class WarmupResult:
    """One (robot, spec) pair's outcome.

    state: ``"cached"`` (already in the cache, or built meanwhile by another process),
    ``"done"`` (built now) or ``"failed"`` (``message`` says why; nothing was cached).
    robot, function: the model's and the function's names; key: the cache key;
    seconds: how long it took; library_bytes: the compiled library's size.
    """

    urdf: str
    spec: str
    state: str
    robot: str
    function: str
    key: str
    message: str
    seconds: float
    library_bytes: int

    @property
    def ok(self) -> bool:
        """True when the function is in the cache (cached or built)."""
        return self.state != "failed"


@dataclass(frozen=True)
class WarmupSummary:
    """What a warmup did: ``results`` per pair (robot-major), and the pairs by outcome."""

    results: List[WarmupResult]
    seconds: float  # the whole warmup, wall clock

    @property
    def built(self) -> List[WarmupResult]:
        """Pairs compiled by this warmup."""
        return [r for r in self.results if r.state == "done"]

    @property
    def cached(self) -> List[WarmupResult]:
        """Pairs that were in the cache already (or that another process built meanwhile)."""
        return [r for r in self.results if r.state == "cached"]

    @property
    def failed(self) -> List[WarmupResult]:
        """Pairs that could not be built (``message`` says why)."""
        return [r for r in self.results if r.state == "failed"]

    @property
    def ok(self) -> bool:
        """True when every pair is in the cache."""
        return not self.failed

    def __repr__(self) -> str:
        return (f"<robodiff.WarmupSummary built={len(self.built)} cached={len(self.cached)} "
                f"failed={len(self.failed)} in {self.seconds:.1f} s>")


def _result(fields: Mapping[str, Any]) -> WarmupResult:
    return WarmupResult(**fields)


def _paths(value: Union[PathLike, Iterable[PathLike]], what: str) -> List[str]:
    if isinstance(value, (str, os.PathLike)):
        return [os.fspath(value)]
    if isinstance(value, Mapping):
        raise TypeError(f"{what}: a dict given; warmup needs spec files' paths (as robodiff warmup --spec)")
    paths = []
    for item in value:
        if not isinstance(item, (str, os.PathLike)):
            raise TypeError(f"{what}: {type(item).__name__} given; a path (str or os.PathLike) is needed")
        paths.append(os.fspath(item))
    return paths


def warmup(urdf: Union[PathLike, Iterable[PathLike]], specs: Union[PathLike, Iterable[PathLike]], *,
           cache_dir: Optional[PathLike] = None, floating_base: bool = False,
           progress: Optional[Callable[[WarmupResult], Any]] = None,
           jobs: Optional[int] = None) -> WarmupSummary:
    """Builds every spec for every robot into the cache; returns a WarmupSummary.

    urdf: a URDF file's path, or several; specs: spec files' paths (docs/function-language.md;
    examples/specs/), one or several. cache_dir: None is the default cache
    (``$ROBODIFF_CACHE_DIR``, ...). floating_base adds a free-flyer root joint to every robot.
    progress: called with each pair's WarmupResult as it finishes (once per pair, from a
    thread of the pool, holding the GIL); an exception it raises is raised by warmup once
    every build finished. jobs: worker processes building at once (None: the cores, at most 2).

    Raises robodiff.Error: INVALID_ARGUMENT for a missing file or a spec that does not
    parse (before anything is built; the message names the file and the field),
    FAILED_PRECONDITION for an unusable cache directory or no ``robodiff-worker``. A
    robot or function that fails to build is a ``failed`` result, not an exception.
    """
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be callable or None; {type(progress).__name__} given")
    start = time.monotonic()
    relay = None if progress is None else (lambda fields: progress(_result(fields)))
    directory = None if cache_dir is None else os.fspath(cache_dir)
    results = _robodiff.warmup(_paths(urdf, "urdf"), _paths(specs, "specs"), directory, bool(floating_base),
                               jobs, relay)
    return WarmupSummary([_result(fields) for fields in results], time.monotonic() - start)
