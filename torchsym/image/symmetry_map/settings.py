"""Settings of the dense reflection symmetry map (thesis Ch. 3) and of its stylization (Sec. 3.4)."""

from __future__ import annotations

import dataclasses
from typing import Literal

from torchsym.core.settings import Settings, group, setting
from torchsym.image.axes.settings import AxisStageSettings

__all__ = [
    "CandidateSettings",
    "ClusteringSettings",
    "DescriptorSettings",
    "PatchMatchSettings",
    "ScoreSettings",
    "StylizeSettings",
    "SymmetryMapSettings",
]


@dataclasses.dataclass(frozen=True)
class CandidateSettings(Settings):
    """Candidate mirror pairs: mirrored-SIFT matches of SIFT keypoints (Sec. 3.2.2, "Initialization")."""

    num_features: int = setting(2000, "the most SIFT keypoints", low=2)
    max_distance: float = setting(
        0.3, "a pair's descriptor distance |d_i - m_j| below this (unit RootSIFT descriptors)", low=0.0, high=2.0
    )
    n_matches: int = setting(3, "mirror matches kept per keypoint (nearest first, below max_distance)", low=1)
    min_pair_distance: float = setting(5.0, "keypoints closer than this are not paired", unit="px", low=0.0)


@dataclasses.dataclass(frozen=True)
class ClusteringSettings(Settings):
    """RansaCov clustering of the pairs into axes (Eqs. 3.1-3.2)."""

    eps_d: float = setting(0.03, "Eq. 3.1: min(d1, d2) / max(d1, d2) > 1 - eps_d", low=0.0, high=1.0)
    eps_theta: float = setting(2.0, "Eq. 3.1: chord within this angle of the axis normal", unit="deg", low=0.0, high=90.0)
    tol_px: float = setting(
        1.5, "a pair also agrees when its points' distances to the axis differ by at most this", unit="px", low=0.0
    )
    cover: Literal["greedy", "milp"] = setting("greedy", "maximum coverage: greedy, or the exact integer program (Eq. 3.2)")
    min_support: int = setting(3, "the fewest pairs in a cluster", low=1)
    max_pairs: int = setting(3000, "the most candidate pairs clustered (strongest matches first)", low=2)


@dataclasses.dataclass(frozen=True)
class DescriptorSettings(Settings):
    """Dense descriptors at the cluster's axis orientation (a departure from per-pixel SIFT, see the package docstring)."""

    cell_px: float = setting(4.0, "side of one of the 4 x 4 spatial cells", unit="px", low=1.0, high=64.0)
    n_dims: int = setting(32, "dimensions kept by the mirror-equivariant PCA (128: no reduction)", low=2, high=128)


@dataclasses.dataclass(frozen=True)
class PatchMatchSettings(Settings):
    """Symmetric PatchMatch (Algorithm 3) and its alternatives (Sec. 3.2.2, "Other Schemes")."""

    scheme: Literal["irs", "mmp", "bmp"] = setting(
        "irs", "irs: iterative random search; mmp: mean mirror pixel; bmp: best mirror pixel"
    )
    max_iters: int = setting(6, "IRS iterations", low=1)
    stride: int = setting(2, "the field is searched on every stride-th pixel, elsewhere it follows by symmetry coherency (1: every pixel)", unit="px", low=1)
    neighbours: bool = setting(False, "also propagate from the 4 grid neighbours (PatchMatch's own step; not in Algorithm 3)")
    n_samples: int = setting(15, "random-search samples per pixel and iteration (the thesis's e)", low=0)
    search_radius: float | None = setting(
        None, "random-search radius r; None: the spread of a pixel's reflections through the cluster's pairs", unit="px", low=1.0, high=1e5
    )
    min_gain: float = setting(0.2, "a random-search sample must lower the cost |d_p - m_q|^2 by more than this (thesis: 0)", low=0.0)
    max_bmp_pairs: int = setting(64, "the most cluster pairs whose reflections BMP and MMP use", low=1)


@dataclasses.dataclass(frozen=True)
class ScoreSettings(Settings):
    """The symmetry score, Eqs. 3.7-3.8."""

    sigma_feature: float = setting(0.4, "S = exp(-|d_p - m_q|^2 / sigma_feature^2) ... (thesis: 1)", low=0.0, low_open=True)
    sigma_d: float = setting(
        0.1, "... x exp(-dist(p, I)^2 / ((w^2 + h^2) sigma_d^2)), dist to the cluster's pixels", unit="x diagonal", low=0.0, low_open=True
    )


@dataclasses.dataclass(frozen=True)
class SymmetryMapSettings(Settings):
    """Settings of :func:`~torchsym.image.symmetry_map.symmetry_map` (thesis Ch. 3, Algorithm 3)."""

    n_axes: int | None = setting(None, "symmetry maps (the thesis's k), RansaCov clusters; None: one per axis the axis stage accepts", low=1, high=64)
    max_side: int | None = setting(640, "the image is resized so that its longer side is at most this; None: never", unit="px", low=32)
    axes: AxisStageSettings = group(AxisStageSettings, "the axis stage whose accepted axes the maps are about with n_axes: null (torchsym.image.axes)")
    candidates: CandidateSettings = group(CandidateSettings)
    clustering: ClusteringSettings = group(ClusteringSettings)
    descriptor: DescriptorSettings = group(DescriptorSettings)
    patchmatch: PatchMatchSettings = group(PatchMatchSettings)
    score: ScoreSettings = group(ScoreSettings)
    seed: int = setting(0, "seed of the random initialisation and search", low=0)


@dataclasses.dataclass(frozen=True)
class StylizeSettings(Settings):
    """Settings of :func:`~torchsym.image.symmetry_map.stylize` (thesis Sec. 3.4)."""

    region_px: int = setting(16, "SLIC superpixel side (OpenCV ximgproc region_size)", unit="px", low=4)
    ruler: float = setting(10.0, "SLIC compactness", low=0.0, low_open=True)
    n_slic_iters: int = setting(10, "SLIC iterations", low=1)
    min_score: float = setting(0.35, "merging stops once every region's average score is above this", low=0.0, high=1.0)
