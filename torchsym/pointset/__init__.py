"""Reflection symmetry of d-dimensional point sets (thesis Ch. 7)."""

from torchsym.pointset.image_axis import (
    ImageAxisResult,
    PointSymmImage,
    harris_corners,
    pointsymm_image,
)
from torchsym.pointset.pointsymm import PointSymm, PointSymmResult, point_symm
from torchsym.pointset.synthetic import SyntheticPointSet, make_symmetric_pointset

__all__ = [
    "ImageAxisResult",
    "PointSymm",
    "PointSymmImage",
    "PointSymmResult",
    "SyntheticPointSet",
    "harris_corners",
    "make_symmetric_pointset",
    "point_symm",
    "pointsymm_image",
]
