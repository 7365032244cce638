"""The result of the whole-group detector."""

from __future__ import annotations

import dataclasses

import torch

from torchsym.core.results import Result
from torchsym.pointcloud.reflection_planes.group import SymmetryGroup
from torchsym.pointcloud.reflection_planes.result import ReflectionPlanesResult

__all__ = ["SymmetryResult"]


@dataclasses.dataclass(frozen=True)
class SymmetryResult(Result):
    """Every symmetry of a point cloud and the point group they make.

    Attributes:
        planes: the every-plane detector's result (planes, axes of revolution).
        axes: ``(K, 3)`` unit directions of the rotation axes found directly (with or
            without planes), highest order first; ``axis_points (K, 3)`` a point on each;
            ``orders (K,)`` int64; ``axis_ratios (K,)`` the distance ratio of the rotation
            by ``2 pi / order``; ``axis_scores (K,)`` its share of points moved onto the
            surface, corrected for chance, in [0, 1].
        rotoreflections: ``(S, 4, 4)`` rotoreflections (and the inversion) found directly.
        group: the closure of the planes, the rotations, the rotoreflections and the axes
            of revolution (:class:`~torchsym.pointcloud.SymmetryGroup`).
        timings: seconds: ``planes``, ``rotations``, ``group``, ``total``.

    Lengths are in input units.
    """

    planes: ReflectionPlanesResult
    axes: torch.Tensor
    axis_points: torch.Tensor
    orders: torch.Tensor
    axis_ratios: torch.Tensor
    axis_scores: torch.Tensor
    rotoreflections: torch.Tensor
    group: SymmetryGroup
    timings: dict[str, float]

    @property
    def score(self) -> float:
        """The shape's symmetry score in [0, 1]: the best of its planes' and its rotation
        axes' scores (0 when it has neither)."""
        axis = float(self.axis_scores.max().clamp(0, 1)) if self.axis_scores.numel() else 0.0
        return max(self.planes.score, axis)
