"""How bilaterally symmetric a binary object mask is: the IoU of the mask with its
reflection about an axis, and the best such IoU over axes through the mask's centroid.

Used to pick the images with one symmetric object from ground-truth masks alone
(``benchmarks/bench_segmentation.py``). Masks are ``(H, W)`` bool arrays or tensors; an
axis is ``normal . (x, y) + offset = 0`` in pixel coordinates (x the column).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch

from torchsym.errors import InputShapeError, InputValueError

__all__ = ["best_reflection_iou", "reflection_iou"]


def _mask(x: Any) -> np.ndarray:
    a = x.detach().cpu().numpy() if isinstance(x, torch.Tensor) else np.asarray(x)
    if a.ndim != 2 or a.size == 0:
        raise InputShapeError(f"mask: expected an (H, W) binary mask, got shape {a.shape}")
    return a.astype(bool)


def _ious(m: np.ndarray, normals: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """``(K,)`` IoU of ``m`` with its reflection about each of ``K`` axes: fg pixels are
    reflected and rounded to the nearest pixel; those landing on fg count as the
    intersection (off the image: no overlap); reflection keeps the area, so the union is
    ``2 |M| - intersection``."""
    h, w = m.shape
    ys, xs = np.nonzero(m)
    n = len(xs)
    if n == 0:
        return np.zeros(len(normals))
    p = np.stack([xs, ys], 1).astype(np.float64)  # (N, 2)
    out = np.empty(len(normals))
    for i in range(0, len(normals), 64):  # chunks of axes keep memory at N x 64
        nr, off = normals[i : i + 64], offsets[i : i + 64]  # (k, 2), (k,)
        d = p @ nr.T + off  # (N, k)
        rx = np.rint(p[:, :1] - 2 * d * nr[:, 0]).astype(np.int64)
        ry = np.rint(p[:, 1:] - 2 * d * nr[:, 1]).astype(np.int64)
        inside = (rx >= 0) & (rx < w) & (ry >= 0) & (ry < h)
        hit = np.zeros_like(inside)
        hit[inside] = m[ry[inside], rx[inside]]
        inter = hit.sum(0)
        out[i : i + 64] = inter / (2 * n - inter)
    return out


def reflection_iou(mask: Any, normal: Any, offset: float) -> float:
    """IoU of ``mask (H, W)`` with its reflection about ``normal . (x, y) + offset = 0``
    (pixels reflected and rounded; 0 for an empty mask)."""
    m = _mask(mask)
    nr = np.asarray(normal.tolist() if isinstance(normal, torch.Tensor) else normal, dtype=np.float64).reshape(-1)
    if nr.shape != (2,) or not np.isfinite(nr).all() or np.linalg.norm(nr) == 0:
        raise InputValueError(f"normal: expected two finite numbers, not both zero, got {nr.tolist()}")
    s = np.linalg.norm(nr)
    return float(_ious(m, (nr / s)[None], np.array([float(offset) / s]))[0])


def best_reflection_iou(
    mask: Any, *, angle_step: float = 1.0, offsets: Sequence[float] = (-0.1, -0.05, 0.0, 0.05, 0.1)
) -> tuple[float, np.ndarray, float]:
    """The best :func:`reflection_iou` over axes through the mask's centroid at every
    ``angle_step`` degrees in [0, 180), each also shifted across itself by ``offsets``
    times the mask's equivalent radius ``sqrt(|M| / pi)``.

    Returns:
        ``(iou, normal (2,), offset)`` of the best axis; ``(0.0, [1, 0], 0.0)`` for an
        empty mask.
    """
    m = _mask(mask)
    if not 0 < angle_step <= 180:
        raise InputValueError(f"angle_step: expected in (0, 180] degrees, got {angle_step}")
    ys, xs = np.nonzero(m)
    if len(xs) == 0:
        return 0.0, np.array([1.0, 0.0]), 0.0
    c = np.array([xs.mean(), ys.mean()])
    radius = math.sqrt(len(xs) / math.pi)
    theta = np.deg2rad(np.arange(0.0, 180.0, angle_step))
    nr = np.stack([-np.sin(theta), np.cos(theta)], 1)  # (A, 2): normal of the axis with direction theta
    shift = np.asarray(offsets, dtype=np.float64) * radius  # (O,)
    normals = np.repeat(nr, len(shift), 0)  # (A O, 2)
    offs = (-(nr @ c)[:, None] + shift[None]).reshape(-1)  # (A O,)
    ious = _ious(m, normals, offs)
    best = int(ious.argmax())
    return float(ious[best]), normals[best], float(offs[best])
