"""Candidate mirror pairs: mirrored-SIFT matches of SIFT keypoints (thesis Sec. 3.2.2, "Initialization").

Each keypoint ``p_i`` is paired with the keypoints ``p_j`` whose descriptor is within
``max_distance`` of its mirrored descriptor, ``|d_i - m_j| < max_distance`` (thesis: 0.1),
up to ``n_matches`` of them, nearest first: a pixel may be symmetric about more than one
axis. Descriptors are kornia's RootSIFT (:func:`torchsym.features.sift.detect_sift`) and
the mirrored descriptors the exact bin permutation
(:func:`torchsym.features.sift.mirror_descriptors`); the matching is
:func:`torchsym.features.mirror_sift_knn`. A pair found from both ends is kept once.
"""

from __future__ import annotations

import torch

from torchsym.features.mirror_pairs import mirror_sift_knn
from torchsym.features.sift import SIFT_MIN_SIDE

__all__ = ["mirror_sift_matches"]


def mirror_sift_matches(
    image: torch.Tensor,
    *,
    num_features: int = 1000,
    max_distance: float = 0.1,
    n_matches: int = 3,
    min_pair_distance: float = 5.0,
    max_pairs: int | None = None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Mirror pairs of ``image`` by thresholded mirrored-SIFT matching.

    Args:
        image: ``(1, C, H, W)`` float image in [0, 1].
        num_features: the most SIFT keypoints.
        max_distance: the largest descriptor distance of a pair.
        n_matches: the most matches per keypoint.
        min_pair_distance: keypoints closer than this (pixels) are not paired.
        max_pairs: the most pairs kept (smallest distances first); None keeps all.

    Returns:
        ``pairs (P, 4)`` float ``x1, y1, x2, y2`` in pixels and ``distances (P,)``, sorted
        by distance, on the image's device.
    """
    empty = (torch.zeros(0, 4, device=image.device), torch.zeros(0, device=image.device))
    if min(image.shape[-2:]) < SIFT_MIN_SIDE:
        return empty
    feats, i, j, d = mirror_sift_knn(image, num_features=num_features, k=n_matches, min_pair_distance=min_pair_distance)
    if len(feats) < 2:
        return empty
    keep = d < max_distance
    i, j, d = i[keep], j[keep], d[keep]
    lo, hi = torch.minimum(i, j), torch.maximum(i, j)
    key = lo * len(feats) + hi
    key, first = _unique_first(key)
    lo, hi, d = lo[first], hi[first], d[first]
    order = d.argsort(stable=True)
    if max_pairs is not None:
        order = order[:max_pairs]
    pts = feats.points.float()
    pairs = torch.cat([pts[lo[order]], pts[hi[order]]], 1)  # (P, 4)
    return pairs, d[order].float()


def _unique_first(key: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Unique values of ``key (M,)`` and the index of the first occurrence of each."""
    uniq, inverse = torch.unique(key, return_inverse=True)
    pos = torch.arange(key.numel(), device=key.device)
    first = torch.full((uniq.numel(),), key.numel(), dtype=torch.int64, device=key.device)
    first = first.scatter_reduce(0, inverse, pos, reduce="amin")
    return uniq, first
