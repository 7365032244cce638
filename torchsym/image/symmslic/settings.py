"""Settings of SymmSLIC (thesis Sec. 4.2)."""

from __future__ import annotations

import dataclasses
from typing import Literal

from torchsym.core.settings import Settings, group, setting
from torchsym.image.axes.settings import AxisStageSettings

__all__ = ["MirrorPairSettings", "SymmSlicSettings"]


@dataclasses.dataclass(frozen=True)
class MirrorPairSettings(Settings):
    """Mirror pixel pairs from boundary curves and a Hough vote of their axes (Sec. 4.2.1)."""

    curve_length: float = setting(64.0, "length p of the curve centred on each edge pixel", unit="px", low=4.0)
    n_curve_samples: int = setting(9, "points sampled along each curve", low=3)
    stride: float = setting(2.0, "arc length between consecutive edge pixels used", unit="px", low=0.5)
    n_partners: int = setting(200, "random partners h per edge pixel", low=1)
    sigma: float = setting(24.0, "width of the pair weight exp(-(o + o') / 4 sigma^2)", unit="px", low=0.0, low_open=True)
    eps: float = setting(0.2, "gradient consistency threshold of Eq. 4.5", low=0.0, low_open=True, high=1.0, high_open=True)
    angle_bin: float = setting(1.0, "Hough bin of the axis angle", unit="deg", low=0.1, high=10.0)
    rho_bin: float = setting(2.0, "Hough bin of the axis offset", unit="px", low=0.5)
    max_axes: int = setting(3, "most symmetry axes (clusters) kept", low=1)
    min_vote_share: float = setting(0.35, "an axis needs this share of the strongest axis's votes", low=0.0, high=1.0)
    min_pairs: int = setting(20, "least pairs for an axis to be kept", low=1)
    min_support: float = setting(
        0.4, "least share of the edge pixels around an axis's pairs that have a mirror edge pixel (within 1.5 px) for the axis to be kept", low=0.0, high=1.0
    )
    edge_sigma: float = setting(2.0, "Gaussian smoothing of the edge detector", unit="px", low=0.5, high=8.0)
    min_edge_length: int = setting(20, "shortest boundary chain kept", unit="px", low=4)


@dataclasses.dataclass(frozen=True)
class SymmSlicSettings(Settings):
    """Symmetry-aware SLIC superpixels (thesis Sec. 4.2, Algorithm 4)."""

    n_superpixels: int = setting(500, "superpixels asked for (k)", low=1)
    compactness: float = setting(
        10.0, "SLIC's compactness m, as OpenCV's ruler (colour in OpenCV's 8-bit Lab); the thesis's lambda, 1 to 40", low=0.0, low_open=True
    )
    max_iters: int = setting(10, "k-means iterations", low=1)
    tol_shift: float = setting(
        1.5, "stop before max_iters once the centres move less than this on average between iterations (SLIC's residual error, L1; the thesis: till convergence)", unit="px", low=0.0
    )
    axes_from: Literal["stage", "pairs"] = setting(
        "stage", "stage: the axes the axis stage accepts (torchsym.image.axes); pairs: the thesis's Hough vote of its "
        "mirror pixel pairs (Sec. 4.2.1)")
    axes: AxisStageSettings = group(AxisStageSettings, "the axis stage read with axes_from: stage (torchsym.image.axes)")
    pairs: MirrorPairSettings = group(MirrorPairSettings)
    min_mirror_correlation: float = setting(
        0.8,
        "the symmetric region grows from the hull of an axis's pairs through pixels whose neighbourhood (Gaussian 4 px) correlates with the mirror image's at least this much; 1: the hull only",
        low=-1.0,
        high=1.0,
    )
    min_size_share: float = setting(0.25, "fragments smaller than this share of the mean superpixel are merged", low=0.0, high=1.0)
    seed: int = setting(0, "seed of the module's generator", low=0)
