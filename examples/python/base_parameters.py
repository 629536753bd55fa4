"""Base inertial parameters with numpy: which columns of the stacked regressor W are
independent, and how the others fold into them.

QR with column pivoting, written out (numpy has none): the column left with the largest
norm after removing the chosen ones is chosen next, until what is left is numerically
zero. With W_b the chosen columns and W_d the rest, W_d = W_b K exactly, so

    W pi = W_b (pi_b + K pi_d) = W_b beta,

and beta (the base parameters) is what torques determine; `robodiff identify` reports the
same kind of combinations (docs/jobs.md, "Identification").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

NAMES = ["m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz"]


@dataclass
class BaseParameters:
    """independent: the chosen columns (ascending), dependent: the others, fold: K."""

    independent: np.ndarray
    dependent: np.ndarray
    fold: np.ndarray

    def of(self, standard: np.ndarray) -> np.ndarray:
        """beta = pi_b + K pi_d for standard parameters pi."""
        return standard[self.independent] + self.fold @ standard[self.dependent]

    def names(self, joint_names: Sequence[str]) -> list[str]:
        """'joint.param' of each base parameter's own column, '+' when others fold into it."""
        labels = []
        for row, column in enumerate(self.independent):
            folded = np.any(np.abs(self.fold[row]) > 1e-9)
            label = f"{joint_names[column // 10]}.{NAMES[column % 10]}"
            labels.append(label + (" +" if folded else ""))
        return labels


def pivoted_columns(w: np.ndarray, tolerance: float = 1e-8) -> np.ndarray:
    """Indices of a maximal set of independent columns, by greedy column pivoting."""
    residual = np.array(w, dtype=float)
    scale = max(np.linalg.norm(residual, axis=0).max(), 1.0)
    chosen: list[int] = []
    while len(chosen) < min(residual.shape):
        norms = np.linalg.norm(residual, axis=0)
        norms[chosen] = 0.0
        best = int(np.argmax(norms))
        if norms[best] <= tolerance * scale:
            break
        direction = residual[:, best] / norms[best]
        residual -= np.outer(direction, direction @ residual)  # remove it from every column
        chosen.append(best)
    return np.array(sorted(chosen), dtype=int)


def base_parameters(w: np.ndarray) -> BaseParameters:
    """The base parameters of a stacked regressor w (rows: torques, cols: 10 per joint)."""
    independent = pivoted_columns(w)
    dependent = np.setdiff1d(np.arange(w.shape[1]), independent)
    fold, *_ = np.linalg.lstsq(w[:, independent], w[:, dependent], rcond=None)
    fold[np.abs(fold) < 1e-12] = 0.0
    return BaseParameters(independent, dependent, fold)
