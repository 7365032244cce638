"""Reflection symmetry in photographs (thesis Ch. 2-4)."""

from torchsym.image.axes import ReflectionAxesBatch, ReflectionAxesResult
from torchsym.image.boundary_cliques import BoundaryCliqueDetector, boundary_clique_axes
from torchsym.image.ksymmetry import KSymmetryDetector, ksymmetry_axes
from torchsym.image.symmetry_map import StylizeSolver, SymmetryMapResult, SymmetryMapSolver, stylize, symmetry_map

__all__: list[str] = [
    "BoundaryCliqueDetector",
    "KSymmetryDetector",
    "ReflectionAxesBatch",
    "ReflectionAxesResult",
    "boundary_clique_axes",
    "ksymmetry_axes",
    "StylizeSolver",
    "SymmetryMapResult",
    "SymmetryMapSolver",
    "stylize",
    "symmetry_map",
]
