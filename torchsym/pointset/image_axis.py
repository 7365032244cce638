"""PointSymm on images: the symmetry axis of the Harris corners, with RANSAC (thesis Sec. 7.4.4)."""

from __future__ import annotations

import dataclasses
from typing import Any

import kornia
import numpy as np
import torch
import torch.nn.functional as F
from scipy.spatial import cKDTree
from torch import nn

from torchsym.core.checks import check_image, check_in_range, check_int, check_positive
from torchsym.core.random import DEFAULT_SEED, make_generator, random_subset
from torchsym.core.registry import register_solver
from torchsym.core.results import Result, on_input_device
from torchsym.errors import InputShapeError, InputValueError
from torchsym.pointset.pointsymm import point_symm

__all__ = ["ImageAxisResult", "PointSymmImage", "harris_corners", "pointsymm_image"]


@dataclasses.dataclass(frozen=True)
class ImageAxisResult(Result):
    """The reflection symmetry axis of an image found by :func:`pointsymm_image`.

    Attributes:
        normal: ``(2,)`` unit normal of the axis ``normal . (x, y) + offset = 0`` in pixel
            coordinates (``x`` the column, ``y`` the row).
        offset: ``()`` offset of the axis.
        segment: ``(2, 2)`` the axis clipped to the image, two ``(x, y)`` end points
            (NaN if the line misses the image).
        corners: ``(K, 2)`` the Harris corners ``(x, y)`` used as the point set.
        inliers: ``(K,)`` bool, corners whose reflection lands near another corner.
        permutation: ``(K,)`` int64, mirror corner of each inlier, -1 elsewhere.
        score: fraction of corners that are inliers.
        iterations: RANSAC iterations run.
    """

    normal: torch.Tensor
    offset: torch.Tensor
    segment: torch.Tensor
    corners: torch.Tensor
    inliers: torch.Tensor
    permutation: torch.Tensor
    score: float
    iterations: int


