"""Pairs of reflection-symmetric boundary samples (thesis Sec. 2.3.2, Eq. 2.9).

For a chord at angle ``beta`` and tangent angles ``alpha`` (mod pi), the tangent reflected
through the chord's bisector is ``2 beta - alpha``, so both terms of Eq. 2.9 equal
``mean_t |2 beta - alpha_i(t) - alpha_j(t')|`` (mod pi), with ``t'`` running along ``b_j``
in the matching direction (both directions are tried).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from torchsym.image.boundary import BoundarySegments

__all__ = ["BoundaryPairs", "symmetric_boundary_pairs", "wrap_half_turn"]


def wrap_half_turn(x: np.ndarray) -> np.ndarray:
    """Angles mod pi into [-pi/2, pi/2], keeping float32 input in float32.

    ``x - pi * rint(x / pi)``: the magnitudes of ``mod(x + pi/2, pi) - pi/2`` (only
    ``+-pi/2`` may come out with the other sign; callers take ``abs``).
    """
    pi = x.dtype.type(np.pi) if isinstance(x, np.ndarray) else np.pi
    return x - pi * np.rint(x / pi)


def symmetric_boundary_pairs(
    segments: BoundarySegments,
    *,
    theta: float = 5.0,
    min_distance: float = 24.0,
    max_shift: float = 3.0,
    collinear_angle: float = 15.0,
    chunk: int = 256,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pairs of reflection-symmetric boundary samples (Eq. 2.9 below ``theta`` degrees).

    Boundary samples lie every ``stride`` pixels, so the exact mirror of ``p_i`` usually
    falls between two samples of the other curve, and the chord angle ``beta`` enters
    Eq. 2.9 twice. Each candidate's second point is therefore slid along its curve's
    tangent by at most ``max_shift`` pixels to where the chord is perpendicular to the
    axis that the two centre tangents imply (``2 beta = alpha_i + alpha_j`` mod pi),
    and Eq. 2.9 is evaluated for that pixel pair.

    Args:
        segments: boundary samples and their segment orientations.
        theta: threshold in degrees on the sum of the two integrals of Eq. 2.9.
        min_distance: the least chord length in pixels.
        max_shift: the most a second point moves along its curve (the sample stride).
        collinear_angle: pairs whose chord is within this angle (degrees) of both centre
            tangents are skipped.
        chunk: rows screened at once.

    Returns:
        ``index (M, 2)`` int64 sample indices, ``second (M, 2)`` the refined second
        points, ``cost (M,)`` the Eq. 2.9 value in radians, ``sums (M, S)`` the matched
        tangent sums ``alpha_i(t) + alpha_j(t')``.
    """
    p, a = segments.points, segments.angles  # (N, 2), (N, S)
    n, s = a.shape
    th = math.radians(theta)
    a0 = a[:, s // 2]
    sin_col = math.sin(math.radians(collinear_angle))
    # screening without atan2 or mod: |wrap_pi(2 beta - a_i - a_j)| < slack  <=>
    # cos(4 beta - 2 (a_i + a_j)) > cos(2 slack), with 4 beta from the chord by double-angle formulas
    pf = p.astype(np.float32)
    c2, s2 = np.cos(2 * a0).astype(np.float32), np.sin(2 * a0).astype(np.float32)  # (N,)
    ct, st = np.cos(a0).astype(np.float32), np.sin(a0).astype(np.float32)
    found_i, found_j = [], []
    for i0 in range(0, n, chunk):
        i1 = min(n, i0 + chunk)
        cols = slice(i0 + 1, n)
        dx = pf[None, cols, 0] - pf[i0:i1, None, 0]  # (c, N - i0 - 1)
        dy = pf[None, cols, 1] - pf[i0:i1, None, 1]
        len2 = dx * dx + dy * dy
        ok = len2 >= min_distance**2
        ok &= np.triu(np.ones((i1 - i0, n - i0 - 1), dtype=bool))  # j > i
        inv = 1.0 / np.maximum(len2, 1e-12)
        c2b, s2b = (dx * dx - dy * dy) * inv, 2 * dx * dy * inv  # cos, sin of 2 beta
        c4b, s4b = c2b * c2b - s2b * s2b, 2 * c2b * s2b  # of 4 beta
        cs = c2[i0:i1, None] * c2[None, cols] - s2[i0:i1, None] * s2[None, cols]  # cos 2(a_i + a_j)
        ss = s2[i0:i1, None] * c2[None, cols] + c2[i0:i1, None] * s2[None, cols]
        slack = np.minimum(th + 2 * max_shift * np.sqrt(inv), np.pi / 2)  # atan(x) <= x: never too strict
        ok &= c4b * cs + s4b * ss > np.cos(2 * slack)
        lim = sin_col * np.sqrt(len2)
        ok &= (np.abs(dx * st[i0:i1, None] - dy * ct[i0:i1, None]) > lim) | (
            np.abs(dx * st[None, cols] - dy * ct[None, cols]) > lim
        )
        ii, jj = np.nonzero(ok)
        found_i.append(ii + i0)
        found_j.append(jj + i0 + 1)
    ii = np.concatenate(found_i) if found_i else np.zeros(0, dtype=np.int64)
    jj = np.concatenate(found_j) if found_j else np.zeros(0, dtype=np.int64)
    empty = (np.zeros((0, 2), dtype=np.int64), np.zeros((0, 2)), np.zeros(0), np.zeros((0, s)))
    if ii.size == 0:
        return empty
    d = p[jj] - p[ii]  # (M, 2)
    beta0 = np.arctan2(d[:, 1], d[:, 0])
    # the chord direction the centre tangents ask for, nearest the current chord
    half = 0.5 * (a0[ii] + a0[jj])
    target = half + np.pi / 2 * np.round((beta0 - half) / (np.pi / 2))
    u = np.stack([np.cos(target), np.sin(target)], 1)
    tau = np.stack([np.cos(a0[jj]), np.sin(a0[jj])], 1)
    cross_du = d[:, 0] * u[:, 1] - d[:, 1] * u[:, 0]
    cross_tu = tau[:, 0] * u[:, 1] - tau[:, 1] * u[:, 0]
    shift = -cross_du / np.where(np.abs(cross_tu) < 1e-9, np.inf, cross_tu)
    movable = np.abs(shift) <= max_shift
    second = p[jj] + np.where(movable, shift, 0.0)[:, None] * tau
    d = second - p[ii]
    length = np.hypot(d[:, 0], d[:, 1])
    beta = np.arctan2(d[:, 1], d[:, 0])[:, None]  # (M, 1)
    fwd = a[ii] + a[jj]  # (M, S)
    rev = a[ii] + a[jj][:, ::-1]
    e_f = 2 * np.abs(wrap_half_turn(2 * beta - fwd)).mean(1)  # both terms of Eq. 2.9 are equal
    e_r = 2 * np.abs(wrap_half_turn(2 * beta - rev)).mean(1)
    use_rev = e_r < e_f
    cost = np.where(use_rev, e_r, e_f)
    sums = np.where(use_rev[:, None], rev, fwd)
    keep = (cost < th) & (length >= min_distance)
    return np.stack([ii[keep], jj[keep]], 1).astype(np.int64), second[keep], cost[keep], sums[keep]


@dataclasses.dataclass(frozen=True)
class BoundaryPairs:
    """The symmetric boundary pairs of an image.

    Attributes:
        pairs: ``(M, 4)`` float64 ``x1, y1, x2, y2``: a boundary sample and the refined
            point of its partner.
        sums: ``(M, S)`` the matched tangent sums ``alpha_i(t) + alpha_j(t')``.
        mid: ``(M, 2)`` chord midpoints.
        beta: ``(M,)`` chord angles, radians.
    """

    pairs: np.ndarray
    sums: np.ndarray
    mid: np.ndarray
    beta: np.ndarray

    @classmethod
    def of(cls, segments: BoundarySegments, *, theta: float, min_distance: float, max_shift: float) -> BoundaryPairs:
        """The pairs of :func:`symmetric_boundary_pairs` on ``segments``."""
        index, second, _cost, sums = symmetric_boundary_pairs(segments, theta=theta, min_distance=min_distance,
                                                              max_shift=max_shift)
        pairs = np.concatenate([segments.points[index[:, 0]], second], 1)  # (M, 4)
        chord = pairs[:, 2:] - pairs[:, :2]
        return cls(pairs, sums, 0.5 * (pairs[:, :2] + pairs[:, 2:]), np.arctan2(chord[:, 1], chord[:, 0]))

    def __len__(self) -> int:
        return int(self.pairs.shape[0])
