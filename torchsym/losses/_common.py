"""Shared checks and reductions of the loss functions: ``(B, N, D)`` points with a ``(B, N)`` mask."""

from __future__ import annotations

import torch

from torchsym.errors import InputShapeError, InputValueError

REDUCTIONS = ("none", "mean", "sum")


def check_points(points: torch.Tensor, mask: torch.Tensor | None, name: str = "points") -> torch.Tensor:
    """Check ``points (B, N, D)`` and ``mask (B, N)``; return the mask as the points' dtype (ones if None)."""
    if not isinstance(points, torch.Tensor) or points.dim() != 3 or not points.is_floating_point():
        raise InputShapeError(f"{name}: expected a floating (B, N, D) tensor, got {getattr(points, 'shape', type(points).__name__)}")
    if mask is None:
        return torch.ones(points.shape[:2], dtype=points.dtype, device=points.device)
    if not isinstance(mask, torch.Tensor) or mask.shape != points.shape[:2]:
        got = getattr(mask, "shape", type(mask).__name__)
        raise InputShapeError(f"mask: expected {tuple(points.shape[:2])} to match {name}, got {got}")
    return mask.to(points.dtype)


def check_reduction(reduction: str) -> None:
    if reduction not in REDUCTIONS:
        raise InputValueError(f"reduction: expected one of {REDUCTIONS}, got {reduction!r}")


def reduce(values: torch.Tensor, reduction: str) -> torch.Tensor:
    """``"none"`` keeps ``values``; ``"mean"`` and ``"sum"`` reduce every entry to a scalar."""
    if reduction == "none":
        return values
    return values.mean() if reduction == "mean" else values.sum()


def masked_mean(values: torch.Tensor, weight: torch.Tensor, dim: int) -> torch.Tensor:
    """``sum(w v) / max(sum(w), 1)`` along ``dim``: no host sync, 0 for an empty row."""
    return (values * weight).sum(dim) / weight.sum(dim).clamp_min(1.0)
