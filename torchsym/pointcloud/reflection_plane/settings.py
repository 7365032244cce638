"""Settings of the reflection-plane detector (thesis Sec. 5.2), grouped by stage.

``configs/pointcloud_plane_thesis.yaml`` sets them as close to Algorithms 5 and 6 as they
go; the extensions beyond the thesis are described in ``docs/design/reflection_plane.md``.
"""

from __future__ import annotations

import dataclasses
from typing import Literal

from torchsym.core.settings import Settings, group, setting

__all__ = [
    "AlternationSettings",
    "DenseSettings",
    "InitSettings",
    "KernelSettings",
    "PolishSettings",
    "PrealignSettings",
    "RefineSettings",
    "ReflectionPlaneSettings",
    "StartsSettings",
]


@dataclasses.dataclass(frozen=True)
class InitSettings(Settings):
    """Algorithm 5: candidate normals scored on a sample (thesis Sec. 5.2.3)."""

    n_samples: int = setting(500, "points sampled to score the candidate normals (thesis: n2 = 500)", low=4)
    directions: Literal["sphere", "grid"] = setting(
        "sphere", "candidate normals: 'sphere' (near-uniform, beam search) or 'grid' (the thesis's angle grid)"
    )
    n_directions: int = setting(100, "normals scored with directions='sphere'", low=1)
    grid_step: float = setting(20.0, "grid spacing with directions='grid' (thesis: 20)", unit="deg", low=0.0, low_open=True)
    n_beam: int = setting(8, "normals kept in each round of the beam search (directions='sphere')", low=1)


@dataclasses.dataclass(frozen=True)
class StartsSettings(Settings):
    """Which starts are refined on the subsample, in what order, and when to stop."""

    pca: bool = setting(True, "start from the cloud's three principal axes first")
    min_separation: float = setting(10.0, "smallest angle between two starts", unit="deg", low=0.0, high=180.0)
    accept: float = setting(
        0.95, "stop once a start's support reaches this fraction of a perfect symmetry's", low=0.0, high=1.0
    )
    reference_floor: float = setting(0.5, "lower bound of a perfect symmetry's support", low=0.0, high=1.0)
    dominance: float = setting(1.5, "stop once the best support is this many times the median support", low=0.0)
    dominance_gap: float = setting(0.05, "... and this far above it", low=0.0)
    dominance_after: int = setting(6, "... of at least this many starts tried", low=1)
    confirm: bool = setting(
        False, "stop once a start aligns onto the best plane found from an earlier start (mirror images within the inlier tolerance)"
    )


@dataclasses.dataclass(frozen=True)
class RefineSettings(Settings):
    """The subsample on which every start is refined, and the Algorithm 6 fallback there."""

    n_samples: int = setting(3000, "points of the subsample (clouds this small are used whole; the readers' "
                             "20,000,000: every point, as the thesis)", low=4, high=20_000_000)
    fallback_max_iters: int = setting(10, "Algorithm 6 steps per start when no start was accepted", low=1)
    fallback_patience: int = setting(5, "fallback starts in a row without a gain in support before stopping", low=1)


@dataclasses.dataclass(frozen=True)
class PrealignSettings(Settings):
    """Robust point-to-plane Gauss-Newton alignment of each start (an extension)."""

    enabled: bool = setting(True, "pre-align every start (False: Algorithm 6 on the subsample instead)")
    max_iters: int = setting(8, "Gauss-Newton steps per start", low=1)
    tol_angle: float = setting(0.01, "stop when the normal moves less than this", unit="deg", low=0.0)


@dataclasses.dataclass(frozen=True)
class AlternationSettings(Settings):
    """Algorithm 6's alternating steps, on the subsample and in the polish."""

    update: Literal["reflection", "procrustes"] = setting(
        "reflection", "'reflection': exact least-squares I - 2nn^T; 'procrustes': the thesis's SVD step"
    )
    accelerate: bool = setting(True, "extrapolate steps while the progress residual falls (False: the thesis)")
    max_iters: int = setting(100, "alternation steps per run", low=1)
    tol_angle: float = setting(1e-3, "converged when the normal moves less than this (thesis: 0.001)", unit="deg", low=0.0)
    tol_offset: float = setting(1e-3, "... and the offset less than this (thesis: 0.001)", unit="x diagonal", low=0.0)
    patience: int = setting(5, "steps without a lower progress residual before stopping", low=1)


