"""Mirror symmetric pixel pairs of an image from SIFT and mirrored SIFT (thesis Sec. 2.2.1)."""

from __future__ import annotations

import torch

from torchsym.core.checks import check_int, check_positive
from torchsym.features.mirror_pairs import choose_k1, mirror_sift_distances, mutual_knn_pairs

__all__ = ["mirror_sift_pairs"]


def mirror_sift_pairs(
    image: torch.Tensor, *, max_keypoints: int = 1000, k1: int | None = None, min_pair_distance: float = 5.0,
    backend: str = "kornia",
) -> tuple[torch.Tensor, int]:
    """Mirror symmetric pixel pairs of an image from SIFT and mirrored SIFT (Sec. 2.2.1).

    Keypoints and descriptors by :func:`~torchsym.features.sift.detect_sift`, mirrored
    descriptors by the exact bin permutation, and pairs by mutual ``k1`` nearest neighbours
    (Def. 2.2.1), ``k1`` at the elbow of the pair count when None.

    Args:
        image: ``(C, H, W)`` or ``(1, C, H, W)`` float image in [0, 1].
        max_keypoints: the most SIFT keypoints (default 1000).
        k1: neighbours in the mutual nearest-neighbour rule; None chooses it.
        min_pair_distance: keypoints closer than this (pixels) are not paired.
        backend: SIFT's (:func:`~torchsym.features.sift.detect_sift`): ``"kornia"`` or ``"opencv"``.

    Returns:
        ``pairs (P, 4)`` float64 ``x1, y1, x2, y2`` in pixels, on the image's device, and
        the ``k1`` used (0 when there were fewer than two keypoints).
    """
    min_pair_distance = check_positive(min_pair_distance, "min_pair_distance", allow_zero=True)
    if k1 is not None:
        k1 = check_int(k1, "k1", minimum=1)
    feats, dist = mirror_sift_distances(image, num_features=max_keypoints, min_pair_distance=min_pair_distance, backend=backend)
    if dist is None:
        return torch.zeros(0, 4, dtype=torch.float64, device=feats.points.device), 0
    if k1 is None:
        k1 = choose_k1(dist)
    idx = mutual_knn_pairs(dist, k1)  # (P, 2)
    pts = feats.points.double()
    return torch.cat([pts[idx[:, 0]], pts[idx[:, 1]]], 1), k1
