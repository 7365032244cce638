"""When an iteration has converged: what a linearly converging sequence still has to go."""

from __future__ import annotations

from typing import Any

__all__ = ["remaining_factor"]


def remaining_factor(step: Any, previous: Any | None, *, max_ratio: float = 0.95) -> float:
    """``1 / (1 - r)``: how far a linearly converging sequence still goes, in units of its
    last ``step`` (a vector, torch or NumPy), with ``r`` the ratio of ``step`` to the
    ``previous`` one projected on it, clipped to ``[0, max_ratio]``; 1 without a previous
    step. Nearest-neighbour steps creep by near-constant amounts (``r`` near 1), so a step
    below a tolerance does not mean the iteration has arrived."""
    if previous is None:
        return 1.0
    denom = float(previous @ previous)
    r = float(step @ previous) / denom if denom > 0 else 0.0
    return 1.0 / (1.0 - min(max(r, 0.0), max_ratio))
