"""Reflection symmetry in photographs (thesis Ch. 2-4)."""

from torchsym.image.axes import AxisStage, AxisStageSettings, image_axes
from torchsym.image.boundary_cliques import BoundaryCliqueDetector, BoundaryCliquesSettings, boundary_clique_axes
from torchsym.image.ksymmetry import KSymmetryDetector, KSymmetrySettings, ksymmetry_axes
from torchsym.image.results import ReflectionAxesBatch, ReflectionAxesResult
from torchsym.image.symmslic import SymmSlic, SymmSlicResult, symm_slic
from torchsym.image.pointsymm_axis import ImageAxisResult, PointSymmImage, PointSymmImageSettings, point_symm_image
from torchsym.image.symmetry_map import StylizeSolver, SymmetryMapResult, SymmetryMapSolver, stylize, symmetry_map

__all__: list[str] = [
    "AxisStage",
    "AxisStageSettings",
    "image_axes",
    "BoundaryCliqueDetector",
    "BoundaryCliquesSettings",
    "KSymmetryDetector",
    "KSymmetrySettings",
    "ReflectionAxesBatch",
    "ReflectionAxesResult",
    "SymmSlic",
    "SymmSlicResult",
    "boundary_clique_axes",
    "ksymmetry_axes",
    "symm_slic",
    "ImageAxisResult",
    "PointSymmImage",
    "PointSymmImageSettings",
    "point_symm_image",
    "StylizeSolver",
    "SymmetryMapResult",
    "SymmetryMapSolver",
    "stylize",
    "symmetry_map",
]
from torchsym.image.targets import axis_heatmap, orientation_bins, orientation_labels, segment_distance  # noqa: E402

__all__ += ["axis_heatmap", "orientation_bins", "orientation_labels", "segment_distance"]
