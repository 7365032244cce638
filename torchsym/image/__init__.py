"""Reflection symmetry in photographs (thesis Ch. 2-4)."""

from torchsym.image.boundary_cliques import BoundaryCliqueDetector, BoundaryCliquesSettings, boundary_clique_axes
from torchsym.image.ksymmetry import KSymmetryDetector, KSymmetrySettings, ksymmetry_axes
from torchsym.image.results import ReflectionAxesBatch, ReflectionAxesResult

__all__: list[str] = [
    "BoundaryCliqueDetector",
    "BoundaryCliquesSettings",
    "KSymmetryDetector",
    "KSymmetrySettings",
    "ReflectionAxesBatch",
    "ReflectionAxesResult",
    "boundary_clique_axes",
    "ksymmetry_axes",
]
