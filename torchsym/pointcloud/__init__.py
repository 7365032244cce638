"""Reflection symmetry of 3D point clouds (thesis Ch. 5)."""

from torchsym.pointcloud.reflection_plane import (
    ReflectionPlaneDetector,
    ReflectionPlaneResult,
    ReflectionPlaneSettings,
    detect_reflection_plane,
)
from torchsym.pointcloud.synthetic import (
    SymmetricCloud,
    add_outliers,
    mirror_complete,
    perturb,
    planted_symmetric_cloud,
    random_rigid_motion,
    remove_part,
    sample_surface,
)

__all__ = [
    "ReflectionPlaneDetector",
    "ReflectionPlaneResult",
    "ReflectionPlaneSettings",
    "SymmetricCloud",
    "add_outliers",
    "detect_reflection_plane",
    "mirror_complete",
    "perturb",
    "planted_symmetric_cloud",
    "random_rigid_motion",
    "remove_part",
    "sample_surface",
]
