"""Local features shared by several solvers: SIFT, mirrored SIFT, mirror pairs (thesis Sec. 2.2.1), Harris corners."""

from torchsym.features.harris import harris_corners
from torchsym.features.mirror_pairs import (
    choose_k1,
    elbow_index,
    mirror_distance_matrix,
    mirror_sift_distances,
    mirror_sift_knn,
    mutual_knn_pairs,
    nearest_mirrors,
)
from torchsym.features.sift import (
    SiftFeatures,
    detect_sift,
    mirror_descriptors,
    mirror_permutation,
)

__all__ = [
    "SiftFeatures",
    "choose_k1",
    "detect_sift",
    "elbow_index",
    "harris_corners",
    "mirror_descriptors",
    "mirror_distance_matrix",
    "mirror_permutation",
    "mirror_sift_distances",
    "mirror_sift_knn",
    "mutual_knn_pairs",
    "nearest_mirrors",
]
