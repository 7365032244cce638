"""PointSymm on images: the symmetry axis of the Harris corners, with RANSAC (thesis Sec. 7.4.4)."""

from torchsym.image.pointsymm_axis.detect import MIN_SIDE, PointSymmImage, point_symm_image
from torchsym.image.pointsymm_axis.result import ImageAxisResult
from torchsym.image.pointsymm_axis.settings import HarrisSettings, PointSymmImageSettings, RansacSettings

__all__ = ["HarrisSettings", "ImageAxisResult", "MIN_SIDE", "PointSymmImage", "PointSymmImageSettings", "RansacSettings",
           "point_symm_image"]
