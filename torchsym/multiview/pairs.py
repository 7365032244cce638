"""Mirror symmetric point pairs (MSPP) of a sparse model (thesis Sec. 5.3.2).

Points ``p_j`` and ``p_k`` form a pair when each is the other's nearest neighbour in
descriptor space against the mirrored descriptors of the rest: ``p_k = argmin_{r != j}
|d_j - m_r|`` and ``p_j = argmin_{r != k} |d_k - m_r|`` (best buddies, the thesis's [33]).
Since the mirror permutation is an involution, ``|d_j - m_r| = |d_r - m_j|``: the
distance matrix is symmetric and the pairs are its mutual nearest neighbours.
"""

from __future__ import annotations

import torch

from torchsym.features.sift import mirror_descriptors

__all__ = ["best_buddy_pairs"]

#: rows of the descriptor distance matrix formed at once
CHUNK = 2048


def _nearest_other(descriptors: torch.Tensor, mirrored: torch.Tensor) -> torch.Tensor:
    """For each row ``j`` of ``descriptors`` the ``r != j`` minimising ``|d_j - m_r|``."""
    m = descriptors.shape[0]
    sq_m = (mirrored * mirrored).sum(1)  # (M,)
    out = torch.empty(m, dtype=torch.int64)
    for start in range(0, m, CHUNK):
        d = descriptors[start : start + CHUNK]  # (c, 128)
        dist = sq_m[None, :] - 2.0 * (d @ mirrored.T)  # (c, M), |d|^2 dropped: constant per row
        rows = torch.arange(d.shape[0])
        dist[rows, rows + start] = float("inf")
        out[start : start + CHUNK] = dist.argmin(1)
    return out


def best_buddy_pairs(
    points: torch.Tensor, descriptors: torch.Tensor, *, layout: str = "opencv", min_chord: float = 0.0
) -> torch.Tensor:
    """Mirror symmetric point pairs by best buddies of mirrored SIFT descriptors.

    Args:
        points: ``(M, 3)`` 3D points.
        descriptors: ``(M, 128)`` SIFT descriptors (mean over each point's observations).
        layout: the descriptors' layout, ``"opencv"`` (COLMAP, OpenCV, VLFeat) or
            ``"kornia"`` (see :func:`torchsym.features.mirror_permutation`).
        min_chord: pairs whose points lie closer than this (input units) are dropped:
            COLMAP keeps a keypoint once per orientation, and both copies may be
            triangulated at one place, giving pairs of length zero that tilt the plane.

    Returns:
        ``(S, 2)`` int64 index pairs ``(j, k)`` with ``j < k``.
    """
    d = descriptors.float()
    nearest = _nearest_other(d, mirror_descriptors(d, layout=layout))  # (M,)
    j = torch.arange(d.shape[0])
    mutual = (nearest[nearest] == j) & (j < nearest)
    pairs = torch.stack([j[mutual], nearest[mutual]], 1)  # (S, 2)
    chord = (points[pairs[:, 0]] - points[pairs[:, 1]]).norm(dim=1)
    return pairs[chord > min_chord]
