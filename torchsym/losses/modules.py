"""Module forms of the losses: they hold the settings and call the function, nothing more."""

from __future__ import annotations

import torch
from torch import nn

from torchsym.losses.prsnet import prsnet_symmetry_loss
from torchsym.losses.regularizers import orthogonality_loss
from torchsym.losses.symmetry_distance import symmetry_distance

__all__ = ["OrthogonalityLoss", "PRSNetSymmetryLoss", "SymmetryDistanceLoss"]


class SymmetryDistanceLoss(nn.Module):
    """Module form of :func:`torchsym.losses.symmetry_distance` (same arguments and defaults)."""

    def __init__(self, kind: str = "l2", threshold: float = 0.05, reduction: str = "mean", method: str = "auto") -> None:
        super().__init__()
        self.kind, self.threshold, self.reduction, self.method = kind, threshold, reduction, method

    def forward(self, points: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor, mask: torch.Tensor | None = None) -> torch.Tensor:
        return symmetry_distance(
            points, normal, offset, mask, kind=self.kind, threshold=self.threshold, reduction=self.reduction, method=self.method
        )

    def extra_repr(self) -> str:
        return f"kind={self.kind!r}, threshold={self.threshold}, reduction={self.reduction!r}, method={self.method!r}"


class PRSNetSymmetryLoss(nn.Module):
    """Module form of :func:`torchsym.losses.prsnet_symmetry_loss`."""

    def __init__(self, bound: float = 0.5, reduction: str = "none") -> None:
        super().__init__()
        self.bound, self.reduction = bound, reduction

    def forward(self, points, normal, offset, closest_points, occupancy, mask=None) -> torch.Tensor:
        return prsnet_symmetry_loss(points, normal, offset, closest_points, occupancy, mask, bound=self.bound, reduction=self.reduction)

    def extra_repr(self) -> str:
        return f"bound={self.bound}, reduction={self.reduction!r}"


class OrthogonalityLoss(nn.Module):
    """Module form of :func:`torchsym.losses.orthogonality_loss`."""

    def __init__(self, reduction: str = "mean") -> None:
        super().__init__()
        self.reduction = reduction

    def forward(self, normal: torch.Tensor, plane_mask: torch.Tensor | None = None) -> torch.Tensor:
        return orthogonality_loss(normal, plane_mask, reduction=self.reduction)

    def extra_repr(self) -> str:
        return f"reduction={self.reduction!r}"
