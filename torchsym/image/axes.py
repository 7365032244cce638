"""Symmetry axes in an image: lines from mirror pairs, segments, and the result type.

Shared by :mod:`torchsym.image.ksymmetry` (thesis Sec. 2.2) and
:mod:`torchsym.image.boundary_cliques` (Sec. 2.3). A line is ``a x + b y + c = 0`` with a
unit normal ``(a, b)`` (the thesis's triplet, Sec. 2.2.2); pixel coordinates have their
origin at the top-left pixel, x to the right, y down.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError

__all__ = [
    "AxisEvidence",
    "ReflectionAxesBatch",
    "ReflectionAxesResult",
    "axis_evidence",
    "axis_segment",
    "clip_line_to_image",
    "draw_axes",
    "gradient_noise",
    "mirror_gradients",
    "pair_axes",
    "support_runs",
    "suppress_duplicates",
]


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


def clip_line_to_image(line: torch.Tensor, t_min: float, t_max: float, width: int, height: int):
    """Clip the segment ``foot + t dir, t in [t_min, t_max]`` of ``line (3,)`` to the image box.

    Returns ``(x1, y1, x2, y2)`` as a list of floats, or None when nothing is inside.
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


def axis_segment(line: torch.Tensor, points: torch.Tensor, width: int, height: int, *, trim: float = 0.0):
    """Segment of ``line (3,)`` spanning the projections of ``points (M, 2)``, clipped to the image.

    The axis is the infinite line; its extent is that of the mirror pairs supporting it,
    from the ``trim`` to the ``1 - trim`` quantile of their projections onto the line (so
    one stray pair does not stretch it). Returns ``(x1, y1, x2, y2)`` or None.
    """
    a, b, c = (float(v) for v in line)
    foot = torch.tensor([-c * a, -c * b], dtype=torch.float64)
    d = torch.tensor([-b, a], dtype=torch.float64)
    t = (points.double() - foot) @ d  # (M,)
    if t.numel() == 0:
        return clip_line_to_image(line, -1e9, 1e9, width, height)
    lo, hi = torch.quantile(t, torch.tensor([trim, 1 - trim], dtype=t.dtype))
    return clip_line_to_image(line, float(lo), float(hi), width, height)


def draw_axes(
    image: torch.Tensor,
    axes: torch.Tensor,
    pairs: torch.Tensor | None = None,
    pair_axis: torch.Tensor | None = None,
    *,
    max_pairs: int = 25,
):
    """An RGB uint8 ``(H, W, 3)`` array of ``image (C, H, W)`` with axes (and mirror pairs) drawn.

    The best axis is red, then green, blue, yellow, ...; up to ``max_pairs`` of each
    axis's supporting pairs are thin lines of the same colour with their points as dots.
    """
    import cv2

    img = image.detach().cpu().float()
    if img.dim() == 2:
        img = img[None]
    if img.shape[0] == 1:
        img = img.expand(3, -1, -1)
    arr = (img.clamp(0, 1) * 255).round().byte().permute(1, 2, 0).numpy().copy()  # (H, W, 3) RGB
    h, w = arr.shape[:2]
    thick = max(1, round(max(h, w) / 300))
    colours = [(255, 0, 0), (0, 200, 0), (0, 80, 255), (255, 200, 0), (255, 0, 255), (0, 220, 220), (255, 128, 0)]
    if pairs is not None and pair_axis is not None:
        shown = []
        for k in range(int(axes.shape[0])):
            idx = (pair_axis == k).nonzero().flatten()
            shown += idx[torch.linspace(0, idx.numel() - 1, min(idx.numel(), max_pairs)).round().long()].tolist() if idx.numel() else []
        for i in shown:
            (x1, y1, x2, y2), k = pairs[i].tolist(), int(pair_axis[i])
            col = tuple(int(0.6 * v) for v in colours[k % len(colours)])
            cv2.line(arr, (round(x1), round(y1)), (round(x2), round(y2)), col, 1, cv2.LINE_AA)
            cv2.circle(arr, (round(x1), round(y1)), thick + 1, col, -1)
            cv2.circle(arr, (round(x2), round(y2)), thick + 1, col, -1)
    for k, (x1, y1, x2, y2) in reversed(list(enumerate(axes.tolist()))):
        cv2.line(arr, (round(x1), round(y1)), (round(x2), round(y2)), colours[k % len(colours)], 2 * thick + 1, cv2.LINE_AA)
    return arr


