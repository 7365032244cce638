"""The dense reflection symmetry map of an image and symmetry-preserving stylization (thesis Ch. 3)."""

from torchsym.image.symmetry_map.estimate import SymmetryMapSolver, symmetry_map
from torchsym.image.symmetry_map.result import StylizedResult, SymmetryMapResult
from torchsym.image.symmetry_map.settings import StylizeSettings, SymmetryMapSettings
from torchsym.image.symmetry_map.stylize import StylizeSolver, stylize

__all__ = [
    "StylizedResult",
    "StylizeSettings",
    "StylizeSolver",
    "SymmetryMapResult",
    "SymmetryMapSettings",
    "SymmetryMapSolver",
    "stylize",
    "symmetry_map",
]
