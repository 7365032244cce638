"""Settings of the every-plane detector (thesis Sec. 5.2, extended to every plane), grouped by stage.

The start search reuses the one-plane detector's groups (``init``, ``starts``, ``refine``,
``dense``); see ``docs/design/reflection_planes.md`` for the choices and their evidence.
"""

from __future__ import annotations

import dataclasses

from torchsym.core.settings import Settings, group, setting
from torchsym.pointcloud.reflection_plane.settings import (
    DenseSettings,
    InitSettings,
    RefineSettings,
    ReflectionPlaneSettings,
    StartsSettings,
)

__all__ = ["AcceptSettings", "AlignSettings", "ReflectionPlanesSettings", "RevolutionSettings"]


@dataclasses.dataclass(frozen=True)
class AlignSettings(Settings):
    """Every start aligned on the subsample, then the distinct planes on the whole cloud."""

    n_queries: int = setting(400, "points whose mirror images align the starts on the subsample", low=4)
    max_iters: int = setting(8, "Gauss-Newton steps per start on the subsample", low=1)
    tol_angle: float = setting(0.01, "stop when no normal moves more than this", unit="deg", low=0.0)
    min_support: float = setting(
        0.6, "planes kept after the subsample: support at least this share of a perfect symmetry's", low=0.0, high=1.0
    )
    polish_queries: int = setting(1500, "points whose mirror images polish the kept planes on the whole cloud", low=4)
    polish_iters: int = setting(4, "Gauss-Newton steps of the polish", low=0)
    n_neighbors: int = setting(10, "nearest points whose centroid and local plane a mirror image is matched to", low=3)


@dataclasses.dataclass(frozen=True)
class AcceptSettings(Settings):
    """The test each plane passes: the distance ratio against the sampling distance of a
    random split of the cloud, and the mirror share against chance planes."""

    max_ratio: float = setting(
        1.6, "accept a plane whose mirror images lie at most this far from the cloud", unit="x sampling distance", low=1.0
    )
    n_queries: int = setting(3000, "points of one half whose distances measure the ratio", low=4)
    local_baseline: bool = setting(
        True, "measure the sampling distance where the mirror images land (uneven density), not over the whole cloud"
    )
    min_score: float = setting(
        0.05, "... and whose mirror share beats the best of the chance planes by this (the score)", low=0.0, high=1.0
    )
    generator_factor: float = setting(
        1.2, "planes within this factor of the least ratio generate new candidates (reflected in each other)", low=1.0
    )
    closure_rounds: int = setting(3, "rounds of planes reflected in accepted planes, tested in turn (0: none)", low=0)
    max_planes: int = setting(64, "most planes the closure adds to the tests", low=1)


@dataclasses.dataclass(frozen=True)
class RevolutionSettings(Settings):
    """Continuous axes: an axis is one when rotations about it by generic angles pass the
    distance test."""

    enabled: bool = setting(True, "look for axes of revolution")
    n_angles: int = setting(3, "generic rotation angles tested about each candidate axis", low=1)
    merge_distance: float = setting(
        0.05, "two axes within 5 degrees are one when this near", unit="x bounding-box diagonal", low=0.0
    )
    eigen_gap: float = setting(
        0.1, "a principal axis is a candidate when the other two variances are this close (relative)", low=0.0
    )


@dataclasses.dataclass(frozen=True)
class ReflectionPlanesSettings(Settings):
    """Settings of :func:`~torchsym.pointcloud.detect_reflection_planes`."""

    seed: int = setting(0, "seed of the module's generator", low=0)
    n_starts: int = setting(24, "most well-separated candidate starts refined, after the principal axes", low=1)
    inlier_factor: float = setting(
        2.0, "a point has a mirror when its mirror image is this near the cloud", unit="x spacing", low=0.0, low_open=True
    )
    spacing_quantile: float = setting(
        0.1, "quantile of nearest-neighbour distances that sets the search's kernel widths", low=0.0, high=1.0
    )
    merge_factor: float = setting(
        5.0, "two planes are one when their mirror images lie this near at the median", unit="x inlier tolerance", low=0.0
    )
    n_chance_planes: int = setting(64, "random planes whose highest mirror share is the score's chance level", low=1)
    init: InitSettings = group(InitSettings)
    starts: StartsSettings = group(StartsSettings)
    refine: RefineSettings = group(RefineSettings)
    dense: DenseSettings = group(DenseSettings)
    align: AlignSettings = group(AlignSettings)
    accept: AcceptSettings = group(AcceptSettings)
    revolution: RevolutionSettings = group(RevolutionSettings)

    def one_plane(self) -> ReflectionPlaneSettings:
        """The one-plane detector's settings whose stages the start search reuses."""
        return ReflectionPlaneSettings(
            seed=self.seed, n_starts=self.n_starts, inlier_factor=self.inlier_factor,
            spacing_quantile=self.spacing_quantile, n_chance_planes=self.n_chance_planes,
            init=self.init, starts=self.starts, refine=self.refine, dense=self.dense,
        )
