"""PointSymm on images: the symmetry axis of the Harris corners, with RANSAC (thesis Sec. 7.4.4)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.core.checks import check_image
from torchsym.core.random import make_generator, numpy_rng, random_subset
from torchsym.core.registry import register_solver
from torchsym.core.results import on_input_device
from torchsym.core.settings import Solver, resolve_settings
from torchsym.errors import InputValueError
from torchsym.features.harris import harris_corners
from torchsym.image.lines import clip_line_to_image
from torchsym.image.pointsymm_axis.result import ImageAxisResult
from torchsym.image.pointsymm_axis.settings import PointSymmImageSettings
from torchsym.pointset import PointSymmSettings, point_symm
from torchsym.pointset.score import symmetry_score

__all__ = ["PointSymmImage", "point_symm_image"]

#: smallest image side accepted, in pixels (as the other image solvers)
MIN_SIDE = 32


def _segment(normal: np.ndarray, offset: float, width: int, height: int) -> np.ndarray:
    """``(2, 2)`` end points ``(x, y)`` of the line clipped to the image
    (:func:`~torchsym.image.lines.clip_line_to_image`), NaN if it misses."""
    seg = clip_line_to_image(np.array([normal[0], normal[1], offset]), -1e12, 1e12, width, height)
    return np.full((2, 2), np.nan) if seg is None else np.asarray(seg, dtype=np.float64).reshape(2, 2)


def _reflect(corners: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """``(K, 2)`` the corners reflected in the axis ``normal . p + offset = 0``."""
    return corners - 2.0 * (corners @ normal + offset)[:, None] * normal


def _inliers(corners: np.ndarray, tree: cKDTree, normal: np.ndarray, offset: float, threshold: float):
    """Corners whose reflection lands within ``threshold`` px of a corner, and that corner."""
    dist, idx = tree.query(_reflect(corners, normal, offset))
    return dist < threshold, idx


def _ransac(corners: np.ndarray, tree: cKDTree, settings: PointSymmImageSettings, g: torch.Generator):
    """The axis ``(inliers (K,), normal (2,), offset)`` with most inliers over the RANSAC samples
    of the corners ``(K, 2)``."""
    k = corners.shape[0]
    ransac = settings.ransac
    m = max(4, round(ransac.sample_fraction * k))
    # RANSAC is this path's global search: no plane scan inside each sample
    sample_settings = PointSymmSettings(match_fraction=settings.match_fraction, scan={"enabled": False})
    best = None
    for _ in range(ransac.n_iters):
        subset = random_subset(k, m, generator=g)
        res = point_symm(torch.from_numpy(corners)[subset], sample_settings, generator=g)
        nrm, off = res.normal.numpy(), float(res.offset)
        inl, _ = _inliers(corners, tree, nrm, off, ransac.inlier_threshold)
        if best is None or inl.sum() > best[0].sum():
            best = (inl, nrm, off)
    return best


def _refit(corners: np.ndarray, tree: cKDTree, best, threshold: float, g: torch.Generator):
    """The best axis refitted on its inliers when that keeps at least as many."""
    inl, nrm, off = best
    if inl.sum() >= 2:
        refit = point_symm(torch.from_numpy(corners)[torch.from_numpy(inl)], scan={"enabled": False}, generator=g)
        r_inl, _ = _inliers(corners, tree, refit.normal.numpy(), float(refit.offset), threshold)
        if r_inl.sum() >= inl.sum():
            nrm, off = refit.normal.numpy(), float(refit.offset)
    return nrm, off


@on_input_device
def point_symm_image(
    image: Any,
    settings: PointSymmImageSettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> ImageAxisResult:
    """The reflection symmetry axis of an image from its corner points (thesis Sec. 7.4.4).

    1. the Harris corners (:func:`~torchsym.features.harris_corners`) as a 2-D point set;
    2. RANSAC: PointSymm (:func:`~torchsym.pointset.point_symm`, cardinality limit
       ``match_fraction``, no scan) on random samples of the corners, each axis scored by
       the corners whose reflection lands within ``inlier_threshold`` px of a corner;
    3. the best axis refitted on its inliers; the axis by Theorem 7.2.3.

    Args:
        image: ``(H, W)``, ``(C, H, W)`` or ``(1, C, H, W)`` image, sides >= 32 px (integer
            images are scaled).
        settings: :class:`PointSymmImageSettings`, a mapping, or None for the defaults;
            ``**overrides`` replace single settings (``ransac={"n_iters": 5}``).
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        :class:`ImageAxisResult`, on the image's device.

    Raises:
        InputShapeError: not a single image, or a side under 32 px.
        InputValueError: fewer than 4 corners found.
        ConfigError: a bad setting.
    """
    img = check_image(image, "image", min_size=MIN_SIDE)
    settings = resolve_settings(PointSymmImageSettings, settings, overrides)
    corners_t = harris_corners(img, settings.harris.max_corners, settings.harris.k).cpu()  # step 1: (K, 2), Harris on the image's device
    k = corners_t.shape[0]
    if k < 4:
        raise InputValueError(f"image: expected at least 4 Harris corners, found {k}")
    g = make_generator(generator)
    corners = corners_t.double().numpy()  # (K, 2)
    tree = cKDTree(corners)
    best = _ransac(corners, tree, settings, g)  # step 2
    nrm, off = _refit(corners, tree, best, settings.ransac.inlier_threshold, g)  # step 3
    inl, idx = _inliers(corners, tree, nrm, off, settings.ransac.inlier_threshold)
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
        score=symmetry_score(corners, _reflect(corners, nrm, off), perm, numpy_rng(g), tree=tree),
        iterations=settings.ransac.n_iters,
    )


@register_solver("pointsymm_image", kind="image")
class PointSymmImage(Solver):
    """Symmetry axis of an image from its Harris corners, PointSymm inside RANSAC (Sec. 7.4.4).

    Module form of :func:`point_symm_image`; ``forward(image, generator=None)`` returns an
    :class:`ImageAxisResult`.
    """

    settings_class = PointSymmImageSettings

    def forward(self, image: Any, generator: torch.Generator | None = None) -> ImageAxisResult:
        gen = generator if generator is not None else make_generator(self.settings.seed)
        return point_symm_image(image, self.settings, generator=gen)
