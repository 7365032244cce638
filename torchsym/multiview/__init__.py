"""Hidden 3D reflection symmetry of a scene from several photos (thesis Sec. 5.3)."""

from torchsym.multiview.pairs import best_buddy_pairs
from torchsym.multiview.plane import consensus_plane, inlier_table, pair_planes
from torchsym.multiview.reconstruct import SparseModel, reconstruct
from torchsym.multiview.result import Cameras, MultiviewPlaneResult
from torchsym.multiview.settings import MultiviewPlaneSettings
from torchsym.multiview.solver import MultiviewPlaneDetector, detect_multiview_plane, plane_of_model
from torchsym.multiview.views import Views, as_views

__all__ = [
    "Cameras",
    "MultiviewPlaneDetector",
    "MultiviewPlaneResult",
    "MultiviewPlaneSettings",
    "SparseModel",
    "Views",
    "as_views",
    "best_buddy_pairs",
    "consensus_plane",
    "detect_multiview_plane",
    "inlier_table",
    "pair_planes",
    "plane_of_model",
    "reconstruct",
]
