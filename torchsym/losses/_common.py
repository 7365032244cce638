"""Shared checks and reductions of the loss functions: ``(B, N, D)`` points with a ``(B, N)`` mask.

The losses' contract on bad input (training loops call them): shapes, dtypes and
settings are checked on every call (no tensor is read for that) and raise
:class:`~torchsym.errors.InputShapeError` / :class:`~torchsym.errors.InputValueError`;
NaN or infinite entries raise :class:`~torchsym.errors.InputValueError` for CPU tensors
outside ``torch.compile`` (elsewhere the check would wait on the device, and a
non-finite input gives a non-finite loss); a zero or tiny plane normal gives a finite
loss with finite gradients (see :func:`unit_planes`); an empty batch or cloud gives
zeros (and 0 for ``"mean"``).
"""

from __future__ import annotations

import math

import torch

from torchsym.core.checks import check_finite
from torchsym.errors import InputShapeError, InputValueError

REDUCTIONS = ("none", "mean", "sum")


def _shape(x: object) -> object:
    return tuple(x.shape) if isinstance(x, torch.Tensor) else type(x).__name__


def check_finite_here(t: torch.Tensor, name: str, *, squares: int = 0) -> None:
    """:func:`~torchsym.core.checks.check_finite` for CPU tensors in eager mode (no device
    wait); with ``squares`` > 0, also entries so large that a sum of ``squares`` squared
    differences of such entries overflows the dtype."""
    if t.device.type != "cpu" or torch.compiler.is_compiling() or t.numel() == 0:
        return
    check_finite(t.detach(), name)
    if squares and t.is_floating_point():
        limit = math.sqrt(torch.finfo(t.dtype).max / squares) / 4
        big = float(t.detach().abs().amax())
        if big > limit:
            raise InputValueError(f"{name}: expected entries below {limit:.3g} in {t.dtype} (sums of squared "
                                  f"differences overflow), got {big:.3g}; rescale the input")


def check_points(points: torch.Tensor, mask: torch.Tensor | None, name: str = "points") -> torch.Tensor:
    """Check ``points (B, N, D)`` (floating, ``D >= 1``, finite) and ``mask (B, N)``; return
    the mask as the points' dtype (ones if None)."""
    if not isinstance(points, torch.Tensor) or points.dim() != 3 or not points.is_floating_point() or points.shape[-1] < 1:
        raise InputShapeError(f"{name}: expected a floating (B, N, D) tensor with D >= 1, got {_shape(points)}"
                              + (f" of dtype {points.dtype}" if isinstance(points, torch.Tensor) else ""))
    if points.layout != torch.strided:
        raise InputShapeError(f"{name}: expected a dense tensor, got layout {points.layout}")
    check_finite_here(points, name, squares=max(1, points.shape[1] * points.shape[2]))
    if mask is None:
        return torch.ones(points.shape[:2], dtype=points.dtype, device=points.device)
    if not isinstance(mask, torch.Tensor) or mask.shape != points.shape[:2] or mask.is_complex():
        raise InputShapeError(f"mask: expected a real {tuple(points.shape[:2])} tensor to match {name}, got {_shape(mask)}")
    w = mask.to(points.dtype)
    check_finite_here(w, "mask")
    return w


def check_planes_for(points: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Check ``normal (B, K, D)`` and ``offset (B, K)`` against ``points (B, N, D)``; return
    both in the points' dtype (floating, finite on CPU)."""
    b, _, d = points.shape
    for t, name in ((normal, "normal"), (offset, "offset")):
        if not isinstance(t, torch.Tensor) or t.is_complex() or t.dtype == torch.bool:
            raise InputShapeError(f"{name}: expected a real tensor, got {_shape(t)}")
    if normal.dim() != 3 or normal.shape[0] != b or normal.shape[-1] != d:
        raise InputShapeError(f"normal: expected ({b}, K, {d}) to match the points, got {tuple(normal.shape)}")
    if offset.shape != normal.shape[:2]:
        raise InputShapeError(f"offset: expected {tuple(normal.shape[:2])} to match normal, got {tuple(offset.shape)}")
    normal, offset = normal.to(points.dtype), offset.to(points.dtype)
    check_finite_here(normal, "normal")
    check_finite_here(offset, "offset", squares=max(1, points.shape[1] * points.shape[2]))
    return normal, offset


def unit_planes(normal: torch.Tensor, offset: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Unit normals ``(..., D)`` and offsets ``(...)`` of planes ``normal . x + offset = 0``.

    Huge normals are first divided by their largest entry (a constant for autograd: the
    result does not depend on it), so no square overflows; lengths are clamped below at
    the float32 epsilon, so a zero normal gives the zero vector and offset ``offset / eps``
    times nothing (the reflection through it is the identity) with finite gradients, and a
    tiny normal a short vector: the losses stay finite and differentiable there.
    """
    eps = torch.finfo(torch.promote_types(normal.dtype, torch.float32)).eps
    s = normal.detach().abs().amax(-1, keepdim=True).clamp_min(1.0)  # (..., 1)
    m = normal / s
    r = torch.linalg.vector_norm(m, dim=-1, keepdim=True).clamp_min(eps)  # (..., 1)
    return m / r, offset / (s * r).squeeze(-1)


def check_reduction(reduction: str) -> None:
    if reduction not in REDUCTIONS:
        raise InputValueError(f"reduction: expected one of {REDUCTIONS}, got {reduction!r}")


def check_threshold(threshold: object, name: str = "threshold") -> float:
    """A positive finite threshold whose square is a normal float32 number."""
    ok = isinstance(threshold, (int, float)) and not isinstance(threshold, bool) and math.isfinite(threshold)
    if not ok or not 1e-18 <= float(threshold) <= 1e18:
        raise InputValueError(f"{name}: expected a number in [1e-18, 1e18] (its square a normal float32), got {threshold!r}")
    return float(threshold)


def reduce(values: torch.Tensor, reduction: str) -> torch.Tensor:
    """``"none"`` keeps ``values``; ``"mean"`` and ``"sum"`` reduce every entry to a scalar
    (the mean of no entries is 0)."""
    if reduction == "none":
        return values
    return values.sum() / max(values.numel(), 1) if reduction == "mean" else values.sum()


def masked_mean(values: torch.Tensor, weight: torch.Tensor, dim: int) -> torch.Tensor:
    """``sum(w v) / max(sum(w), 1)`` along ``dim``: no host sync, 0 for an empty row."""
    return (values * weight).sum(dim) / weight.sum(dim).clamp_min(1.0)
