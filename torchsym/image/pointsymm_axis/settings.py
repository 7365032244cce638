"""Settings of PointSymm on images (thesis Sec. 7.4.4)."""

from __future__ import annotations

import dataclasses

from torchsym.core.random import DEFAULT_SEED
from torchsym.core.settings import Settings, group, setting

__all__ = ["HarrisSettings", "PointSymmImageSettings", "RansacSettings"]


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
