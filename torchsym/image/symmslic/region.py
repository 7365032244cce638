"""The symmetric region of each axis, where SymmSLIC places mirror pairs of centres
(thesis Sec. 4.2.2: the convex hull of the pairs L and R, grown through the pixels whose
neighbourhood matches the mirror image's)."""

from __future__ import annotations

import cv2
import numpy as np
import torch
from scipy import ndimage

from torchsym.image.symmslic.pairs import MirrorPixelPairs

__all__ = ["mirror_correlation_map", "symmetric_region"]


def _blur(x: np.ndarray) -> np.ndarray:
    """``x (C, H, W)`` float64 blurred by a Gaussian of 4 px, truncated at 4 sigma, with
    reflected borders (as ``scipy.ndimage.gaussian_filter``)."""
    out = cv2.GaussianBlur(np.ascontiguousarray(x.transpose(1, 2, 0)), (33, 33), 4.0, borderType=cv2.BORDER_REFLECT)
    return out.reshape(x.shape[1], x.shape[2], -1).transpose(2, 0, 1)


def mirror_correlation_map(lab: np.ndarray, normal: np.ndarray, offset: float) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """How well each pixel's neighbourhood (Gaussian, 4 px) matches the mirror image's
    about ``normal . (x, y) + offset = 0``: the normalised cross-correlation over the 3
    channels of ``lab (3, H, W)``, each variance with 4 added, so that a flat patch
    correlates with nothing. Returns ``(ncc (H, W), band (H, W) bool, (mx, my))``:
    ``band`` the pixels whose mirror pixel ``(mx, my)`` (clipped) lies in the image."""
    _, h, w = lab.shape
    ys, xs = np.mgrid[0:h, 0:w]
    d = xs * normal[0] + ys * normal[1] + offset
    mx, my = np.round(xs - 2 * d * normal[0]).astype(np.int64), np.round(ys - 2 * d * normal[1]).astype(np.int64)
    band = (mx >= 0) & (mx < w) & (my >= 0) & (my < h)
    mx, my = mx.clip(0, w - 1), my.clip(0, h - 1)
    x = lab.astype(np.float64)
    y = x[:, my, mx]  # the mirror image
    mxv, myv = _blur(x), _blur(y)
    cov = (_blur(x * y) - mxv * myv).sum(0)
    vx = (_blur(x * x) - mxv**2).sum(0)
    vy = (_blur(y * y) - myv**2).sum(0)
    return cov / np.sqrt((vx + 4.0) * (vy + 4.0)), band, (mx, my)


def _grow(hull: np.ndarray, lab: np.ndarray, normal: np.ndarray, offset: float, min_corr: float) -> np.ndarray:
    """``hull (H, W)`` bool grown through the pixels whose neighbourhood (Gaussian, 4 px)
    correlates with the mirror image's at least ``min_corr`` (normalised cross-correlation
    over the 3 channels of ``lab (3, H, W)``; a flat patch, variance under 4, correlates
    with nothing), keeping the pixels whose mirror lies in the image, then made symmetric."""
    ncc, band, (mx, my) = mirror_correlation_map(lab, normal, offset)
    agree = band & ((ncc >= min_corr) | hull)
    comp, _ = ndimage.label(agree)
    seeds = np.unique(comp[hull & agree])
    grown = np.isin(comp, seeds[seeds > 0])
    return grown | (grown[my, mx] & band)


def symmetric_region(
    pairs: MirrorPixelPairs, normals: torch.Tensor, offsets: torch.Tensor, h: int, w: int, lab: np.ndarray | None = None, min_corr: float = 1.0
) -> np.ndarray:
    """``(H, W)`` int64 axis index of the symmetric region of each axis (-1 outside): the
    convex hull of the axis's pairs, grown (given ``lab (3, H, W)`` and ``min_corr < 1``)
    through the pixels whose neighbourhood correlates with the mirror image's at least
    ``min_corr``; with no pairs (axes given by the caller) the pixels whose mirror lies in
    the image. The first axis wins where regions overlap."""
    region = np.full((h, w), -1, dtype=np.int64)
    ys, xs = np.mgrid[0:h, 0:w]
    for a in reversed(range(normals.shape[0])):
        if len(pairs):
            pts = torch.cat([pairs.left[pairs.axis == a], pairs.right[pairs.axis == a]]).numpy()
            if len(pts) < 3:
                continue
            hull = cv2.convexHull(pts.round().astype(np.int32))
            m = np.zeros((h, w), np.uint8)
            cv2.fillConvexPoly(m, hull, 1)
            inside = m > 0
            if min_corr < 1.0 and lab is not None:
                inside = _grow(inside, lab, normals[a].numpy(), float(offsets[a]), min_corr)
            region[inside] = a
        else:
            n, b = normals[a].numpy(), float(offsets[a])
            d = xs * n[0] + ys * n[1] + b
            mx, my = xs - 2 * d * n[0], ys - 2 * d * n[1]
            inside = (mx >= 0) & (mx <= w - 1) & (my >= 0) & (my <= h - 1)
            region[inside] = a
    return region
