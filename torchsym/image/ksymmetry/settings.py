"""Settings of the k-symmetry axis detector (thesis Sec. 2.2)."""

from __future__ import annotations

import dataclasses
from typing import Literal

from torchsym.core.settings import Settings, group, setting
from torchsym.features.sift import SIFT_MIN_SIDE
from torchsym.image.batching import check_sides

__all__ = ["Clustering", "KSymmetrySettings", "MirrorPairs"]


@dataclasses.dataclass(frozen=True)
class MirrorPairs(Settings):
    """Mirror symmetric pixel pairs from SIFT and mirrored SIFT (Sec. 2.2.1)."""

    max_keypoints: int = setting(1000, "the most SIFT keypoints", low=1)
    k1: int | None = setting(None, "neighbours of the mutual nearest-neighbour rule (Def. 2.2.1); null: at the elbow", low=1, high=1000)
    min_distance: float = setting(5.0, "keypoints closer than this are not paired", unit="px", low=0.0)
    backend: Literal["kornia", "opencv"] = setting("opencv", "SIFT's implementation: opencv (CPU, fast) or kornia (any device)")


@dataclasses.dataclass(frozen=True)
class Clustering(Settings):
    """Algorithm 1 (k-symmetry clustering, cost Eq. 2.5)."""

    max_iters: int = setting(50, "assignment/update rounds at most", low=1)
    outlier_cost: float | None = setting(
        0.0025, "truncation of a pair's cost in coordinates scaled by half the longer side; null: Eq. 2.5 untruncated",
        low=0.0, low_open=True,
    )


@dataclasses.dataclass(frozen=True)
class KSymmetrySettings(Settings):
    """Settings of :func:`~torchsym.image.ksymmetry.ksymmetry_axes`."""

    pairs: MirrorPairs = group(MirrorPairs)
    max_axes: int = setting(5, "the largest k tried; k is the elbow of the cost curve", low=1)
    eps_theta: float = setting(2.0, "angle tolerance of the inlier test (Sec. 2.2.3)", unit="deg", low=0.0, high=90.0, low_open=True)
    eps_d: float = setting(0.05, "distance-ratio tolerance of the inlier test (Sec. 2.2.3)", low=0.0, low_open=True)
    clustering: Clustering = group(Clustering)
    min_support: int = setting(3, "axes supported by fewer pairs are dropped", low=1)
    score: Literal["support", "gradient"] = setting(
        "gradient", "gradient: runs checked by mirrored gradients; support: share of the pairs (thesis)"
    )
    grow_threshold: float | None = setting(
        0.3, "with score gradient: local symmetry above which a segment grows; null: no growth", low=-1.0, high=1.0
    )
    max_side: int | None = setting(640, "longest side an image is detected at (a scaled copy beyond); null: full size",
                                   unit="px", low=SIFT_MIN_SIDE)
    min_side: int | None = setting(None, "longest side below which an image is detected on a scaled-up copy; null: "
                                   "native size", unit="px", low=SIFT_MIN_SIDE, high=8192)

    def check(self) -> None:
        check_sides(self.min_side, self.max_side)
