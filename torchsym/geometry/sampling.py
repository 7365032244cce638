"""Deterministic samples of directions on the sphere."""

from __future__ import annotations

import math

import torch

__all__ = ["sphere_normals"]


def sphere_normals(count: int, *, dtype: torch.dtype = torch.float64) -> torch.Tensor:
    """``(count, 3)`` near-uniform unit normals on the upper half sphere (Fibonacci lattice).

    Every plane through the origin has exactly one normal with ``z >= 0``, so the half
    sphere covers all planes. ``count = 100`` leaves no plane much more than 10 degrees
    from a sample (the basin of thesis Sec. 5.2.3).
    """
    i = torch.arange(count, dtype=dtype) + 0.5
    z = 1.0 - i / count  # uniform in (0, 1]
    r = torch.sqrt((1.0 - z * z).clamp_min(0))
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    return torch.stack([r * torch.cos(phi), r * torch.sin(phi), z], dim=1)
