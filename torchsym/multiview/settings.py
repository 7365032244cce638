"""Settings of the multi-view plane detector (thesis Sec. 5.3)."""

from __future__ import annotations

import dataclasses

from torchsym.core.settings import Settings, group, setting

__all__ = ["ConsensusSettings", "MultiviewPlaneSettings", "PairSettings", "ReconstructionSettings"]


@dataclasses.dataclass(frozen=True)
class ReconstructionSettings(Settings):
    """Sparse structure from motion by COLMAP (Sec. 5.3.1)."""

    max_image_side: int = setting(1600, "photos are scaled so that their longer side is at most this", unit="px", low=64)
    max_features: int = setting(8192, "most SIFT features kept per photo", low=16)
    single_camera: bool = setting(True, "all photos share one camera's intrinsics")
    n_extraction_threads: int = setting(2, "threads for SIFT extraction (any count gives the same bits; 1 without single_camera)", low=1)
    n_threads: int = setting(1, "threads for COLMAP's matching and mapping (bit-reproducible with 1 only)", low=1)


@dataclasses.dataclass(frozen=True)
class PairSettings(Settings):
    """Mirror symmetric point pairs (MSPP) as best buddies of mirrored SIFT (Sec. 5.3.2)."""

    min_chord: float = setting(
        1e-3, "pairs whose points lie closer than this are dropped (COLMAP's duplicate points)", unit="x scene extent", low=0.0
    )


@dataclasses.dataclass(frozen=True)
class ConsensusSettings(Settings):
    """The outlier loop over every pair's plane and the consensus plane (Sec. 5.3.3-5.3.4)."""

    eps_d: float = setting(0.04, "tolerance on the ratio of a pair's two distances to the plane", low=0.0, low_open=True, high=1.0)
    eps_theta: float = setting(1.0, "tolerance on the angle between a pair's chord and the normal", unit="deg", low=0.0, low_open=True, high=90.0)
    margin_angle: float = setting(5.0, "planes at least this far from the winner compete for the confidence", unit="deg", low=0.0, high=90.0)
    min_margin: float = setting(2.0, "least ratio of the winner's inliers to the best competitor's for a symmetry to be reported", low=1.0)
    min_inliers: int = setting(6, "least inlier pairs for a symmetry to be reported", low=2)
    lam: float = setting(0.25, "weight of the chord-normal constraint against the midpoint one (Eq. 5.6)", low=0.0, low_open=True)


@dataclasses.dataclass(frozen=True)
class MultiviewPlaneSettings(Settings):
    """Hidden 3D reflection plane of a scene from several photos (thesis Sec. 5.3)."""

    reconstruction: ReconstructionSettings = group(ReconstructionSettings)
    pairs: PairSettings = group(PairSettings)
    consensus: ConsensusSettings = group(ConsensusSettings)
    seed: int = setting(0, "seed of COLMAP's random number generator", low=0)
