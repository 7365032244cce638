"""Reflection symmetry in photographs (thesis Ch. 2-4)."""

from torchsym.image.axes import ReflectionAxesBatch, ReflectionAxesResult
from torchsym.image.boundary_cliques import BoundaryCliqueDetector, boundary_clique_axes
from torchsym.image.ksymmetry import KSymmetryDetector, ksymmetry_axes

__all__: list[str] = [
    "BoundaryCliqueDetector",
    "KSymmetryDetector",
    "ReflectionAxesBatch",
    "ReflectionAxesResult",
    "boundary_clique_axes",
    "ksymmetry_axes",
]
from torchsym.image.targets import axis_heatmap, orientation_bins, orientation_labels, segment_distance  # noqa: E402

__all__ += ["axis_heatmap", "orientation_bins", "orientation_labels", "segment_distance"]
