"""Dense evidence of an axis: how exactly the image's gradients are mirrored about it.

The sparse mirror pairs vote for an axis; :func:`axis_evidence` checks it over every pixel
of a band around it (in the spirit of Eq. 2.9, thesis Sec. 2.3.2) and finds how far along
the line the mirror symmetry reaches. Not in the thesis; why each rule exists is in
``docs/design/axes.md``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from torchsym.core.checks import check_in_range, check_int, check_positive
from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError
from torchsym.image.lines import clip_line_to_image

__all__ = ["EDGE_NOISE", "AxisEvidence", "axis_evidence", "gradient_noise", "mirror_correlation", "mirror_gradients"]


def mirror_correlation(gray: np.ndarray, line: np.ndarray, points: np.ndarray) -> float:
    """Normalised correlation of ``gray (H, W)`` with its reflection about ``line (3,)``.

    Taken over the bounding box of ``points (M, 2)`` (the axis's mirror pairs), where the
    reflected image is defined. 1 for an image that is exactly symmetric there; values
    <= 0 mean no photometric symmetry.
    """
    import cv2

    a, b, c = (float(v) for v in line)
    h, w = gray.shape
    m = np.array([[1 - 2 * a * a, -2 * a * b, -2 * a * c], [-2 * a * b, 1 - 2 * b * b, -2 * b * c]], dtype=np.float64)
    x0, y0 = np.floor(points.min(0)).astype(int)
    x1, y1 = np.ceil(points.max(0)).astype(int)
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w - 1), min(y1, h - 1)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return 0.0
    refl = cv2.warpAffine(gray, m, (w, h), flags=cv2.INTER_LINEAR, borderValue=np.nan)
    u = gray[y0 : y1 + 1, x0 : x1 + 1].astype(np.float64)
    v = refl[y0 : y1 + 1, x0 : x1 + 1].astype(np.float64)
    ok = np.isfinite(v)
    if ok.sum() < 16:
        return 0.0
    u, v = u[ok] - u[ok].mean(), v[ok] - v[ok].mean()
    den = math.sqrt(float((u * u).sum() * (v * v).sum()))
    return float((u * v).sum() / den) if den > 0 else 0.0


def mirror_gradients(gray: np.ndarray, sigma: float = 1.5) -> tuple[np.ndarray, np.ndarray]:
    """``(gx, gy)`` float32 gradients of ``gray (H, W)`` after Gaussian smoothing by ``sigma`` pixels.

    The input of :func:`axis_evidence` (Sobel derivatives of the smoothed image, OpenCV).
    """
    import cv2

    g = cv2.GaussianBlur(np.ascontiguousarray(gray, dtype=np.float32), (0, 0), float(sigma))
    return cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3)


# Gradients at most this many times the image's median gradient magnitude
# (:func:`gradient_noise`) never count as edges when a segment grows
# (``noise_level`` of :func:`axis_evidence`).
EDGE_NOISE = 3.0


def gradient_noise(gx: np.ndarray, gy: np.ndarray) -> float:
    """The median gradient magnitude of ``gx, gy (H, W)``: the level of the image's noise
    and smooth shading (most pixels lie off edges)."""
    gx, gy = np.asarray(gx), np.asarray(gy)
    if gx.shape != gy.shape:
        raise InputShapeError(f"gx, gy: expected two arrays of one shape, got {gx.shape} and {gy.shape}")
    return float(np.median(np.hypot(gx, gy))) if gx.size else 0.0


def _bilinear(img: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``img (H, W)`` float32 at float positions ``(x, y)`` by bilinear interpolation
    (OpenCV's ``remap``, weights in steps of 1/32 px), NaN where it reaches outside the image."""
    import cv2

    n = x.size
    if n == 0:
        return np.zeros(0, np.float32)
    cols = min(n, 4096)  # remap's maps are images: rows and columns below 32767
    rows = -(-n // cols)
    mx, my = (np.zeros(rows * cols, np.float32) for _ in range(2))
    mx[:n], my[:n] = x, y
    out = cv2.remap(np.asarray(img, np.float32), mx.reshape(rows, cols), my.reshape(rows, cols), cv2.INTER_LINEAR,
                    borderMode=cv2.BORDER_CONSTANT, borderValue=float("nan"))
    return out.reshape(-1)[:n]


@dataclasses.dataclass(frozen=True)
class AxisEvidence(Result):
    """Dense mirror-gradient evidence for one axis (:func:`axis_evidence`).

    Attributes:
        symmetry: ``sum 2 g(p) . R g(p') / sum (|g(p)|^2 + |g(p')|^2)`` over the band of
            the supporting pairs' extent, in [-1, 1]: 1 when every gradient there equals
            the reflection of the gradient at its mirror point (direction and size), about
            0 for unrelated clutter.
        area: the part of that band where both ``p`` and ``p'`` lie in the image, as a
            fraction of the image's area.
        extent: ``(t_lo, t_hi)`` along the line (parameter of :func:`clip_line_to_image`),
            the support's extent grown where the mirror evidence continues.
    """

    symmetry: float
    area: float
    extent: tuple[float, float]

    @property
    def score(self) -> float:
        """The axis score of both methods' ``score="gradient"``, in [0, 1]: ``symmetry *
        sqrt(area)`` (negative symmetry counts as 0). Both factors are ratios, so the score
        does not grow with the image's size or edge density: a band of smoothed noise
        mirrors little of its gradient energy, a small symmetric detail covers little."""
        return max(self.symmetry, 0.0) * math.sqrt(min(max(self.area, 0.0), 1.0))


def _grow(
    t: np.ndarray, gain: np.ndarray, bin_length: float, strong: np.ndarray | None = None, max_gap: int | None = None
) -> float:
    """How far to grow past an end: ``t >= 0`` distances beyond it, ``gain`` per sample.

    Bins ``[k L, (k + 1) L)``; the run of bins from the end with the largest positive
    total gain, or 0 when every run loses. With ``strong`` (bool per sample) and
    ``max_gap``, the run crosses at most ``max_gap`` consecutive bins without a strong
    sample.
    """
    if t.size == 0:
        return 0.0
    nb = int(t.max() // bin_length) + 1
    bins = (t // bin_length).astype(np.int64)
    total = np.cumsum(np.bincount(bins, weights=gain, minlength=nb))
    if strong is not None and max_gap is not None:
        empty = np.bincount(bins, weights=strong.astype(np.float64), minlength=nb) == 0  # (nb,)
        width = min(max_gap, nb) + 1  # a window longer than the bins finds no gap
        gaps = np.flatnonzero(np.convolve(empty, np.ones(width), "valid") == width) if width <= nb else np.zeros(0, np.int64)
        if gaps.size:  # the first run of max_gap + 1 empty bins starts at gaps[0]
            total = total[: gaps[0]]
            if total.size == 0:
                return 0.0
    k = int(np.argmax(total))
    return (k + 1) * bin_length if total[k] > 0 else 0.0


def axis_evidence(
    gx: np.ndarray,
    gy: np.ndarray,
    line: Any,
    pairs: Any,
    *,
    min_half_width: float = 8.0,
    min_offset: float = 4.0,
    grow_threshold: float | None = 0.3,
    step: float = 2.0,
    bin_length: float = 4.0,
    max_gap: int | None = 2,
    noise_level: float = 0.0,
) -> AxisEvidence:
    """How exactly the image's gradients are mirrored about ``line``, and how far along it.

    With ``R`` the reflection about ``line`` and ``p'`` the mirror point of ``p``, a
    symmetric image has ``g(p) = R g(p')`` for its gradient ``g``. Over a band of points
    ``min_offset`` to ``w`` pixels from the line (``w``: the 90th percentile of the pairs'
    half chords, at least ``min_half_width``), sampled every ``step`` pixels along the
    pairs' extent ``[t0, t1]``, ``symmetry = sum 2 g(p) . R g(p') / sum (|g(p)|^2 +
    |g(p')|^2)`` (points whose mirror falls outside the image are left out).

    The extent grows past each end by the run of ``bin_length`` bins maximising
    ``sum 2 g . R g' - grow_threshold (|g|^2 + |g'|^2)`` over points whose gradient is
    above ``noise_level`` (the rest add nothing); the run crosses at most ``max_gap``
    bins without such a point. Why each rule exists, and the ones that were measured and
    removed: ``docs/design/axes.md``.

    Args:
        gx: ``(H, W)`` x-derivative (:func:`mirror_gradients`).
        gy: ``(H, W)`` y-derivative, the same shape.
        line: ``(3,)`` ``a x + b y + c = 0``; ``(a, b)`` is normalised here.
        pairs: ``(M, 4)`` supporting mirror pairs ``x1, y1, x2, y2``, ``M >= 1``, finite.
        min_half_width: the least band half-width, px (default 8).
        min_offset: band points nearer the line than this are left out, px (default 4).
        grow_threshold: local symmetry in [-1, 1] above which the extent grows; None: no
            growth (default 0.3).
        step: sampling step of the band, px (default 2).
        bin_length: bin length along the line, px (default 4).
        max_gap: the most consecutive empty bins the growth crosses; None: no limit
            (default 2).
        noise_level: gradient magnitude (units of ``gx``) at or below which a point never
            counts for the growth (default 0).

    Returns:
        :class:`AxisEvidence`.

    Raises:
        InputShapeError: ``gx``, ``gy``, ``line`` or ``pairs`` of the wrong shape.
        InputValueError: non-finite ``line`` or ``pairs``, a zero normal, no pairs, or a
            setting out of range.
    """

    gx, gy, ln, norm, pairs = _check_inputs(gx, gy, line, pairs)
    for name, val in (("min_half_width", min_half_width), ("min_offset", min_offset)):
        check_positive(val, name, allow_zero=True)
    step, bin_length = check_positive(step, "step"), check_positive(bin_length, "bin_length")
    if max_gap is not None:
        max_gap = check_int(max_gap, "max_gap", minimum=0)
    noise_level = check_positive(noise_level, "noise_level", allow_zero=True)
    if grow_threshold is not None:
        grow_threshold = check_in_range(grow_threshold, "grow_threshold", -1.0, 1.0)
    h, w = gx.shape
    a, b, c = ln / norm
    d = np.array([-b, a])
    foot = np.array([-c * a, -c * b])
    t_all = (pairs.reshape(-1, 2) - foot) @ d  # (2M,) the pairs' points along the line
    t0, t1 = float(t_all.min()), float(t_all.max())
    half = 0.5 * np.hypot(pairs[:, 2] - pairs[:, 0], pairs[:, 3] - pairs[:, 1])
    width = max(float(np.percentile(half, 90)), float(min_half_width), min_offset + step)
    full = clip_line_to_image(np.array([a, b, c]), -1e9, 1e9, w, h)
    if full is None:
        return AxisEvidence(0.0, 0.0, (t0, t1))
    f0, f1 = sorted(((np.array(full[:2]) - foot) @ d, (np.array(full[2:]) - foot) @ d))
    tt, part, dot2, g2, r2, ok = _mirrored_band(gx, gy, (a, b), foot, (t0, t1), (f0, f1), width, min_offset, step)
    energy = g2 + r2
    inside = ok & (part == 0)
    area = float(inside.sum()) * step * step / (h * w)
    symmetry = float(dot2[inside].sum() / max(float(energy[inside].sum()), 1e-12))
    lo, hi = t0, t1
    if grow_threshold is not None and inside.any():
        strong = np.maximum(g2, r2) > noise_level * noise_level
        gain = np.where(strong, dot2 - grow_threshold * energy, 0.0)
        up, down = part == 1, part == 2
        hi = t1 + _grow(tt[up] - t1, gain[up], bin_length, strong[up], max_gap)
        lo = t0 - _grow(t0 - tt[down], gain[down], bin_length, strong[down], max_gap)
    return AxisEvidence(symmetry, area, (float(lo), float(hi)))


def _check_inputs(gx: Any, gy: Any, line: Any, pairs: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, np.ndarray]:
    """The arrays of :func:`axis_evidence` checked: ``gx, gy, line (3,), |(a, b)|, pairs (M, 4)``."""
    gx, gy = np.asarray(gx), np.asarray(gy)
    if gx.ndim != 2 or gy.shape != gx.shape:
        raise InputShapeError(f"gx, gy: expected two (H, W) arrays of one shape, got {gx.shape} and {gy.shape}")
    ln = np.asarray(line, dtype=np.float64).reshape(-1)
    if ln.shape != (3,):
        raise InputShapeError(f"line: expected (3,) a, b, c, got shape {np.asarray(line).shape}")
    norm = float(np.hypot(ln[0], ln[1])) if np.isfinite(ln).all() else float("nan")
    if not norm > 0:
        raise InputValueError(f"line: expected finite (a, b, c) with (a, b) != 0, got {ln.tolist()}")
    pairs = np.asarray(pairs, dtype=np.float64)
    if pairs.ndim != 2 or pairs.shape[1] != 4:
        raise InputShapeError(f"pairs: expected (M, 4) x1, y1, x2, y2, got shape {pairs.shape}")
    if pairs.shape[0] == 0 or not np.isfinite(pairs).all():
        raise InputValueError(f"pairs: expected at least one finite pair, got {pairs.shape[0]} (finite: {np.isfinite(pairs).all()})")
    return gx, gy, ln, norm, pairs


def _mirrored_band(
    gx: np.ndarray, gy: np.ndarray, normal: tuple[float, float], foot: np.ndarray, support: tuple[float, float],
    full: tuple[float, float], width: float, min_offset: float, step: float,
) -> tuple[np.ndarray, ...]:
    """Gradients sampled on the band around the line and at their mirror points.

    Rows every ``step`` along the line: inside the support ``[t0, t1]`` (part 0), beyond
    ``t1`` (1) and before ``t0`` (2) up to the image's ``full`` extent; offsets
    ``min_offset .. width`` on both sides. Returns per sample ``t``, ``part``,
    ``2 g . R g'``, ``|g|^2``, ``|R g'|^2`` and ``ok`` (both points in the image).
    """
    a, b = normal
    n, d = np.array([a, b]), np.array([-b, a])
    (t0, t1), (f0, f1) = support, full
    t_in = t0 + step * np.arange(int((t1 - t0) // step) + 1)
    t_up = t1 + step * (0.5 + np.arange(max(math.ceil((f1 - t1) / step), 0)))
    t_down = t0 - step * (0.5 + np.arange(max(math.ceil((t0 - f0) / step), 0)))
    ts = np.concatenate([t_in, t_up, t_down])
    part = np.concatenate([np.zeros(t_in.size), np.ones(t_up.size), np.full(t_down.size, 2)]).astype(np.int8)
    ss = np.arange(min_offset, width + 1e-9, step)
    ss = np.concatenate([-ss[::-1], ss])
    p = (foot + ts[:, None, None] * d + ss[None, :, None] * n).reshape(-1, 2)  # (T * S, 2)
    tt = np.repeat(ts, ss.size)
    part = np.repeat(part, ss.size)
    gpx, gpy = _bilinear(gx, p[:, 0], p[:, 1]), _bilinear(gy, p[:, 0], p[:, 1])
    # the offsets are symmetric (ss[j] = -ss[S - 1 - j]), so the mirror point of each
    # sample is the sample in the mirrored column: its gradient is already sampled
    qx, qy = (v.reshape(ts.size, ss.size)[:, ::-1].reshape(-1) for v in (gpx, gpy))
    dn = qx * a + qy * b
    rx, ry = qx - 2 * dn * a, qy - 2 * dn * b  # R g(p')
    ok = np.isfinite(gpx) & np.isfinite(rx)
    gpx, gpy, rx, ry = (np.where(ok, v, 0.0) for v in (gpx, gpy, rx, ry))
    return tt, part, 2 * (gpx * rx + gpy * ry), gpx * gpx + gpy * gpy, rx * rx + ry * ry, ok
