"""robodiff.check: a spec's function cross-checked three ways, as ``robodiff check`` does.

At seeded random states, each output of the compiled Function (what ``model.function(spec)``
gives: the cached library, or the server's) is compared with what shares none of its
code: the value with the double reference (robodiff.reference; a user function's with
the double evaluation of its expressions), Jacobians and Hessians with central finite
differences of it, and every output with the interpreter (the builder's graph run node
by node, built here from the same spec). The comparisons and tolerances are the CLI's
(core/functions spec_check.hpp).
"""

from __future__ import annotations

import json
import numbers
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, List, Mapping, Union

from . import _robodiff
from .reference import _parsed

if TYPE_CHECKING:
    from .client import Model

__all__ = ["check", "CheckResult", "CheckComparison"]


@dataclass(frozen=True)
class CheckComparison:
    """One output against one expectation, the worst over all states.

    against: ``"reference (core/dynamics)"``, ``"double evaluation"`` (a user function's
    value), ``"finite differences"``, ``"second finite differences"`` or ``"interpreted"``.
    Relative errors are elementwise, relative to max(|expected|, 1e-3 max|expected|, 1e-6);
    state, seed, row and col say where the worst relative error is.
    """

    output: str
    against: str
    worst_abs_error: float
    worst_rel_error: float
    state: int
    seed: int
    row: int
    col: int
    tolerance: float
    passed: bool


@dataclass(frozen=True)
class CheckResult:
    """What :func:`check` found: per output and expectation, a :class:`CheckComparison`.

    ``bool(result)`` and ``result.passed`` are True when every comparison passes;
    ``str(result)`` is a table like the CLI's.
    """

    function: str
    backend: str
    samples: int
    seed: int
    comparisons: List[CheckComparison]

    @property
    def passed(self) -> bool:
        """Every comparison within its tolerance."""
        return all(c.passed for c in self.comparisons)

    @property
    def failures(self) -> List[CheckComparison]:
        """The comparisons past their tolerance."""
        return [c for c in self.comparisons if not c.passed]

    def __bool__(self) -> bool:
        return self.passed

    def __str__(self) -> str:
        lines = [f"check {self.function}: {self.backend} backend, {self.samples} random states from seed {self.seed}"]
        width = max((len(c.output) for c in self.comparisons), default=0)
        for c in self.comparisons:
            lines.append(f"  {c.output:<{width}} vs {c.against:<26} worst abs {c.worst_abs_error:.2e} "
                         f"rel {c.worst_rel_error:.2e} (state {c.state}, [{c.row}, {c.col}]) "
                         f"tolerance {c.tolerance:.0e} {'PASS' if c.passed else 'FAIL'}")
        failed = len(self.failures)
        lines.append(f"{failed} of {len(self.comparisons)} comparisons FAIL" if failed
                     else f"all {len(self.comparisons)} comparisons pass")
        return "\n".join(lines)


def _spec_text(spec: Union[Mapping[str, Any], str, "os.PathLike[str]"]) -> str:
    """The spec's JSON text from a dict, a JSON string or a spec file's path."""
    if isinstance(spec, Mapping):
        return json.dumps(spec)
    if isinstance(spec, str) and spec.lstrip().startswith("{"):
        return spec
    if isinstance(spec, (str, os.PathLike)):
        with open(os.fspath(spec), encoding="utf-8") as file:
            return file.read()
    raise TypeError(f"spec: {type(spec).__name__} given; a dict, a JSON string or a path is needed")


def _whole(value: Any) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def check(model: "Model", spec: Union[Mapping[str, Any], str, "os.PathLike[str]"], samples: int = 3,
          seed: int = 1, backend: str = "generated") -> CheckResult:
    """Cross-checks a spec's function on ``model`` at ``samples`` random states.

    spec: a dict, a JSON string or a spec file's path, as ``Model.function`` takes it.
    State i is drawn from seed ``seed + i`` (q within the joint limits, v and a in
    [-1, 1], tau in [-5, 5]), as ``robodiff check --seed`` draws it. backend:
    ``"generated"`` checks ``model.function(spec)`` (so it must be in the cache in local
    mode, or a server must build it) against the references and the interpreter;
    ``"interpreted"`` checks the interpreter alone (nothing compiled, no cache needed).
    Tolerances (relative): values 1e-10 (aba and minv 1e-9), Jacobians 1e-5, Hessians
    1e-4, generated code against the interpreter 1e-11 (aba and minv 1e-9); a user
    function's values 1e-9, derivatives 1e-4, Hessians 1e-3, backends 1e-9.
    Returns a :class:`CheckResult` (falsy when a comparison fails; nothing is raised for
    that). Raises robodiff.Error for a spec that does not build (INVALID_ARGUMENT) or a
    Function that cannot be had, ValueError for a bad samples or backend.
    """
    if backend not in ("generated", "interpreted"):
        raise ValueError(f"backend: {backend!r} given; 'generated' or 'interpreted' is needed")
    if not _whole(samples) or samples < 1:
        raise ValueError(f"samples: {samples!r} given; a whole number of 1 or more is needed")
    if not _whole(seed) or not 0 <= seed < 2**64:
        raise ValueError(f"seed: {seed!r} given; a whole number from 0 to 2**64 - 1 is needed")
    reference = _parsed(model)
    text = _spec_text(spec)
    function = model.function(spec) if backend == "generated" else None
    found = _robodiff.check_spec(reference, text, function, int(samples), int(seed))
    comparisons = [CheckComparison(**row) for row in found["comparisons"]]
    return CheckResult(found["function"], backend, samples, seed, comparisons)
