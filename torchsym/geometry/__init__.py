"""Reflection geometry in d dimensions, batched and differentiable, and the triangle mesh type."""

from torchsym.geometry.mesh import Mesh

from torchsym.geometry.reflection import (
    angles_to_normal,
    canonical_sign,
    normal_to_angles,
    plane_angle,
    plane_distance,
    plane_from_pairs,
    plane_from_reflection,
    point_plane_distance,
    reflect_points,
    reflection_matrix,
    reflection_matrix_from_angles,
    reflection_transform,
    spread_normals,
    tangent_basis,
)
from torchsym.geometry.sampling import sphere_normals

__all__ = [
    "Mesh",
    "angles_to_normal",
    "canonical_sign",
    "normal_to_angles",
    "plane_angle",
    "plane_distance",
    "plane_from_pairs",
    "plane_from_reflection",
    "point_plane_distance",
    "reflect_points",
    "reflection_matrix",
    "reflection_matrix_from_angles",
    "reflection_transform",
    "sphere_normals",
    "spread_normals",
    "tangent_basis",
]
