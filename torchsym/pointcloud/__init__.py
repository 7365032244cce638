"""Reflection symmetry of 3D point clouds (thesis Ch. 5)."""

from torchsym.pointcloud.reflection_plane import (
    ReflectionPlaneDetector,
    ReflectionPlaneResult,
    detect_reflection_plane,
    sphere_normals,
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
    "SymmetricCloud",
    "add_outliers",
    "detect_reflection_plane",
    "mirror_complete",
    "perturb",
    "planted_symmetric_cloud",
    "random_rigid_motion",
    "remove_part",
    "sample_surface",
    "sphere_normals",
]