@dataclasses.dataclass(frozen=True)
class PolishSettings(Settings):
    """The winning start refined against the whole cloud: Algorithm 6 on a cloud no larger
    than the subsample (thesis Sec. 5.2.3); Gauss-Newton steps to its surface, coarse to
    fine, on a larger one (an extension)."""

    enabled: bool = setting(True, "run the polish (else the subsample's fit is returned)")
    n_queries: int = setting(5000, "points whose mirror images the steps on a larger cloud fit", low=4)
    n_neighbors: int = setting(10, "nearest points whose centroid and local plane a mirror image is matched to", low=3)
    max_iters: int = setting(8, "Gauss-Newton steps on a larger cloud", low=1)
    tol_se: float = setting(
        1.0, "... until the normal moves less than this many standard errors of the step's fit",
        unit="x standard error", low=0.0,
    )


@dataclasses.dataclass(frozen=True)
class KernelSettings(Settings):
    """Kernel-correlation refinement for perturbed clouds (an extension)."""

    enabled: bool = setting(True, "run the stage when the cloud has no exact mirror pairs and is thick")
    exact_factor: float = setting(0.05, "a mirror is exact within this", unit="x inlier tolerance", low=0.0)
    max_exact_share: float = setting(0.1, "run only when fewer points than this have an exact mirror", low=0.0, high=1.0)
    min_variation: float = setting(0.1, "... and the surface variation is above this", low=0.0)
    width_factor: float = setting(2.0, "kernel width", unit="x median residual", low=0.0, low_open=True)
    n_starts: int = setting(8, "best-supported starts refined besides the polished plane and the axes", low=0)
    n_scan_starts: int = setting(4, "best sphere normals by kernel score refined too", low=0)
    n_neighbors: int = setting(8, "nearest points the kernel sums over", low=1)
    max_iters: int = setting(15, "reweighted steps per start", low=1)
    final_max_iters: int = setting(100, "reweighted steps from the best start", low=1)
    tol_angle: float = setting(0.01, "stop when the normal moves less than this", unit="deg", low=0.0)


@dataclasses.dataclass(frozen=True)
class DenseSettings(Settings):
    """The dense part of the subsample (the sampled surface without scattered outliers)."""

    sparse_factor: float = setting(6.0, "a point is sparse beyond this", unit="x spacing", low=0.0)
    min_sparse_share: float = setting(
        0.15, "use the dense part for the axes and the sample from this share of sparse points", low=0.0, high=1.0
    )
    n_neighbors: int = setting(10, "neighbour whose distance measures the density", low=1)
    quantile: float = setting(0.2, "quantile of those distances the density is compared with", low=0.0, high=1.0)
    factor: float = setting(2.0, "a point is dense within this", unit="x that quantile", low=0.0)


@dataclasses.dataclass(frozen=True)
class ReflectionPlaneSettings(Settings):
    """Settings of :func:`~torchsym.pointcloud.detect_reflection_plane` (thesis Sec. 5.2)."""

    seed: int = setting(0, "seed of the module's generator", low=0)
    n_starts: int = setting(40, "most well-separated starts refined, in rank order (thesis: 1)", low=1)
    inlier_factor: float = setting(
        2.0, "a point is an inlier when its mirror image is this near the cloud", unit="x spacing", low=0.0, low_open=True
    )
    spacing_quantile: float = setting(
        0.1, "quantile of nearest-neighbour distances that sets the search's kernel widths", low=0.0, high=1.0
    )
    tol_se: float = setting(
        0.0,
        "iterative stages (alternation, pre-alignment, kernel) also converge once a step moves the plane less than "
        "this many standard errors of their fit (0, the default: their absolute tolerances alone)",
        unit="x standard error", low=0.0, high=100.0,
    )
    n_chance_planes: int = setting(
        64, "random planes whose highest mirror share is the score's chance level (0: the raw share)", low=0
    )
    init: InitSettings = group(InitSettings)
    starts: StartsSettings = group(StartsSettings)
    refine: RefineSettings = group(RefineSettings)
    prealign: PrealignSettings = group(PrealignSettings)
    alternation: AlternationSettings = group(AlternationSettings)
    polish: PolishSettings = group(PolishSettings)
    kernel: KernelSettings = group(KernelSettings)
    dense: DenseSettings = group(DenseSettings)