@dataclasses.dataclass(frozen=True)
class ReflectionAxesResult(Result):
    """Reflection symmetry axes found in one image (thesis Ch. 2).

    Attributes:
        axes: ``(K, 4)`` float segments ``x1, y1, x2, y2`` in input-image pixels (origin
            top-left, x right, y down), best first: the axis line clipped to the image and
            to the extent of its supporting pairs (or the extent the method reports,
            e.g. grown by :func:`axis_evidence`).
        scores: ``(K,)`` float, decreasing: the method's axis score (its documentation
            says which; by default the support, the number of mirror pairs).
        lines: ``(K, 3)`` float lines ``(a, b, c)``, ``a x + b y + c = 0`` with unit ``(a, b)``.
        pairs: ``(P, 4)`` float mirror pairs ``x1, y1, x2, y2`` found in the image.
        pair_axis: ``(P,)`` int64 index into ``axes`` of the axis each pair supports, -1
            for pairs that support none.
        image_size: ``(height, width)`` of the input image.
        method: the solver's registered name.
        converged: False when an iteration stopped at its limit or a step fell back.
        info: method-specific diagnostics (cost curves, fallbacks, timings), plain Python.
    """

    axes: torch.Tensor
    scores: torch.Tensor
    lines: torch.Tensor
    pairs: torch.Tensor
    pair_axis: torch.Tensor
    image_size: tuple[int, int]
    method: str
    converged: bool = True
    info: dict[str, Any] = dataclasses.field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.axes.shape[0])

    def write_artifacts(self, data: Any, out_dir: Path, stem: str) -> list[Path]:
        """Write ``{stem}_axes.png``: the image with the axes and their mirror pairs drawn."""
        import cv2

        img = data[0] if isinstance(data, torch.Tensor) and data.dim() == 4 else data
        if not isinstance(img, torch.Tensor):
            img = torch.as_tensor(np.asarray(img))
        out_dir = Path(out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
        path = out_dir / f"{stem}_axes.png"
        arr = draw_axes(img, self.axes, self.pairs, self.pair_axis)
        cv2.imwrite(str(path), arr[:, :, ::-1])
        return [path]


def empty_result(height: int, width: int, method: str, *, pairs: torch.Tensor | None = None, **info: Any) -> ReflectionAxesResult:
    """A result with no axes (blank image, too few features)."""
    pairs = torch.zeros(0, 4) if pairs is None else pairs
    return ReflectionAxesResult(
        axes=torch.zeros(0, 4),
        scores=torch.zeros(0),
        lines=torch.zeros(0, 3),
        pairs=pairs,
        pair_axis=torch.full((pairs.shape[0],), -1, dtype=torch.int64),
        image_size=(height, width),
        method=method,
        converged=True,
        info=dict(info),
    )


def build_result(
    lines: list[torch.Tensor],
    supports: list[torch.Tensor],
    scores: list[float],
    pairs: torch.Tensor,
    height: int,
    width: int,
    method: str,
    *,
    converged: bool = True,
    extents: list[tuple[float, float]] | None = None,
    **info: Any,
) -> ReflectionAxesResult:
    """Turn per-axis lines, supporting pair indices and scores into a sorted result.

    Each axis's segment spans its supporting pairs (:func:`axis_segment`), or, when
    ``extents`` is given, the interval ``(t_lo, t_hi)`` of the line's parameter
    (:func:`axis_evidence`). Axes whose segment misses the image are dropped.
    """
    order = sorted(range(len(lines)), key=lambda k: -scores[k])
    axes, keep_lines, keep_scores = [], [], []
    pair_axis = torch.full((pairs.shape[0],), -1, dtype=torch.int64)
    for k in order:
        sup = supports[k]
        pts = pairs[sup].reshape(-1, 2)
        if extents is None:
            seg = axis_segment(lines[k], pts, width, height)
        else:
            seg = clip_line_to_image(lines[k], extents[k][0], extents[k][1], width, height)
        if seg is None:
            continue
        pair_axis[sup] = len(axes)
        axes.append(seg)
        keep_lines.append(lines[k].double())
        keep_scores.append(float(scores[k]))
    if not axes:
        return empty_result(height, width, method, pairs=pairs, **info)
    return ReflectionAxesResult(
        axes=torch.tensor(axes, dtype=torch.float32),
        scores=torch.tensor(keep_scores, dtype=torch.float32),
        lines=torch.stack(keep_lines).float(),
        pairs=pairs.float(),
        pair_axis=pair_axis,
        image_size=(height, width),
        method=method,
        converged=converged,
        info=dict(info),
    )


@dataclasses.dataclass(frozen=True)
class ReflectionAxesBatch(Result):
    """Reflection axes of a batch of images.

    Attributes:
        results: one :class:`ReflectionAxesResult` per image, in batch order.
    """

    results: tuple[ReflectionAxesResult, ...]

    def __len__(self) -> int:
        return len(self.results)

    def __getitem__(self, i: int) -> ReflectionAxesResult:
        return self.results[i]

    def write_artifacts(self, data: Any, out_dir: Path, stem: str) -> list[Path]:
        """Write one ``{stem}_{b}_axes.png`` per image of ``data (B, C, H, W)``."""
        paths: list[Path] = []
        for b, res in enumerate(self.results):
            paths += res.write_artifacts(data[b], out_dir, f"{stem}_{b}")
        return paths


def check_max_side(max_side: Any) -> int | None:
    """``max_side`` of the image detectors: None or an integer >= ``SIFT_MIN_SIDE`` (32)."""
    from torchsym.core.checks import check_int
    from torchsym.features.sift import SIFT_MIN_SIDE

    return None if max_side is None else check_int(max_side, "max_side", minimum=SIFT_MIN_SIDE)


def to_input_pixels(res: ReflectionAxesResult, height: int, width: int) -> ReflectionAxesResult:
    """``res``, found on a resized copy of an image, in the pixels of the ``height x width`` input.

    Pixel centres map to pixel centres (``x = (x' + 0.5) * width / w' - 0.5``, as
    ``interpolate(align_corners=False)`` samples), so a segment clipped to the copy's
    border ends within half a copy pixel of the input's border; each line
    ``a x + b y + c = 0`` is mapped the same way and renormalised.
    ``info["working_size"]`` records the copy's size.
    """
    h, w = res.image_size
    sx, sy = width / w, height / h

    def points(t: torch.Tensor) -> torch.Tensor:
        t = t.double().clone()
        t[..., 0::2] = (t[..., 0::2] + 0.5) * sx - 0.5
        t[..., 1::2] = (t[..., 1::2] + 0.5) * sy - 0.5
        return t.float()

    ln = res.lines.double()
    a, b = ln[:, 0] / sx, ln[:, 1] / sy
    c = ln[:, 2] + ln[:, 0] * (0.5 / sx - 0.5) + ln[:, 1] * (0.5 / sy - 0.5)
    lines = torch.stack([a, b, c], 1) / torch.hypot(a, b)[:, None] if ln.shape[0] else ln
    return dataclasses.replace(
        res, axes=points(res.axes), lines=lines.float(), pairs=points(res.pairs), image_size=(height, width),
        info={**res.info, "working_size": (h, w)},
    )


def run_batched(
    fn, image: Any, settings: dict[str, Any], *, max_side: int | None = None
) -> ReflectionAxesResult | ReflectionAxesBatch:
    """Apply a single-image detector ``fn`` to ``(C, H, W)`` or ``(B, C, H, W)`` input.

    With ``max_side``, an image whose longer side exceeds it is detected on a copy scaled
    down (antialiased) to that side and the result given in the input's pixels
    (:func:`to_input_pixels`). The image detectors default to 640: their settings in
    pixels (segment length, pair distances) were chosen on photos 640 pixels on their
    longer side, the benchmark's size, and the thesis names no size. A 4000 x 3000 photo
    took 22 s and 1.8 GB at full size through ``torchsym detect`` with the default
    pipeline, 4.1 s and 0.8 GB at 640 (reading, drawing and writing included; scratch run).
    """
    from torchsym.core.checks import check_image

    img = check_image(image, "image", min_size=16)
    height, width = int(img.shape[-2]), int(img.shape[-1])
    work = img
    if max_side is not None and max(height, width) > max_side:
        from torchsym.features.sift import SIFT_MIN_SIDE

        scale = max_side / max(height, width)
        # the short side of a long strip is kept at SIFT's smallest (the scale then differs
        # per axis; the mapping back handles it)
        size = tuple(min(side, max(SIFT_MIN_SIDE, round(side * scale))) for side in (height, width))
        # antialiased resizing exists for float32 and float64 only
        src = img if img.dtype in (torch.float32, torch.float64) else img.float()
        # a triangle filter (non-negative weights): the copy stays within the input's range,
        # whatever that range is (no clamp to [0, 1])
        work = torch.nn.functional.interpolate(src, size=size, mode="bilinear", align_corners=False, antialias=True)

    def one(b: int) -> ReflectionAxesResult:
        res = fn(work[b : b + 1], **settings)
        return res if work is img else to_input_pixels(res, height, width)

    if img.shape[0] == 1:
        return one(0)
    return ReflectionAxesBatch(tuple(one(b) for b in range(img.shape[0])))


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
    """The median gradient magnitude of an image: the level of its noise and smooth shading.

    Most pixels of a photograph lie off its edges, so the median of ``|g|`` measures
    what the gradients are where nothing is: sensor noise and slow shading. On the
    synthetic benchmark images the background's smoothed noise peaks at about twice the
    median, while object edges are ten times it and more.
    """

    gx, gy = np.asarray(gx), np.asarray(gy)
    if gx.shape != gy.shape:
        raise InputShapeError(f"gx, gy: expected two arrays of one shape, got {gx.shape} and {gy.shape}")
    return float(np.median(np.hypot(gx, gy))) if gx.size else 0.0


def _bilinear(img: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``img`` at float positions ``(x, y)`` by bilinear interpolation, NaN outside the image."""
    from scipy.ndimage import map_coordinates

    return map_coordinates(img, np.stack([y, x]), order=1, mode="constant", cval=np.nan, prefilter=False)


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
            the support's extent grown where the mirror evidence continues (and trimmed
            to edge crossings with ``crossings``).
        kept: indices of the pairs the evidence rests on when the support was cut at
            empty background (``split_gap`` of :func:`axis_evidence`); None: every pair.
    """

    symmetry: float
    area: float
    extent: tuple[float, float]
    kept: tuple[int, ...] | None = None

    def score(self, support: int) -> float:
        """The axis score of both methods' ``score="gradient"``: ``symmetry * sqrt(area) *
        log(1 + support)`` (negative symmetry counts as 0), for ``support`` mirror pairs."""
        return max(self.symmetry, 0.0) * math.sqrt(max(self.area, 0.0)) * math.log1p(support)


def _grow(
    t: np.ndarray, gain: np.ndarray, bin_length: float, strong: np.ndarray | None = None, max_gap: int | None = None
) -> float:
    """How far to grow past an end: ``t >= 0`` distances beyond it, ``gain`` per sample.

    Bins ``[k L, (k + 1) L)``; the run of bins from the end with the largest positive
    total gain, or 0 when every run loses. With ``strong`` (bool per sample) and
    ``max_gap``, the run may not cross more than ``max_gap`` consecutive bins without a
    strong sample: empty background costs nothing, so without this rule a run could
    cross it to reach a stray mirrored edge far beyond the object.
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
    edge_fraction: float = 0.5,
    step: float = 2.0,
    bin_length: float = 4.0,
    max_gap: int | None = 2,
    noise_level: float = 0.0,
    chord_angle: float = 45.0,
    along_gap: float | None = 0.1,
    crossings: bool = False,
    split_gap: int | None = 4,
) -> AxisEvidence:
    """How exactly the image's gradients are mirrored about ``line``, and how far along it.

    A dense check of the axis that the sparse pairs voted for, in the spirit of Eq. 2.9
    (thesis Sec. 2.3.2: the reflected orientation of a boundary must match the orientation
    at its mirror point), but over every pixel of a band around the axis rather than at
    boundary samples only. With ``R`` the reflection and ``p'`` the mirror point of ``p``,
    a symmetric image has ``g(p) = R g(p')`` for its gradient ``g``; the ``symmetry`` of
    :class:`AxisEvidence` is ``1 - sum |g(p) - R g(p')|^2 / sum (|g(p)|^2 + |g(p')|^2)``,
    so an edge without an edge at its mirror point counts against the axis as much as a
    misoriented one (where both points lie in the image; points whose mirror falls
    outside are left out).

    - Band: points with offset between ``min_offset`` and the half-width ``w`` from the
      line, sampled every ``step`` pixels from the support's first point ``t0``; ``w`` is
      the 90th percentile of the supporting pairs' half chords, at least
      ``min_half_width`` and ``min_offset + step``. Points closer to the line than
      ``min_offset`` are left out: after smoothing a pixel that near the axis correlates
      with its mirror whatever the image.
    - ``symmetry`` and ``area``: over the band's part within the supporting pairs' extent
      ``[t0, t1]``.
    - ``extent``: ``[t0, t1]`` grown past each end by the run of bins (``bin_length``
      pixels, counted from that end) that maximises
      ``sum 2 g . R g' - grow_threshold (|g|^2 + |g'|^2)``, i.e. as far as the local
      symmetry stays above ``grow_threshold`` on balance. Only points whose gradient (or
      their mirror's) is at least ``edge_fraction`` of the mean within ``[t0, t1]`` count:
      smooth shading along the axis is mirror symmetric too (a ramp along the axis is its
      own mirror image) but is no part of the object. Boundary pairs are at least a
      minimum chord apart (``segment_length`` in
      :func:`~torchsym.image.boundary_cliques.boundary_clique_axes`), so the supporting
      pairs stop short of an object's narrow ends (a leaf's tip, an animal's chin) while
      the gradients there are still mirrored. ``None`` keeps ``[t0, t1]``. The run may
      not cross more than ``max_gap`` consecutive bins without a counted gradient: empty
      background adds nothing to the sum, so without this rule a segment could cross it
      to a stray mirrored edge far beyond the object (on the synthetic benchmark images
      segments grew up to 120 px past an object's end).
    - Noise: gradients no larger than ``noise_level`` never count for the growth (callers
      pass ``EDGE_NOISE`` times :func:`gradient_noise`). The ``edge_fraction`` rule alone
      is relative to the support's own gradients: on a weakly textured object, or a
      support of pairs on the background, the background's noise passed it, its smooth
      shading (mirror symmetric along the axis) kept the gain positive, and segments grew
      to the image border (3 of the 4 axes missed on the 30 synthetic benchmark images).
    - Pairs along the axis: a pair whose chord is more than ``chord_angle`` degrees from
      the normal is no mirror pair of this axis (a zero-length chord counts as a mirror
      pair). Its two points are boundary points on
      the line, where an outline crosses its own axis (Eq. 2.9 accepts such a pair,
      since each segment is its own mirror image): the ends of an object, or of another
      object further along the line. With ``along_gap``, the extent is that of the true
      mirror pairs, stretched to such points only step by step, each within
      ``along_gap * max(H, W)`` of the extent so far (None: every point counts, as
      before). On the synthetic images single pairs between two objects on one line
      stretched a segment by up to 190 px.
    - ``split_gap``: pairs gathered on one line may belong to two objects on it, or to
      an object and clutter. Where more than ``split_gap`` consecutive bins inside
      ``[t0, t1]`` hold no counted gradient (by the growth's rules: above
      ``edge_fraction`` of the support's mean and above ``noise_level``), the band
      crosses empty background there; the support is cut at such gaps and the evidence
      is that of the part holding the most pair midpoints (the first along the line on
      a tie; :attr:`AxisEvidence.kept` lists its pairs; with growth only). On 30
      fresh synthetic images (seeds 3000-3029) this found the last missed axis (75 of
      75); dev max F and the benchmark's 30 images were unchanged.
    - ``crossings``: the grown extent is trimmed to the outermost points where an edge
      crosses the line (within 1 px, a gradient at least the growth's edge level;
      searched one bin beyond each end), unless the trimmed extent, widened by a bin,
      would leave out half of the pairs' midpoints. A symmetric object's outline
      crosses its axis at both ends, while a stray pair beyond it (two mirrored blobs of
      texture) need not. Meant for keypoint pairs
      (:func:`~torchsym.image.ksymmetry.mirror_pair_candidates`), which sit on blobs
      rather than outlines; on the boundary pairs of method (b) it cost max F on the
      development photographs (0.426 to 0.255 on the thesis's criterion), since
      photographed objects often end without a crisp edge on the axis.

    Args:
        gx: ``(H, W)`` x-derivative (:func:`mirror_gradients`).
        gy: ``(H, W)`` y-derivative, the same shape.
        line: ``(3,)`` ``a x + b y + c = 0``; ``(a, b)`` is normalised here.
        pairs: ``(M, 4)`` supporting mirror pairs ``x1, y1, x2, y2``, ``M >= 1``, finite.
        min_half_width: the least band half-width, pixels.
        min_offset: the band leaves out points nearer the line than this, pixels.
        grow_threshold: local symmetry in [-1, 1] above which the extent grows; None: no
            growth.
        edge_fraction: gradients weaker than this fraction of the support's mean gradient
            do not count for the growth.
        step: sampling step of the band, pixels.
        bin_length: bin length along the line for the growth, pixels.
        max_gap: the most consecutive bins without a counted gradient that the growth
            crosses (None: no limit).
        noise_level: gradient magnitude (units of ``gx``) at or below which a point
            never counts for the growth.
        chord_angle: pairs whose chord is farther than this from the line's normal,
            degrees, are points on the line rather than mirror pairs (see above).
        along_gap: the longest step, as a fraction of ``max(H, W)``, by which such
            points stretch the extent; None lets every point of every pair count.
        crossings: trim the grown extent to the outermost edge crossings of the line
            (only with growth, ``grow_threshold`` not None).
        split_gap: the most consecutive empty bins inside the support before it is cut
            (see above; None: never cut).

    Returns:
        :class:`AxisEvidence`.

    Raises:
        InputShapeError: ``gx``, ``gy``, ``line`` or ``pairs`` of the wrong shape.
        InputValueError: non-finite ``line`` or ``pairs``, a zero normal, no pairs, or a
            setting out of range.
    """
    from torchsym.core.checks import check_in_range, check_int, check_positive

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
    for name, val in (("min_half_width", min_half_width), ("min_offset", min_offset), ("edge_fraction", edge_fraction)):
        check_positive(val, name, allow_zero=True)
    step, bin_length = check_positive(step, "step"), check_positive(bin_length, "bin_length")
    if max_gap is not None:
        max_gap = check_int(max_gap, "max_gap", minimum=0)
    noise_level = check_positive(noise_level, "noise_level", allow_zero=True)
    if not isinstance(crossings, (bool, np.bool_)):
        raise InputValueError(f"crossings: expected True or False, got {crossings!r}")
    chord_angle = check_in_range(chord_angle, "chord_angle", 0.0, 90.0)
    if along_gap is not None:
        along_gap = check_positive(along_gap, "along_gap", allow_zero=True)
    if split_gap is not None:
        split_gap = check_int(split_gap, "split_gap", minimum=0)
    if grow_threshold is not None:
        grow_threshold = check_in_range(grow_threshold, "grow_threshold", -1.0, 1.0)
    h, w = gx.shape
    a, b, c = ln / norm
    n = np.array([a, b])
    d = np.array([-b, a])
    foot = np.array([-c * a, -c * b])
    t0, t1 = _support_extent(pairs, n, d, foot, chord_angle, None if along_gap is None else along_gap * max(h, w))
    half = 0.5 * np.hypot(pairs[:, 2] - pairs[:, 0], pairs[:, 3] - pairs[:, 1])
    width = max(float(np.percentile(half, 90)), float(min_half_width), min_offset + step)
    full = clip_line_to_image(np.array([a, b, c]), -1e9, 1e9, w, h)
    if full is None:
        return AxisEvidence(0.0, 0.0, (t0, t1))
    f0, f1 = sorted(((np.array(full[:2]) - foot) @ d, (np.array(full[2:]) - foot) @ d))
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
    dot2 = 2 * (gpx * rx + gpy * ry)
    g2, r2 = gpx * gpx + gpy * gpy, rx * rx + ry * ry
    energy = g2 + r2
    inside = ok & (part == 0)
    area = float(inside.sum()) * step * step / (h * w)
    symmetry = float(dot2[inside].sum() / max(float(energy[inside].sum()), 1e-12))
    lo, hi = t0, t1
    if grow_threshold is not None and inside.any():
        ref = float(np.sqrt(g2[inside]).mean())
        level = max(edge_fraction * ref, noise_level)
        strong = np.maximum(g2, r2) > level * level
        if split_gap is not None and pairs.shape[0] > 1:
            keep = _split_support(pairs, foot, d, t0, t1, tt[part == 0], strong[part == 0], bin_length, split_gap)
            if keep is not None:
                part_ev = axis_evidence(
                    gx, gy, ln, pairs[keep], min_half_width=min_half_width, min_offset=min_offset,
                    grow_threshold=grow_threshold, edge_fraction=edge_fraction, step=step, bin_length=bin_length,
                    max_gap=max_gap, noise_level=noise_level, chord_angle=chord_angle, along_gap=along_gap,
                    crossings=crossings, split_gap=None,
                )
                return dataclasses.replace(part_ev, kept=tuple(int(i) for i in np.flatnonzero(keep)))
        gain = np.where(strong, dot2 - grow_threshold * energy, 0.0)
        up, down = part == 1, part == 2
        hi = t1 + _grow(tt[up] - t1, gain[up], bin_length, strong[up], max_gap)
        lo = t0 - _grow(t0 - tt[down], gain[down], bin_length, strong[down], max_gap)
        if crossings:
            mids = (0.5 * (pairs[:, :2] + pairs[:, 2:]) - foot) @ d  # (M,)
            lo, hi = _trim_to_crossings(gx, gy, foot, d, n, (lo, hi), mids, level, bin_length)
    return AxisEvidence(symmetry, area, (float(lo), float(hi)))


def _split_support(
    pairs: np.ndarray, foot: np.ndarray, d: np.ndarray, t0: float, t1: float,
    t: np.ndarray, strong: np.ndarray, bin_length: float, split_gap: int,
) -> np.ndarray | None:
    """The pairs of the best-supported part of ``[t0, t1]``, or None when nothing splits it.

    Bins of ``bin_length`` along the line; runs of more than ``split_gap`` bins without
    a ``strong`` sample (``t`` their positions) and with counted bins on both sides cut
    the support; the part holding the most pair midpoints is kept.
    """
    nb = int((t1 - t0) // bin_length) + 1
    bins = np.clip(((t - t0) // bin_length).astype(np.int64), 0, nb - 1)
    empty = np.bincount(bins, weights=strong.astype(np.float64), minlength=nb) == 0  # (nb,)
    change = np.diff(np.concatenate([[0], empty.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(change == 1), np.flatnonzero(change == -1)  # empty runs [start, stop)
    inner = (stops - starts > split_gap) & (starts > 0) & (stops < nb)
    if not inner.any():
        return None
    cuts = t0 + bin_length * 0.5 * (starts[inner] + stops[inner])  # (C,) middles of the gaps
    mids = (0.5 * (pairs[:, :2] + pairs[:, 2:]) - foot) @ d  # (M,)
    part = np.searchsorted(cuts, mids)  # (M,) in 0..C
    keep = part == np.bincount(part, minlength=cuts.size + 1).argmax()
    return keep if 0 < keep.sum() < pairs.shape[0] else None


def _support_extent(
    pairs: np.ndarray, n: np.ndarray, d: np.ndarray, foot: np.ndarray, chord_angle: float, gap: float | None
) -> tuple[float, float]:
    """``(t0, t1)``: the pairs' extent along the line (see ``along_gap`` of :func:`axis_evidence`)."""
    t_all = (pairs.reshape(-1, 2) - foot) @ d  # (2M,)
    if gap is None:
        return float(t_all.min()), float(t_all.max())
    chord = pairs[:, 2:] - pairs[:, :2]
    mirror = np.abs(chord @ n) >= math.cos(math.radians(chord_angle)) * np.linalg.norm(chord, axis=1)  # (M,)
    if not mirror.any() or mirror.all():
        return float(t_all.min()), float(t_all.max())
    t_pairs = t_all.reshape(-1, 2)
    lo, hi = float(t_pairs[mirror].min()), float(t_pairs[mirror].max())
    on_line = np.sort(t_pairs[~mirror].reshape(-1))
    for t in on_line[on_line > hi]:  # ascending: stretch while each step is short
        if t - hi > gap:
            break
        hi = float(t)
    for t in on_line[on_line < lo][::-1]:
        if lo - t > gap:
            break
        lo = float(t)
    return lo, hi


def _trim_to_crossings(
    gx: np.ndarray, gy: np.ndarray, foot: np.ndarray, d: np.ndarray, n: np.ndarray,
    extent: tuple[float, float], mids: np.ndarray, level: float, slack: float,
) -> tuple[float, float]:
    """``extent`` trimmed to the outermost points of the line (within 1 px) whose gradient
    magnitude is at least ``level``, searched ``slack`` beyond each end; kept whole when
    the trimmed extent, widened by ``slack``, would hold fewer than half of the pairs'
    midpoints ``mids`` (positions along the line), or would be empty."""
    lo, hi = extent
    ts = np.arange(lo - slack, hi + slack + 1e-9, 1.0)  # (T,)
    mag = np.zeros(ts.size)
    for off in (-1.0, 0.0, 1.0):
        p = foot + ts[:, None] * d + off * n
        m = np.hypot(_bilinear(gx, p[:, 0], p[:, 1]), _bilinear(gy, p[:, 0], p[:, 1]))
        mag = np.fmax(mag, np.nan_to_num(m, nan=0.0))
    cross = ts[mag >= level]
    if cross.size == 0:
        return lo, hi
    a, b = max(lo, float(cross.min())), min(hi, float(cross.max()))
    if a >= b:  # the only crossings lie within the slack beyond one end
        return lo, hi
    held = np.count_nonzero((mids >= a - slack) & (mids <= b + slack))
    return (a, b) if 2 * held >= mids.size else (lo, hi)


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
    from torchsym.core.checks import check_positive

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
    one: the same object found twice (by two sources of candidate axes, or by two
    clusters on one line), while two objects on one line are both kept.

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
    from torchsym.core.checks import check_in_range, check_positive

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
