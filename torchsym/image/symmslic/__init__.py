"""SymmSLIC superpixels and unsupervised symmetric-object segmentation (thesis Ch. 4)."""

from torchsym.image.symmslic.pairs import MirrorPixelPairs, mirror_pixel_pairs
from torchsym.image.symmslic.result import SymmSlicResult
from torchsym.image.symmslic.settings import MirrorPairSettings, SymmSlicSettings
from torchsym.image.symmslic.region import mirror_correlation_map, symmetric_region
from torchsym.image.symmslic.solver import SymmSlic, symm_slic

__all__ = [
    "MirrorPairSettings",
    "MirrorPixelPairs",
    "SymmSlic",
    "SymmSlicResult",
    "SymmSlicSettings",
    "mirror_correlation_map",
    "mirror_pixel_pairs",
    "symm_slic",
    "symmetric_region",
]
