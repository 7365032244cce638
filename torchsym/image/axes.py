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

__all__ = ["ReflectionAxesBatch", "ReflectionAxesResult", "axis_segment", "clip_line_to_image", "draw_axes", "pair_axes"]


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
            top-left, x right, y down), best first: the axis line clipped to the extent of
            its supporting pairs and to the image.
        scores: ``(K,)`` float, decreasing: the axis's support (number of mirror pairs).
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
    **info: Any,
) -> ReflectionAxesResult:
    """Turn per-axis lines, supporting pair indices and scores into a sorted result.

    Axes whose segment misses the image are dropped.
    """
    order = sorted(range(len(lines)), key=lambda k: -scores[k])
    axes, keep_lines, keep_scores = [], [], []
    pair_axis = torch.full((pairs.shape[0],), -1, dtype=torch.int64)
    for k in order:
        sup = supports[k]
        pts = pairs[sup].reshape(-1, 2)
        seg = axis_segment(lines[k], pts, width, height)
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


def run_batched(fn, image: Any, settings: dict[str, Any]) -> ReflectionAxesResult | ReflectionAxesBatch:
    """Apply a single-image detector ``fn`` to ``(C, H, W)`` or ``(B, C, H, W)`` input."""
    from torchsym.core.checks import check_image

    img = check_image(image, "image", min_size=16)
    if img.shape[0] == 1:
        return fn(img, **settings)
    return ReflectionAxesBatch(tuple(fn(img[b : b + 1], **settings) for b in range(img.shape[0])))


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
