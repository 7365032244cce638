"""Candidate axes from a set of mirror pairs, by greedy inlier counting.

The initialisation of thesis Sec. 2.2.3 taken to the end: a public building block used by
both axis detectors for their mirrored-SIFT pairs.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from torchsym.core.checks import check_int, check_positive
from torchsym.errors import InputShapeError, InputValueError
from torchsym.image.lines import fit_axis

__all__ = ["GATHER_ANGLE", "GATHER_DISTANCE", "RUN_GAP", "mirror_pair_candidates", "pixel_inliers", "support_runs"]

GATHER_ANGLE = 3.0  # deg: a pair supports an axis when its chord is this close to the normal
GATHER_DISTANCE = 0.01  # and its midpoint this close to the line, x the image's longer side
RUN_GAP = 0.1  # support is split where midpoints are farther apart along the line, x the longer side


def check_pairs(pairs: Any) -> np.ndarray:
    """``pairs`` as a finite ``(P, 4)`` float64 array; typed errors naming ``pairs``."""
    arr = np.asarray(pairs, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise InputShapeError(f"pairs: expected (P, 4) x1, y1, x2, y2, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputValueError("pairs: expected finite coordinates, got NaN or infinity")
    return arr


def pixel_inliers(pairs: np.ndarray, lines: np.ndarray, angle_tol: float, tol: float) -> np.ndarray:
    """``(P, K)`` bool: pair ``i`` of ``pairs (P, 4)`` supports line ``k`` of ``lines (K, 3)``
    (chord within ``angle_tol`` degrees of the normal, midpoint within ``tol`` px of the line)."""
    chord = pairs[:, 2:] - pairs[:, :2]
    normal = chord / np.maximum(np.linalg.norm(chord, axis=1, keepdims=True), 1e-12)
    mid = 0.5 * (pairs[:, :2] + pairs[:, 2:])
    return (np.abs(normal @ lines[:, :2].T) > math.cos(math.radians(angle_tol))) & (
        np.abs(mid @ lines[:, :2].T + lines[None, :, 2]) < tol
    )


def support_runs(line: Any, pairs: np.ndarray, members: np.ndarray, gap: float) -> list[np.ndarray]:
    """Split an axis's supporting pairs into runs along the line.

    Pairs that vote for one line may belong to several objects on it (or to clutter far
    along it); sorted by the position of their midpoints on the line, they are cut
    wherever two consecutive midpoints are more than ``gap`` pixels apart.

    Args:
        line: ``(3,)`` ``a x + b y + c = 0`` with unit ``(a, b)``.
        pairs: ``(P, 4)`` mirror pairs ``x1, y1, x2, y2``.
        members: ``(M,)`` indices into ``pairs`` of the supporting pairs.
        gap: the largest gap in pixels within one run.

    Returns:
        Index arrays (into ``pairs``), one per run, in order along the line.
    """
    pairs = np.asarray(pairs, dtype=np.float64)
    if pairs.ndim != 2 or pairs.shape[1] != 4:
        raise InputShapeError(f"pairs: expected (P, 4) x1, y1, x2, y2, got shape {pairs.shape}")
    ln = np.asarray(line, dtype=np.float64).reshape(-1)
    if ln.shape != (3,):
        raise InputShapeError(f"line: expected (3,) a, b, c, got shape {np.asarray(line).shape}")
    gap = check_positive(gap, "gap")
    members = np.asarray(members, dtype=np.int64).reshape(-1)
    if members.size and (members.min() < 0 or members.max() >= pairs.shape[0]):
        raise InputValueError(f"members: expected indices in [0, {pairs.shape[0] - 1}], got {members.min()}..{members.max()}")
    if members.size == 0:
        return []
    a, b = float(ln[0]), float(ln[1])
    mid = 0.5 * (pairs[members, :2] + pairs[members, 2:])  # (M, 2)
    t = mid @ np.array([-b, a])
    order = np.argsort(t, kind="stable")
    cuts = np.flatnonzero(np.diff(t[order]) > gap) + 1
    return [members[run] for run in np.split(order, cuts)]


def mirror_pair_candidates(
    pairs: np.ndarray,
    height: int,
    width: int,
    *,
    angle_tol: float = GATHER_ANGLE,
    distance_tol: float = GATHER_DISTANCE,
    min_support: int = 4,
    max_candidates: int = 30,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Candidate axes of a set of mirror pairs, by greedy inlier counting.

    Every pair's own axis is a candidate; the candidate with the most inlier pairs is
    fitted to them (:func:`~torchsym.image.lines.fit_axis`), its inliers are removed, and
    so on while a candidate keeps at least ``min_support`` inliers. A pair is an inlier
    when its chord is within ``angle_tol`` degrees of the axis normal and its midpoint
    within ``distance_tol * max(height, width)`` px of the line (a tolerance in pixels,
    not the thesis's ratio ``eps_d``: see ``docs/design/axes.md``). No pair is forced
    onto an axis, so a small object with a handful of pairs still yields a candidate.

    Args:
        pairs: ``(P, 4)`` mirror pairs ``x1, y1, x2, y2`` in pixels.
        height: image height (the distance tolerance's scale).
        width: image width.
        angle_tol: angle tolerance, degrees.
        distance_tol: distance tolerance as a fraction of the image's longer side.
        min_support: the least inliers of a candidate.
        max_candidates: the most candidates (greedy rounds).

    Returns:
        ``(line (3,), members (M,))`` per candidate, most inliers first; ``members``
        index ``pairs``.
    """
    pairs = check_pairs(pairs)
    height, width = check_int(height, "height", minimum=1), check_int(width, "width", minimum=1)
    angle_tol = check_positive(angle_tol, "angle_tol")
    distance_tol = check_positive(distance_tol, "distance_tol")
    min_support = check_int(min_support, "min_support", minimum=1)
    max_candidates = check_int(max_candidates, "max_candidates", minimum=1)
    if pairs.shape[0] < min_support:
        return []
    chord = pairs[:, 2:] - pairs[:, :2]
    normal = chord / np.maximum(np.linalg.norm(chord, axis=1, keepdims=True), 1e-12)  # (P, 2)
    mid = 0.5 * (pairs[:, :2] + pairs[:, 2:])
    tol = distance_tol * max(height, width)
    inl = pixel_inliers(pairs, np.concatenate([normal, -(normal * mid).sum(1, keepdims=True)], 1), angle_tol, tol)
    centre = np.array([(width - 1) / 2, (height - 1) / 2])
    scale = max(height, width) / 2.0
    free = np.ones(pairs.shape[0], dtype=bool)
    counts = inl.sum(0, dtype=np.int64)  # (P,) free inliers of each pair's axis, kept up to date
    out = []
    while len(out) < max_candidates:
        ranked = np.where(free, counts, -1)
        j = int(ranked.argmax())
        if ranked[j] < min_support:
            break
        first = np.flatnonzero(inl[:, j] & free)
        line = fit_axis(pairs[first], centre, scale)
        members = np.union1d(np.flatnonzero(pixel_inliers(pairs, line[None], angle_tol, tol)[:, 0] & free), first)
        taken = np.union1d(members, [j])
        taken = taken[free[taken]]
        counts -= inl[taken].sum(0, dtype=np.int64)
        free[taken] = False
        out.append((line, members))
    return out
