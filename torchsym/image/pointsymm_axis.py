"""PointSymm on images: the symmetry axis of the Harris corners, with RANSAC (thesis Sec. 7.4.4)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.core.checks import check_image
from torchsym.core.random import DEFAULT_SEED, make_generator, numpy_rng, random_subset
from torchsym.core.registry import register_solver
from torchsym.core.results import Result, on_input_device
from torchsym.core.settings import Settings, Solver, group, resolve_settings, setting
from torchsym.errors import InputValueError
from torchsym.features.harris import harris_corners
from torchsym.pointset import PointSymmSettings, point_symm
from torchsym.pointset.score import symmetry_score

__all__ = ["ImageAxisResult", "PointSymmImage", "PointSymmImageSettings", "point_symm_image"]

#: smallest image side accepted, in pixels (as the other image solvers)
MIN_SIDE = 32


@dataclasses.dataclass(frozen=True)
class HarrisSettings(Settings):
    """The corner points: Harris corners through kornia."""

    max_corners: int = setting(200, "largest number of Harris corners used, strongest first", low=4)
    k: float = setting(0.04, "the Harris detector's k", low=0.0, low_open=True)


@dataclasses.dataclass(frozen=True)
class RansacSettings(Settings):
    """RANSAC over PointSymm fits on random subsets of the corners."""

    n_iters: int = setting(20, "RANSAC iterations (all run)", low=1)
    sample_fraction: float = setting(0.5, "fraction of the corners in each sample", low=0.0, high=1.0, low_open=True)
    inlier_threshold: float = setting(3.0, "largest distance from a reflected corner to its mirror", unit="px", low=0.0, low_open=True)


@dataclasses.dataclass(frozen=True)
class PointSymmImageSettings(Settings):
    """Settings of :func:`point_symm_image` (thesis Sec. 7.4.4)."""

    harris: HarrisSettings = group(HarrisSettings)
    ransac: RansacSettings = group(RansacSettings)
    match_fraction: float = setting(0.8, "PointSymm's cardinality limit inside each sample (Sec. 7.4.4)", low=0.0, high=1.0, low_open=True)
    seed: int = setting(DEFAULT_SEED, "seed of the generator a module uses when called without one", low=0)


@dataclasses.dataclass(frozen=True)
class ImageAxisResult(Result):
    """The reflection symmetry axis of an image found by :func:`point_symm_image`.

    Attributes:
        normal: ``(2,)`` unit normal of the axis ``normal . (x, y) + offset = 0`` in pixel
            coordinates (``x`` the column, ``y`` the row).
        offset: ``()`` offset of the axis.
        segment: ``(2, 2)`` the axis clipped to the image, two ``(x, y)`` end points
            (NaN if the line misses the image).
        corners: ``(K, 2)`` the Harris corners ``(x, y)`` used as the point set.
        inliers: ``(K,)`` bool, corners whose reflection lands near another corner.
        permutation: ``(K,)`` int64, mirror corner of each inlier, -1 elsewhere.
        score: in [0, 1], calibrated against chance
            (:func:`~torchsym.pointset.score.symmetry_score`): ``q``, the mean over the
            corners of ``max(0, 1 - r / min(nn, moved))`` (``r`` the distance from the
            reflected corner to its mirror, inliers only, ``nn`` the distance to the corner's
            nearest other corner, ``moved`` how far the reflection moves it), corrected by
            its mean ``q_0`` under random axes: ``max(0, (q - q_0) / (1 - q_0))``. Noise gives
            dense, evenly spaced corners whose reflections land near some corner by chance;
            this score counts only what the axis does better than chance.
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


def _segment(normal: np.ndarray, offset: float, width: int, height: int) -> np.ndarray:
    """``(2, 2)`` end points ``(x, y)`` of the line clipped to the image, NaN if it misses."""
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
