"""Duplicate planes merged, and new candidates from the planes already accepted.

Two symmetry planes generate more: reflecting plane ``j`` in plane ``i`` gives the plane
of the reflection ``T_i T_j T_i``, a symmetry whenever both are (two planes at ``pi / k``
generate all ``k`` planes of a ``k``-fold axis). Planes are ``normals (K, 3)``,
``offsets (K,)``; points are normalised.
"""

from __future__ import annotations

import math

import torch

from torchsym.pointcloud.reflection_planes.align import reflect_in_planes

__all__ = ["MERGE_ANGLE", "conjugate_planes", "distinct_planes", "mirror_gaps"]

#: planes closer than this (degrees) are one unless their mirror images differ much: the
#: planes of a k-fold axis are 180 / k apart, and beyond k = 36 the axis is one of revolution
MERGE_ANGLE = 5.0


def mirror_gaps(probe: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor, others_n, others_b) -> torch.Tensor:
    """``(K, L)`` median over ``probe (Q, 3)`` of the distance between its mirror images
    in plane ``k`` of ``(normals, offsets)`` and plane ``l`` of ``(others_n, others_b)``."""
    a = reflect_in_planes(probe, normals, offsets)  # (K, Q, 3)
    b = reflect_in_planes(probe, others_n, others_b)  # (L, Q, 3)
    return (a[:, None] - b[None]).norm(dim=-1).median(-1).values


def distinct_planes(
    probe: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor, order: torch.Tensor, tol: float,
    angle: float = MERGE_ANGLE,
) -> list[int]:
    """Indices of the planes in ``order`` (best first) that are not within ``tol`` (the
    median mirror-image gap, :func:`mirror_gaps`) of a plane kept before them, nor within
    ``angle`` degrees of one with a mirror-image gap under ``4 tol``."""
    if order.numel() == 0:
        return []
    n, b = normals[order], offsets[order]
    gaps = mirror_gaps(probe, n, b, n, b)  # (K, K)
    close = (gaps < tol) | (((n @ n.T).abs() > math.cos(math.radians(angle))) & (gaps < 4.0 * tol))
    kept: list[int] = []
    for i in range(order.numel()):
        if not any(bool(close[i, j]) for j in kept):
            kept.append(i)
    return [int(order[i]) for i in kept]


def conjugate_planes(normals: torch.Tensor, offsets: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Every plane ``j`` reflected in every other plane ``i``: ``(K (K - 1), 3)`` normals and
    offsets. The reflection of ``n_j . x + b_j = 0`` in plane ``i`` is
    ``(R_i n_j) . y + b_j - 2 b_i (n_i . n_j) = 0``, ``R_i = I - 2 n_i n_i^T``."""
    k = normals.shape[0]
    cos = normals @ normals.T  # (K, K) [i, j] = n_i . n_j
    new_n = normals[None, :, :] - 2.0 * cos[:, :, None] * normals[:, None, :]  # (K_i, K_j, 3)
    new_b = offsets[None, :] - 2.0 * offsets[:, None] * cos  # (K_i, K_j)
    off_diag = ~torch.eye(k, dtype=torch.bool, device=normals.device)
    return new_n[off_diag], new_b[off_diag]
