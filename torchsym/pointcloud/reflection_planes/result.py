"""The result of the every-plane detector."""

from __future__ import annotations

import dataclasses

import torch

from torchsym.core.results import Result
from torchsym.geometry.reflection import reflect_points

__all__ = ["ReflectionPlanesResult"]


@dataclasses.dataclass(frozen=True)
class ReflectionPlanesResult(Result):
    """Every reflection plane of a point cloud, best first, and its axes of revolution.

    Attributes:
        normals: ``(P, 3)`` unit normals, largest-magnitude component positive.
        offsets: ``(P,)`` offsets: plane ``p`` is ``normals[p] . x + offsets[p] = 0``.
        scores: ``(P,)`` in [0, 1], descending: each plane's mirror share corrected for
            chance, as :attr:`~torchsym.pointcloud.ReflectionPlaneResult.score`.
        ratios: ``(P,)`` mean distance from the mirror images of one half of the cloud to
            the other half, over the mean distance between the halves (1: exact).
        transforms: ``(P, 4, 4)`` homogeneous reflections acting on ``[x; 1]``.
        pairs: ``(M, 3)`` int64 rows ``(p, i, j)``, ``i <= j``: points ``i`` and ``j`` are
            mutual nearest mirror images within the tolerance under plane ``p``.
        continuous_axes: ``(A, 3)`` unit directions of axes of revolution (planes through
            them at every angle, not listed in ``normals``).
        axis_points: ``(A, 3)`` a point on each axis (the nearest to the cloud's centre).
        axis_ratios: ``(A,)`` the worst distance ratio of the rotations tested about each axis.
        center: ``(3,)`` the point nearest to every plane and axis in the least-squares
            sense (the fixed point of the symmetry group), or the cloud's median without any.
        tolerance: the mirror tolerance (``inlier_factor`` x the median spacing).
        sampling_distance: the mean distance between the two halves of the cloud.
        n_starts: starts aligned; n_tested: planes tested.
        timings: seconds per stage: ``prepare``, ``align``, ``test``, ``score``, ``total``.

    Lengths are in input units.
    """

    normals: torch.Tensor
    offsets: torch.Tensor
    scores: torch.Tensor
    ratios: torch.Tensor
    transforms: torch.Tensor
    pairs: torch.Tensor
    continuous_axes: torch.Tensor
    axis_points: torch.Tensor
    axis_ratios: torch.Tensor
    center: torch.Tensor
    tolerance: float
    sampling_distance: float
    n_starts: int
    n_tested: int
    timings: dict[str, float]

    @property
    def score(self) -> float:
        """The shape's symmetry score in [0, 1]: the best plane's, 0 without a plane."""
        return float(self.scores.max()) if self.scores.numel() else 0.0

    @property
    def n_planes(self) -> int:
        """Planes found (axes of revolution not counted)."""
        return int(self.normals.shape[0])

    def reflect(self, points: torch.Tensor, plane: int = 0) -> torch.Tensor:
        """Reflect ``(..., N, 3)`` points in plane ``plane`` (0: the best)."""
        return reflect_points(points, self.normals[plane].to(points), self.offsets[plane].to(points))

    def plane_pairs(self, plane: int) -> torch.Tensor:
        """``(M_p, 2)`` the mirror pairs of plane ``plane``."""
        return self.pairs[self.pairs[:, 0] == plane, 1:]
