"""The result of PointSymm on images (thesis Sec. 7.4.4)."""

from __future__ import annotations

import dataclasses

import torch

from torchsym.core.results import Result

__all__ = ["ImageAxisResult"]


@dataclasses.dataclass(frozen=True)
class ImageAxisResult(Result):
    """The reflection symmetry axis of an image found by :func:`point_symm_image`.

    Attributes:
        normal: ``(2,)`` unit normal of the axis ``normal . (x, y) + offset = 0`` in pixel
            coordinates (``x`` the column, ``y`` the row).
        offset: ``()`` offset of the axis.
        segment: ``(2, 2)`` the axis clipped to the image, two ``(x, y)`` end points
            (NaN if the line misses the image).
        corners: ``(K, 2)`` the Harris corners ``(x, y)`` used as the point set.
        inliers: ``(K,)`` bool, corners whose reflection lands near another corner.
        permutation: ``(K,)`` int64, mirror corner of each inlier, -1 elsewhere.
        score: in [0, 1], calibrated against chance
            (:func:`~torchsym.pointset.score.symmetry_score`): ``q``, the mean over the
            corners of ``max(0, 1 - r / min(nn, moved))`` (``r`` the distance from the
            reflected corner to its mirror, inliers only, ``nn`` the distance to the corner's
            nearest other corner, ``moved`` how far the reflection moves it), corrected by
            its mean ``q_0`` under random axes: ``max(0, (q - q_0) / (1 - q_0))``. Noise gives
            dense, evenly spaced corners whose reflections land near some corner by chance;
            this score counts only what the axis does better than chance.
        iterations: RANSAC iterations run.
    """

    normal: torch.Tensor
    offset: torch.Tensor
    segment: torch.Tensor
    corners: torch.Tensor
    inliers: torch.Tensor
    permutation: torch.Tensor
    score: float
    iterations: int
