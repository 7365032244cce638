"""Symmetry prior on a field: ``f(x)`` against ``f(S x)`` (SDF, occupancy, NeRF density or colour).

A neural field symmetric about a plane satisfies ``f(S x) = f(x)``. Priors of this kind
(SymmNeRF, NeuMan's symmetric human prior, NeRD's symmetric depth) compare the field at
sample points and at their mirror images; here with any callable field and a
``(B, K)`` set of planes.
"""

from __future__ import annotations

from collections.abc import Callable

import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.losses._common import _shape, check_finite_here, check_planes_for, check_points, check_reduction, masked_mean, reduce
from torchsym.losses.symmetry_distance import reflect_batch

__all__ = ["field_symmetry_loss"]


def field_symmetry_loss(
    field: Callable[[torch.Tensor], torch.Tensor],
    points: torch.Tensor,
    normal: torch.Tensor,
    offset: torch.Tensor,
    mask: torch.Tensor | None = None,
    *,
    kind: str = "l2",
    stop_gradient: str = "none",
    reduction: str = "none",
) -> torch.Tensor:
    """Mean ``|f(x_i) - f(S x_i)|`` (``"l1"``) or its square (``"l2"``) per batch entry and plane.

    Args:
        field: maps ``(B, M, D)`` points to ``(B, M)`` or ``(B, M, C)`` values (called
            twice: on ``points`` and on all their ``K`` reflections at once).
        points: ``(B, N, D)`` sample points; ``mask (B, N)`` marks real ones.
        normal, offset: ``(B, K, D)`` and ``(B, K)`` planes (normals normalised here).
        kind: ``"l2"`` (squared difference summed over channels) or ``"l1"``.
        stop_gradient: ``"none"``, ``"mirror"`` (no gradient through ``f(S x)``: the
            mirrored value is the target) or ``"source"`` (none through ``f(x)``).
        reduction: ``"none"`` gives ``(B, K)``; ``"mean"`` / ``"sum"`` a scalar.

    A zero normal compares ``f(x)`` with itself (0, finite gradients). Raises
    :class:`InputShapeError` for shapes that do not match (the field's outputs too) and
    :class:`InputValueError` for NaN or infinite inputs or field values (CPU tensors
    outside ``torch.compile``) or an unknown option.
    """
    w = check_points(points, mask)
    normal, offset = check_planes_for(points, normal, offset)
    check_reduction(reduction)
    if kind not in ("l1", "l2"):
        raise InputValueError(f"kind: expected 'l1' or 'l2', got {kind!r}")
    if stop_gradient not in ("none", "mirror", "source"):
        raise InputValueError(f"stop_gradient: expected 'none', 'mirror' or 'source', got {stop_gradient!r}")
    b, n, d = points.shape
    k = normal.shape[1]
    f0 = field(points)
    f1 = field(reflect_batch(points, normal, offset).reshape(b, k * n, d))
    for f, m in ((f0, n), (f1, k * n)):
        if not isinstance(f, torch.Tensor) or f.dim() not in (2, 3) or f.shape[:2] != (b, m) or not f.is_floating_point():
            raise InputShapeError(
                f"field: expected outputs (B, M) or (B, M, C), floating, for (B, M, D) inputs, got {_shape(f)} for {(b, m, d)}"
            )
    check_finite_here(f0, "field(points)", squares=max(1, f0[:1].numel()))
    check_finite_here(f1, "field(reflected points)", squares=max(1, f0[:1].numel()))
    c = 1 if f0.dim() == 2 else f0.shape[2]
    if (1 if f1.dim() == 2 else f1.shape[2]) != c:
        raise InputShapeError(f"field: expected the same channels on points and reflections, got {tuple(f0.shape)} and {tuple(f1.shape)}")
    f0 = f0.reshape(b, 1, n, c)
    f1 = f1.reshape(b, k, n, c)
    if stop_gradient == "mirror":
        f1 = f1.detach()
    elif stop_gradient == "source":
        f0 = f0.detach()
    diff = f0 - f1
    per = (diff**2).sum(-1) if kind == "l2" else diff.abs().sum(-1)  # (B, K, N)
    return reduce(masked_mean(per, w.unsqueeze(1), dim=-1), reduction)
