"""Triangle meshes: the mesh type, its checks and operators, and intrinsic symmetry (thesis Ch. 6)."""

from torchsym.mesh.correction import (
    CorrectionResult,
    correct_eigenfunctions,
    correction_cost,
)
from torchsym.mesh.geodesic import (
    geodesic_distances,
    shortest_paths,
    split_fans,
    surface_geodesic_lengths,
    thin_points,
)
from torchsym.mesh.hks import heat_kernel_signature, hks_feature_points, hks_times
from torchsym.mesh.fmaps import (
    functional_to_pointwise,
    map_consistency,
    map_quality,
    nearest_involution,
    pointwise_to_functional,
    zoomout,
)
from torchsym.mesh.intrinsic import (
    IntrinsicSymmetry,
    IntrinsicSymmetryResult,
    IntrinsicSymmetrySettings,
    intrinsic_symmetry,
)
from torchsym.geometry.mesh import Mesh
from torchsym.mesh.operators import (
    adjacency_matrix,
    consistently_wound,
    cotangent_laplacian,
    edge_graph,
    face_areas,
    laplacian_eigen,
    mass_matrix,
    ring_neighbourhood,
)
from torchsym.mesh.orientation import (
    anticommutation_penalty,
    descriptor_operators,
    orientation_operators,
    orientation_reversal,
    orientation_reversing_map,
    reduce_descriptors,
    resolvent_mask,
)
from torchsym.mesh.pairs import eigenfunction_signs, pair_affinity, symmetric_pairs
from torchsym.mesh.repair import HoleFilling, boundary_loops, close_holes
from torchsym.mesh.validate import ValidatedMesh, validate_mesh

__all__ = [
    "CorrectionResult",
    "HoleFilling",
    "IntrinsicSymmetry",
    "IntrinsicSymmetryResult",
    "IntrinsicSymmetrySettings",
    "Mesh",
    "ValidatedMesh",
    "adjacency_matrix",
    "anticommutation_penalty",
    "boundary_loops",
    "close_holes",
    "consistently_wound",
    "correct_eigenfunctions",
    "correction_cost",
    "cotangent_laplacian",
    "descriptor_operators",
    "edge_graph",
    "eigenfunction_signs",
    "face_areas",
    "functional_to_pointwise",
    "geodesic_distances",
    "heat_kernel_signature",
    "hks_feature_points",
    "hks_times",
    "intrinsic_symmetry",
    "laplacian_eigen",
    "map_consistency",
    "map_quality",
    "mass_matrix",
    "nearest_involution",
    "orientation_operators",
    "orientation_reversal",
    "orientation_reversing_map",
    "pair_affinity",
    "pointwise_to_functional",
    "reduce_descriptors",
    "resolvent_mask",
    "ring_neighbourhood",
    "shortest_paths",
    "split_fans",
    "surface_geodesic_lengths",
    "symmetric_pairs",
    "thin_points",
    "validate_mesh",
    "zoomout",
]
