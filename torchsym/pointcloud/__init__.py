"""Reflection symmetry of 3D point clouds (thesis Ch. 5)."""

from torchsym.pointcloud.reflection_plane import (
    ReflectionPlaneDetector,
    ReflectionPlaneResult,
    ReflectionPlaneSettings,
    detect_reflection_plane,
)
from torchsym.pointcloud.reflection_planes import (
    ReflectionPlanesDetector,
    ReflectionPlanesResult,
    ReflectionPlanesSettings,
    detect_reflection_planes,
)
from torchsym.pointcloud.reflection_planes.bop import (
    bop_symmetries,
    group_from_bop,
    models_info_entry,
    read_models_info,
    write_models_info,
)
from torchsym.pointcloud.reflection_planes.group import SymmetryGroup, symmetry_group
from torchsym.pointcloud.symmetry import SymmetryDetector, SymmetryResult, SymmetrySettings, detect_symmetry
from torchsym.pointcloud.shapes import box_mesh, boxes_mesh, chair_mesh, cone_mesh, prism_mesh, table_mesh
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
    "ReflectionPlanesDetector",
    "ReflectionPlanesResult",
    "ReflectionPlanesSettings",
    "SymmetricCloud",
    "SymmetryDetector",
    "SymmetryGroup",
    "SymmetryResult",
    "SymmetrySettings",
    "add_outliers",
    "bop_symmetries",
    "box_mesh",
    "boxes_mesh",
    "chair_mesh",
    "cone_mesh",
    "detect_reflection_plane",
    "detect_reflection_planes",
    "detect_symmetry",
    "group_from_bop",
    "mirror_complete",
    "models_info_entry",
    "perturb",
    "planted_symmetric_cloud",
    "prism_mesh",
    "read_models_info",
    "random_rigid_motion",
    "remove_part",
    "sample_surface",
    "symmetry_group",
    "table_mesh",
    "write_models_info",
]
