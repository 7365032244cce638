"""Reflection symmetry of d-dimensional point sets (thesis Ch. 7)."""

from torchsym.pointset.settings import PointSymmSettings
from torchsym.pointset.solver import PointSymm, PointSymmResult, point_symm
from torchsym.pointset.synthetic import SyntheticPointSet, make_symmetric_pointset

__all__ = [
    "PointSymm",
    "PointSymmResult",
    "PointSymmSettings",
    "SyntheticPointSet",
    "make_symmetric_pointset",
    "point_symm",
]
