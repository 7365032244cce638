"""Reflection geometry in d dimensions, batched and differentiable, and the triangle mesh type."""

from torchsym.geometry.mesh import Mesh

from torchsym.geometry.reflection import (
    angles_to_normal,
    canonical_sign,
    normal_to_angles,
    pair_fit_errors,
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
    "pair_fit_errors",
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

from torchsym.geometry.cone import sample_cone  # noqa: E402
from torchsym.geometry.conventions import (  # noqa: E402
    check_planes,
    planes_from_nerd,
    planes_from_prsnet,
    planes_to_nerd,
    planes_to_prsnet,
)
from torchsym.geometry.plane_votes import PlaneClusters, cluster_planes, pair_planes, plane_vote_distance  # noqa: E402
from torchsym.geometry.volume import grid_cell_centres, reflect_volume  # noqa: E402

__all__ += [
    "PlaneClusters",
    "check_planes",
    "cluster_planes",
    "grid_cell_centres",
    "pair_planes",
    "planes_from_nerd",
    "planes_from_prsnet",
    "planes_to_nerd",
    "planes_to_prsnet",
    "plane_vote_distance",
    "reflect_volume",
    "sample_cone",
]