def harris_corners(image: Any, n_corners: int = 200, harris_k: float = 0.04, nms_size: int = 5) -> torch.Tensor:
    """The ``n_corners`` strongest Harris corners of an image, ``(K, 2)`` as ``(x, y)`` pixels.

    Uses :func:`kornia.feature.harris_response` on the grey image, keeps the local maxima in
    ``nms_size x nms_size`` windows whose response is positive and at least 1% of the
    largest, and returns the strongest ones in decreasing order of response.

    Args:
        image: ``(H, W)``, ``(C, H, W)`` or ``(1, C, H, W)`` image.
        n_corners: largest number of corners returned.
        harris_k: the Harris detector's ``k``.
        nms_size: odd window size of the non-maximum suppression.
    """
    img = check_image(image, "image", min_size=3)
    if img.shape[0] != 1:
        raise InputShapeError(f"image: expected a single image (B = 1), got {tuple(img.shape)}")
    gray = img.mean(1, keepdim=True)  # (1, 1, H, W)
    resp = kornia.feature.harris_response(gray, k=harris_k)[0, 0]  # (H, W)
    peak = F.max_pool2d(resp[None, None], nms_size, stride=1, padding=nms_size // 2)[0, 0]
    keep = (resp == peak) & (resp > 0) & (resp >= 0.01 * resp.max())
    rows, cols = keep.nonzero(as_tuple=True)
    order = resp[rows, cols].argsort(descending=True)[:n_corners]
    return torch.stack([cols[order], rows[order]], 1).to(img.dtype)  # (K, 2)


def _segment(normal: np.ndarray, offset: float, width: int, height: int) -> np.ndarray:
    pts = []
    a, b = normal
    for x in (0.0, width - 1.0):
        if abs(b) > 1e-12:
            y = -(a * x + offset) / b
            if 0 <= y <= height - 1:
                pts.append((x, y))
    for y in (0.0, height - 1.0):
        if abs(a) > 1e-12:
            x = -(b * y + offset) / a
            if 0 <= x <= width - 1:
                pts.append((x, y))
    if len(pts) < 2:
        return np.full((2, 2), np.nan)
    pts = np.array(pts)
    far = np.argmax(((pts[:, None] - pts[None]) ** 2).sum(-1).reshape(-1))
    return pts[[far // len(pts), far % len(pts)]]


def _inliers(corners: np.ndarray, tree: cKDTree, normal: np.ndarray, offset: float, threshold: float):
    moved = corners - 2.0 * (corners @ normal + offset)[:, None] * normal
    dist, idx = tree.query(moved)
    return dist < threshold, idx


@on_input_device
def pointsymm_image(
    image: Any,
    *,
    n_corners: int = 200,
    harris_k: float = 0.04,
    ransac_iters: int = 20,
    sample_fraction: float = 0.5,
    inlier_threshold: float = 3.0,
    match_fraction: float = 0.8,
    generator: torch.Generator | None = None,
) -> ImageAxisResult:
    """The reflection symmetry axis of an image from its corner points (thesis Sec. 7.4.4).

    The Harris corners (:func:`harris_corners`) form a 2D point set; corners off the
    symmetric object have no mirror, so PointSymm (:func:`point_symm`, with the cardinality
    limit ``match_fraction``) runs inside RANSAC: each iteration fits a random subset of
    ``sample_fraction`` of the corners, and counts the corners whose reflection lands within
    ``inlier_threshold`` pixels of a corner; the best axis is refitted on its inliers. The
    axis is read off by Theorem 7.2.3. RANSAC is the global search here, so PointSymm runs
    without its scan of extra starting planes (``n_scan=0``).

    Args:
        image: ``(H, W)``, ``(C, H, W)`` or ``(1, C, H, W)`` image (integer images are scaled).
        n_corners: largest number of Harris corners used.
        harris_k: the Harris detector's ``k``.
        ransac_iters: RANSAC iterations.
        sample_fraction: fraction of the corners in each RANSAC sample.
        inlier_threshold: largest distance in pixels from a reflected corner to its mirror.
        match_fraction: PointSymm's cardinality limit inside each sample (Sec. 7.4.4).
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        :class:`ImageAxisResult`.

    Raises:
        InputShapeError: not a single image.
        InputValueError: fewer than 4 corners found, or a bad setting.
    """
    _check_settings(n_corners, harris_k, ransac_iters, sample_fraction, inlier_threshold, match_fraction)
    img = check_image(image, "image", min_size=3)
    corners_t = harris_corners(img, n_corners, harris_k).cpu()  # (K, 2): Harris on the image's device
    k = corners_t.shape[0]
    if k < 4:
        raise InputValueError(f"image: expected at least 4 Harris corners, found {k}")
    g = make_generator(generator)
    corners = corners_t.double().numpy()
    tree = cKDTree(corners)
    m = max(4, round(sample_fraction * k))
    best = None
    for _ in range(ransac_iters):
        subset = random_subset(k, m, generator=g)
        # RANSAC is this path's global search: no plane scan inside each sample (n_scan=0)
        res = point_symm(corners_t.double()[subset], match_fraction=match_fraction, n_scan=0, generator=g)
        nrm, off = res.normal.numpy(), float(res.offset)
        inl, _ = _inliers(corners, tree, nrm, off, inlier_threshold)
        if best is None or inl.sum() > best[0].sum():
            best = (inl, nrm, off)
    inl, nrm, off = best
    if inl.sum() >= 2:
        refit = point_symm(corners_t.double()[torch.from_numpy(inl)], n_scan=0, generator=g)
        r_inl, _ = _inliers(corners, tree, refit.normal.numpy(), float(refit.offset), inlier_threshold)
        if r_inl.sum() >= inl.sum():
            nrm, off = refit.normal.numpy(), float(refit.offset)
    inl, idx = _inliers(corners, tree, nrm, off, inlier_threshold)
    perm = np.where(inl, idx, -1)
    h, w = img.shape[-2:]
    dtype = img.dtype
    return ImageAxisResult(
        normal=torch.as_tensor(nrm, dtype=dtype),
        offset=torch.as_tensor(off, dtype=dtype),
        segment=torch.as_tensor(_segment(nrm, off, w, h), dtype=dtype),
        corners=corners_t,
        inliers=torch.from_numpy(inl),
        permutation=torch.as_tensor(perm, dtype=torch.int64),
        score=float(inl.mean()),
        iterations=ransac_iters,
    )


def _check_settings(n_corners, harris_k, ransac_iters, sample_fraction, inlier_threshold, match_fraction) -> None:
    check_int(n_corners, "n_corners", minimum=4)
    check_positive(harris_k, "harris_k")
    check_int(ransac_iters, "ransac_iters", minimum=1)
    check_positive(sample_fraction, "sample_fraction")
    check_in_range(sample_fraction, "sample_fraction", 0.0, 1.0)
    check_positive(inlier_threshold, "inlier_threshold")
    check_positive(match_fraction, "match_fraction")
    check_in_range(match_fraction, "match_fraction", 0.0, 1.0)


@register_solver("pointsymm_image", kind="image")
class PointSymmImage(nn.Module):
    """Symmetry axis of an image from its Harris corners, PointSymm inside RANSAC (Sec. 7.4.4).

    Module form of :func:`pointsymm_image`; ``seed`` seeds the generator used when
    ``forward`` is called without one. ``forward`` takes an image and returns an
    :class:`ImageAxisResult`.
    """

    def __init__(
        self,
        *,
        n_corners: int = 200,
        harris_k: float = 0.04,
        ransac_iters: int = 20,
        sample_fraction: float = 0.5,
        inlier_threshold: float = 3.0,
        match_fraction: float = 0.8,
        seed: int = DEFAULT_SEED,
    ) -> None:
        super().__init__()
        _check_settings(n_corners, harris_k, ransac_iters, sample_fraction, inlier_threshold, match_fraction)
        self.n_corners, self.harris_k, self.ransac_iters = n_corners, harris_k, ransac_iters
        self.sample_fraction, self.inlier_threshold, self.match_fraction = sample_fraction, inlier_threshold, match_fraction
        self.seed = check_int(seed, "seed")

    def settings(self) -> dict[str, Any]:
        """The keyword settings passed to :func:`pointsymm_image`."""
        return {
            "n_corners": self.n_corners,
            "harris_k": self.harris_k,
            "ransac_iters": self.ransac_iters,
            "sample_fraction": self.sample_fraction,
            "inlier_threshold": self.inlier_threshold,
            "match_fraction": self.match_fraction,
        }

    def forward(self, image: Any, generator: torch.Generator | None = None) -> ImageAxisResult:
        gen = make_generator(self.seed) if generator is None else generator
        return pointsymm_image(image, generator=gen, **self.settings())

    def extra_repr(self) -> str:
        return ", ".join(f"{k}={v!r}" for k, v in {**self.settings(), "seed": self.seed}.items())
