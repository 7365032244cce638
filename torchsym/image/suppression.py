"""Duplicate suppression: one axis kept per object when several candidates find it."""

from __future__ import annotations

import math

import numpy as np

from torchsym.core.checks import check_in_range, check_positive
from torchsym.errors import InputShapeError

__all__ = ["suppress_duplicates"]


def suppress_duplicates(
    lines: list[np.ndarray],
    extents: list[tuple[float, float]],
    scores: list[float],
    *,
    angle: float = 10.0,
    distance: float = 10.0,
) -> list[int]:
    """Indices of the axes kept after dropping near-duplicates of better-scored ones.

    Axis ``j`` duplicates a kept axis ``i`` when the lines are within ``angle`` degrees,
    the centre of ``j``'s segment is within ``distance`` pixels of ``i``'s line, and,
    projected onto ``i``'s line, the two segments overlap by at least half the shorter
    one: the same object found twice, while two objects on one line are both kept.

    Args:
        lines: ``(3,)`` lines with unit normals.
        extents: ``(t_lo, t_hi)`` of each segment along its line (as in
            :func:`clip_line_to_image`).
        scores: the axes' scores; higher wins.
        angle: angle tolerance, degrees.
        distance: distance tolerance, pixels.

    Returns:
        Kept indices, best score first.
    """
    if not len(lines) == len(extents) == len(scores):
        raise InputShapeError(f"lines, extents, scores: expected one of each per axis, got {len(lines)}, {len(extents)}, {len(scores)}")
    angle = check_in_range(angle, "angle", 0.0, 90.0)
    distance = check_positive(distance, "distance")
    cos_tol = math.cos(math.radians(angle))
    geo = []
    for k, (ln, ext) in enumerate(zip(lines, extents)):
        ln = np.asarray(ln, dtype=np.float64).reshape(-1)
        if ln.shape != (3,) or len(ext) != 2:
            raise InputShapeError(f"lines[{k}], extents[{k}]: expected (a, b, c) and (t_lo, t_hi), got {ln.shape} and {len(ext)} values")
        a, b, c = ln
        d = np.array([-b, a])
        foot = np.array([-c * a, -c * b])
        ends = foot + np.outer(sorted(float(t) for t in ext), d)  # (2, 2)
        geo.append((np.array([a, b]), c, d, ends))
    keep: list[int] = []
    for j in sorted(range(len(lines)), key=lambda k: -scores[k]):
        nj, _, _, ej = geo[j]
        duplicate = False
        for i in keep:
            ni, ci_off, di, ei = geo[i]
            if abs(float(nj @ ni)) <= cos_tol or abs(float(ni @ ej.mean(0)) + ci_off) >= distance:
                continue
            si, sj = np.sort(ei @ di), np.sort(ej @ di)  # both segments along i's line
            overlap = min(si[1], sj[1]) - max(si[0], sj[0])
            if overlap >= 0.5 * min(si[1] - si[0], sj[1] - sj[0]):
                duplicate = True
                break
        if not duplicate:
            keep.append(j)
    return keep
