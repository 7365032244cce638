"""Photographs with a known reflection axis for choosing the axis stage's settings.

Leeds Butterflies (Wang, Markert and Everingham 2009; fetched from the GitHub copy
``dsw88/cs601r-project1-dataset``, folder ``dataset/butterflies/``, into ``--butterflies``,
never committed): 832 photographs, each with a hand-drawn mask of the butterfly. The axis of
a photograph is the mask's best reflection axis (:func:`bench_segmentation.mask_axis`, the
rule of the segmentation benchmark: axes through the centroid every degree, shifted by up
to 0.1 equivalent radius), drawn as the segment of that line inside the mask; a photograph
counts only when that reflection's IoU is at least ``MIN_IOU`` (a butterfly seen from the
side has no axis in the picture).

The ICCV'17 dev photographs (``axes.txt``) load by :func:`load_dev`.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import cv2
import numpy as np
import torch

from bench_segmentation import RULE_SIDE, small_mask
from torchsym.metrics.masks import best_reflection_iou

MIN_IOU = 0.80
BUTTERFLIES = Path("/work/data/butterflies")


def load_dev(folder: Path) -> list[tuple[str, Path, torch.Tensor]]:
    """``(name, path, gt (G, 4))`` per dev photograph, sorted by name (GT in original pixels)."""
    gt: dict[str, list[list[float]]] = {}
    for line in (folder / "axes.txt").read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        name, *xy = line.split()
        gt.setdefault(name, []).append([float(v) for v in xy])
    return [(name, folder / name, torch.tensor(gt[name], dtype=torch.float64)) for name in sorted(gt)]


def mask_axis(obj: np.ndarray) -> tuple[float, np.ndarray, float]:
    """``(iou, n (2,), c)``: :func:`bench_segmentation.mask_axis` with its IoU, in one search."""
    s = RULE_SIDE / max(obj.shape)
    iou, n, off = best_reflection_iou(small_mask(obj))
    off = off + float(n.sum()) * (0.5 * s - 0.5)
    return float(iou), np.asarray(n, dtype=np.float64), float(off / s)


def butterfly_axis(mask_path: Path) -> tuple[float, list[float]] | None:
    """``(iou, [x1, y1, x2, y2])``: the mask's best reflection axis as a segment inside the mask."""
    m = cv2.imread(str(mask_path), cv2.IMREAD_UNCHANGED)
    if m is None:
        return None
    obj = (m[..., 0] if m.ndim == 3 else m) > 127
    if obj.sum() < 100:
        return None
    iou, n, c = mask_axis(obj)
    u = np.array([-n[1], n[0]])
    ys, xs = np.nonzero(obj)
    p = np.stack([xs, ys], 1).astype(np.float64)
    near = np.abs(p @ n + c) <= 1.5
    if near.sum() < 2:
        return None
    t = p[near] @ u
    base = -c * n  # the foot of the origin on the line
    a, b = base + t.min() * u, base + t.max() * u
    return float(iou), [float(a[0]), float(a[1]), float(b[0]), float(b[1])]


def load_butterflies(
    folder: Path = BUTTERFLIES, cache: Path = Path("/tmp/axes47"), every: int = 2
) -> list[tuple[str, Path, torch.Tensor]]:
    """``(name, path, gt (1, 4))`` of the butterflies whose mask has an axis (IoU >= ``MIN_IOU``),
    by name; every ``every``-th photograph by name (the mask's axis search costs ~2 s)."""
    cache.mkdir(parents=True, exist_ok=True)
    file = cache / "butterfly_axes.json"
    table = json.loads(file.read_text()) if file.exists() else {}
    changed = False
    for img in sorted((folder / "images").glob("*.png"))[::every]:
        if img.stem not in table:
            table[img.stem] = butterfly_axis(folder / "segmentations" / f"{img.stem}_seg0.png")
            changed = True
            if len(table) % 20 == 0:
                file.write_text(json.dumps(table))
    if changed:
        file.write_text(json.dumps(table))
    out = []
    for name, row in sorted(table.items()):
        if row is not None and row[0] >= MIN_IOU:
            out.append((name, folder / "images" / f"{name}.png", torch.tensor([row[1]], dtype=torch.float64)))
    return out


def split_half(names: list[str], salt: str = "axes47") -> tuple[list[str], list[str]]:
    """A fixed split by a hash of the name: ``(choose, check)`` halves."""
    h = {n: hashlib.sha1((salt + n).encode()).hexdigest() for n in names}
    a = sorted(n for n in names if int(h[n][:8], 16) % 2 == 0)
    return a, sorted(set(names) - set(a))
