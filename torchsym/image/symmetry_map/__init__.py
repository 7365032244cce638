"""The dense reflection symmetry map of an image and symmetry-preserving stylization (thesis Ch. 3)."""

from torchsym.image.symmetry_map.estimate import SymmetryMapSolver, symmetry_map
from torchsym.image.symmetry_map.result import StylizedResult, SymmetryMapResult
from torchsym.image.symmetry_map.settings import StylizeSettings, SymmetryMapSettings

__all__ = [
    "StylizedResult",
    "StylizeSettings",
    "SymmetryMapResult",
    "SymmetryMapSettings",
    "SymmetryMapSolver",
    "symmetry_map",
]
