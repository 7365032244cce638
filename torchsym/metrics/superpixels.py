"""Superpixel and segmentation measures (thesis Sec. 4.3), as D. Stutz's superpixel
benchmark defines them (``davidstutz/superpixel-benchmark``, ``lib_eval/evaluation.cpp``),
and the mirror consistency of superpixels about an axis.

Label maps are ``(H, W)`` integer arrays or tensors; ground truth segmentations too.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from scipy import ndimage

from torchsym.errors import InputShapeError, InputValueError

__all__ = [
    "achievable_segmentation_accuracy",
    "boundary_map",
    "boundary_recall",
    "compactness",
    "explained_variation",
    "mirror_consistency",
    "segmentation_error",
    "undersegmentation_error",
]


def _labels(x: Any, name: str) -> np.ndarray:
    a = x.detach().cpu().numpy() if isinstance(x, torch.Tensor) else np.asarray(x)
    if a.ndim != 2 or a.size == 0:
        raise InputShapeError(f"{name}: expected an (H, W) label map, got shape {a.shape}")
    if not (np.issubdtype(a.dtype, np.number) or a.dtype == np.bool_) or np.issubdtype(a.dtype, np.complexfloating):
        raise InputShapeError(f"{name}: expected integer labels, got dtype {a.dtype}")
    if np.issubdtype(a.dtype, np.floating) and not (np.isfinite(a).all() and (a == np.round(a)).all() and np.abs(a).max() < 2**62):
        raise InputValueError(f"{name}: expected integer labels, got non-integer, NaN or infinite values")
    return a.astype(np.int64)


def _same_shape(a: np.ndarray, b: np.ndarray) -> None:
    if a.shape != b.shape:
        raise InputShapeError(f"labels, truth: expected the same (H, W), got {a.shape} and {b.shape}")


def boundary_map(labels: Any) -> np.ndarray:
    """``(H, W)`` bool: pixels whose label differs from the right or lower neighbour
    (Stutz's ``is_boundary_pixel``)."""
    a = _labels(labels, "labels")
    b = np.zeros(a.shape, dtype=bool)
    b[:, :-1] |= a[:, :-1] != a[:, 1:]
    b[:-1, :] |= a[:-1, :] != a[1:, :]
    return b


def boundary_recall(labels: Any, truth: Any, *, tolerance: int | None = None) -> float:
    """Share of ground-truth boundary pixels with a superpixel boundary pixel within
    ``tolerance`` pixels (Chebyshev; default ``round(0.0025 * diagonal)``)."""
    a, g = _labels(labels, "labels"), _labels(truth, "truth")
    _same_shape(a, g)
    r = int(round(0.0025 * math.hypot(*a.shape))) if tolerance is None else int(tolerance)
    gb = boundary_map(g)
    if not gb.any():
        return 1.0
    near = ndimage.binary_dilation(boundary_map(a), structure=np.ones((2 * r + 1, 2 * r + 1), bool)) if r > 0 else boundary_map(a)
    return float((near & gb).sum() / gb.sum())


def _overlap(a: np.ndarray, g: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Intersection counts ``(S, G)`` and the sizes of superpixels and segments."""
    _, ai = np.unique(a, return_inverse=True)
    _, gi = np.unique(g, return_inverse=True)
    ai, gi = ai.reshape(-1), gi.reshape(-1)
    table = np.zeros((ai.max() + 1, gi.max() + 1), dtype=np.int64)
    np.add.at(table, (ai, gi), 1)
    return table, table.sum(1), table.sum(0)


def undersegmentation_error(labels: Any, truth: Any) -> float:
    """Neubert and Protzel's undersegmentation error:
    ``(1/N) sum_G sum_{S meets G} min(|S & G|, |S - G|)``."""
    a, g = _labels(labels, "labels"), _labels(truth, "truth")
    _same_shape(a, g)
    table, s_size, _ = _overlap(a, g)
    leak = np.minimum(table, s_size[:, None] - table)
    return float(leak[table > 0].sum() / a.size)


def achievable_segmentation_accuracy(labels: Any, truth: Any) -> float:
    """``(1/N) sum_S max_G |S & G|``: the accuracy of the best labelling of superpixels."""
    a, g = _labels(labels, "labels"), _labels(truth, "truth")
    _same_shape(a, g)
    table, _, _ = _overlap(a, g)
    return float(table.max(1).sum() / a.size)


def explained_variation(labels: Any, image: Any) -> float:
    """``sum_S |S| |mu_S - mu|^2 / sum_x |I(x) - mu|^2`` over the image's channels
    (``image``: ``(C, H, W)`` or ``(H, W)``)."""
    a = _labels(labels, "labels")
    im = image.detach().cpu().double().numpy() if isinstance(image, torch.Tensor) else np.asarray(image, dtype=np.float64)
    im = im[None] if im.ndim == 2 else im
    if not np.isfinite(im).all():
        raise InputValueError("image: expected finite values")
    if im.shape[1:] != a.shape:
        raise InputShapeError(f"labels, image: expected (H, W) and (C, H, W), got {a.shape} and {im.shape}")
    _, ai = np.unique(a, return_inverse=True)
    ai = ai.reshape(-1)
    x = im.reshape(im.shape[0], -1)
    mu = x.mean(1, keepdims=True)
    total = ((x - mu) ** 2).sum()
    if total == 0:
        return 1.0
    count = np.bincount(ai)
    means = np.stack([np.bincount(ai, weights=x[c]) / count for c in range(x.shape[0])])
    return float((count * ((means - mu) ** 2).sum(0)).sum() / total)


def compactness(labels: Any) -> float:
    """Schick et al.'s compactness ``sum_S |S|/N * 4 pi |S| / P_S^2``, with the perimeter
    ``P_S`` counted in pixel edges (image borders included)."""
    a = _labels(labels, "labels")
    _, ai = np.unique(a, return_inverse=True)
    ai = ai.reshape(a.shape)
    pad = np.pad(ai, 1, constant_values=-1)
    perim = np.zeros(ai.max() + 1)
    for shifted in (pad[:-2, 1:-1], pad[2:, 1:-1], pad[1:-1, :-2], pad[1:-1, 2:]):
        np.add.at(perim, ai[shifted != ai], 1)
    area = np.bincount(ai.reshape(-1)).astype(np.float64)
    return float((area / a.size * 4 * math.pi * area / np.maximum(perim, 1) ** 2).sum())


def mirror_consistency(labels: Any, normal: Any, offset: float, *, region: Any | None = None) -> float:
    """How well superpixels are mirror images of each other about the axis
    ``normal . (x, y) + offset = 0``: for every superpixel on the axis's negative side
    (within ``region``, an ``(H, W)`` bool mask, if given) the IoU of its reflection with
    the superpixel that overlaps the reflection most, averaged with the superpixels'
    areas as weights. 1 for exactly mirrored superpixels; any method's labels can be
    scored given an axis."""
    a = _labels(labels, "labels")
    a = np.unique(a, return_inverse=True)[1].reshape(a.shape)  # labels 0..S-1, whatever integers came in
    n = np.asarray(normal.tolist() if isinstance(normal, torch.Tensor) else normal, dtype=np.float64)
    if n.shape != (2,) or not np.isfinite(n).all() or not np.linalg.norm(n) > 0 or not math.isfinite(float(offset)):
        raise InputValueError(f"normal, offset: expected a finite non-zero (2,) normal and a finite offset, got {n.tolist()} and {offset!r}")
    n = n / np.linalg.norm(n)
    b = float(offset) / 1.0
    h, w = a.shape
    ys, xs = np.mgrid[0:h, 0:w]
    d = xs * n[0] + ys * n[1] + b
    mx, my = np.round(xs - 2 * d * n[0]).astype(np.int64), np.round(ys - 2 * d * n[1]).astype(np.int64)
    inside = (mx >= 0) & (mx < w) & (my >= 0) & (my < h)
    left = (d < 0) & inside
    if region is not None:
        left &= _labels(region, "region").astype(bool)
    if not left.any():
        return 0.0
    src = a[left]
    dst = a[my[left], mx[left]]
    _, si = np.unique(src, return_inverse=True)
    ud, di = np.unique(dst, return_inverse=True)
    table = np.zeros((si.max() + 1, di.max() + 1), dtype=np.int64)
    np.add.at(table, (si, di), 1)
    best = table.argmax(1)
    inter = table[np.arange(len(best)), best]
    size_src = table.sum(1)
    size_dst = np.bincount(a.reshape(-1), minlength=a.max() + 1)[ud[best]]
    iou = inter / (size_src + size_dst - inter)
    return float((iou * size_src).sum() / size_src.sum())


def segmentation_error(mask: Any, truth: Any, *, box: Sequence[int] | None = None, ignore: Any | None = None) -> dict[str, float]:
    """Misclassified pixels of a binary ``mask`` against ``truth`` (both ``(H, W)``):
    ``over_image``, over all pixels (the thesis's normalisation, Sec. 4.3.1), and
    ``over_box``, over the pixels of ``box`` (GrabCut in One Cut's).

    Args:
        mask, truth: ``(H, W)`` binary (non-zero is the object).
        box: ``(x0, y0, x1, y1)`` pixel box, ``x0 <= x < x1``, ``y0 <= y < y1`` (the box a
            method was given); default: the truth's bounding box.
        ignore: optional ``(H, W)`` binary; these pixels (e.g. GrabCut's unlabelled band
            along the outline) count neither as errors nor in either denominator.
    """
    m, g = _labels(mask, "mask").astype(bool), _labels(truth, "truth").astype(bool)
    _same_shape(m, g)
    counted = np.ones(m.shape, bool)
    if ignore is not None:
        ign = _labels(ignore, "ignore").astype(bool)
        if ign.shape != m.shape:
            raise InputShapeError(f"ignore: expected {m.shape} like mask, got {ign.shape}")
        counted = ~ign
    wrong = (m != g) & counted
    if box is None:
        ys, xs = np.nonzero(g)
        box = (0, 0, m.shape[1], m.shape[0]) if len(ys) == 0 else (xs.min(), ys.min(), xs.max() + 1, ys.max() + 1)
    if len(box) != 4 or not box[0] < box[2] or not box[1] < box[3]:
        raise InputValueError(f"box: expected (x0, y0, x1, y1) with x0 < x1 and y0 < y1, got {tuple(box)}")
    x0, y0, x1, y1 = (int(v) for v in box)
    n_box = int(counted[max(y0, 0) : y1, max(x0, 0) : x1].sum())
    n_all = int(counted.sum())
    return {"over_image": float(wrong.sum() / max(n_all, 1)), "over_box": float(wrong.sum() / max(n_box, 1))}
