"""Lines in an image: axes of mirror pairs, their fit, and their segments in the image.

A line is ``a x + b y + c = 0`` with a unit normal ``(a, b)`` (the thesis's triplet,
Sec. 2.2.2). Pixel coordinates have their origin at the top-left pixel, x to the right,
y down. Along a line, points are ``foot + t * direction`` with ``foot = -c (a, b)`` and
``direction = (-b, a)``; ``t`` is the parameter of an extent ``(t_lo, t_hi)``.
"""

from __future__ import annotations

import math

import numpy as np
import torch

__all__ = ["axis_segment", "clip_line_to_image", "fit_axis", "pair_axes", "pair_rows"]


def pair_axes(first: torch.Tensor, second: torch.Tensor) -> torch.Tensor:
    """Axis of each mirror pair: the perpendicular bisector of ``first -> second``.

    Args:
        first: ``(..., 2)`` points.
        second: ``(..., 2)`` their mirror points.

    Returns:
        ``(..., 3)`` lines ``(a, b, c)`` with ``(a, b)`` unit (along the chord).
    """
    chord = first - second  # (..., 2)
    n = chord / chord.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    mid = 0.5 * (first + second)
    return torch.cat([n, -(n * mid).sum(-1, keepdim=True)], dim=-1)


def pair_rows(left: torch.Tensor, right: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Rows ``X`` and ``Y`` of Eq. 2.6 for mirror pairs ``left, right (P, 2)``.

    For an axis ``u = (a, b, c)``, ``X u`` is each midpoint's offset from the line (Eq. 2.3)
    and ``Y u`` the chord's component along it (Eq. 2.2). Returns two ``(P, 3)`` tensors.
    """
    mid = 0.5 * (left + right)  # (P, 2)
    x = torch.cat([mid, torch.ones_like(mid[:, :1])], 1)  # (P, 3)
    y = torch.stack([right[:, 1] - left[:, 1], left[:, 0] - right[:, 0], torch.zeros_like(mid[:, 0])], 1)  # (P, 3)
    return x, y


def fit_axis(pairs: np.ndarray, centre: np.ndarray, scale: float) -> np.ndarray:
    """The axis best fitting mirror pairs: the update step of Algorithm 1 (Eq. 2.7-2.8).

    The smallest eigenvector of ``B = X^T X + Y^T Y`` in coordinates centred on ``centre
    (2,)`` and divided by ``scale``; returned as a ``(3,)`` line in pixels, unit ``(a, b)``.

    Args:
        pairs: ``(M, 4)`` mirror pairs ``x1, y1, x2, y2`` in pixels, ``M >= 2``.
        centre: ``(2,)`` the image centre.
        scale: half the image's longer side.
    """
    left = torch.from_numpy((pairs[:, :2] - centre) / scale)
    right = torch.from_numpy((pairs[:, 2:] - centre) / scale)
    x, y = pair_rows(left, right)
    _, vecs = torch.linalg.eigh(x.T @ x + y.T @ y)
    a, b, c = (float(v) for v in vecs[:, 0])
    line = np.array([a, b, c * scale - a * centre[0] - b * centre[1]])
    return line / max(math.hypot(line[0], line[1]), 1e-12)


def clip_line_to_image(line, t_min: float, t_max: float, width: int, height: int) -> list[float] | None:
    """Clip the segment ``foot + t dir, t in [t_min, t_max]`` of ``line (3,)`` to the image box.

    Returns ``[x1, y1, x2, y2]`` as floats, or None when nothing is inside.
    """
    a, b, c = (float(v) for v in line)
    foot = np.array([-c * a, -c * b])
    d = np.array([-b, a])
    lo, hi = t_min, t_max
    for k, (low, high) in enumerate(((0.0, width - 1.0), (0.0, height - 1.0))):
        if abs(d[k]) < 1e-12:
            if not (low <= foot[k] <= high):
                return None
            continue
        t0, t1 = sorted(((low - foot[k]) / d[k], (high - foot[k]) / d[k]))
        lo, hi = max(lo, t0), min(hi, t1)
    if hi <= lo:
        return None
    p, q = foot + lo * d, foot + hi * d
    return [float(p[0]), float(p[1]), float(q[0]), float(q[1])]


def axis_segment(line, points: torch.Tensor, width: int, height: int, *, trim: float = 0.0) -> list[float] | None:
    """Segment of ``line (3,)`` spanning the projections of ``points (M, 2)``, clipped to the image.

    The extent runs from the ``trim`` to the ``1 - trim`` quantile of the projections (no
    points: the whole line). Returns ``[x1, y1, x2, y2]`` or None.
    """
    a, b, c = (float(v) for v in line)
    foot = torch.tensor([-c * a, -c * b], dtype=torch.float64)
    d = torch.tensor([-b, a], dtype=torch.float64)
    t = (points.double() - foot) @ d  # (M,)
    if t.numel() == 0:
        return clip_line_to_image(line, -1e9, 1e9, width, height)
    lo, hi = torch.quantile(t, torch.tensor([trim, 1 - trim], dtype=t.dtype))
    return clip_line_to_image(line, float(lo), float(hi), width, height)
