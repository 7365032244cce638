"""Reflection of a volume (an SDF or occupancy grid) about a plane, by ``affine_grid`` + ``grid_sample``.

Grid convention (PRS-Net's, ``pointClosestCellIndex`` in ``IGLICT/PRS-Net``
``models/network.py``): a grid of ``G_1 x ... x G_D`` cells covers the cube
``[-bound, bound]^D``; ``volume[b, c, i_1, ..., i_D]`` is the value at the centre of cell
``i``, whose coordinate ``d`` is ``x_d = -bound + (2 i_d + 1) bound / G_d``. The first
spatial axis is ``x``. ``grid_sample`` with ``align_corners=False`` uses the same
cell-centre layout in ``[-1, 1]``, with its coordinates listed from the last axis.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from torchsym.errors import InputShapeError, InputValueError

__all__ = ["grid_cell_centres", "reflect_volume"]


def grid_cell_centres(shape: tuple[int, ...], bound: float = 0.5, *, dtype=torch.float32, device=None) -> torch.Tensor:
    """Coordinates of the cell centres of a grid over ``[-bound, bound]^D``, ``(*shape, D)``."""
    axes = [(-bound + (2 * torch.arange(g, dtype=dtype, device=device) + 1) * bound / g) for g in shape]
    return torch.stack(torch.meshgrid(*axes, indexing="ij"), dim=-1)


def reflect_volume(
    volume: torch.Tensor,
    normal: torch.Tensor,
    offset: torch.Tensor,
    *,
    bound: float = 0.5,
    mode: str = "bilinear",
    padding_mode: str = "border",
) -> torch.Tensor:
    """The volume seen through the mirror: ``out(x) = volume(S x)`` for the reflection ``S``.

    Args:
        volume: ``(B, C, G_1, G_2)`` or ``(B, C, G_1, G_2, G_3)`` grid (SDF, occupancy, features).
        normal: ``(B, D)`` plane normals (any non-zero length), ``D`` the number of spatial axes.
        offset: ``(B,)`` plane offsets, in the units of ``bound``.
        bound: half the side of the cube the grid covers.
        mode: ``grid_sample`` interpolation (``"bilinear"`` is trilinear in 3D; ``"nearest"``).
        padding_mode: what lies outside the grid (``"border"``, ``"zeros"``, ``"reflection"``).

    Returns:
        ``(B, C, *G)`` reflected volume, differentiable in the volume, normal and offset.
        A volume symmetric about the plane is returned unchanged (up to interpolation).
    """
    if not isinstance(volume, torch.Tensor) or volume.dim() not in (4, 5):
        got = getattr(volume, "shape", type(volume).__name__)
        raise InputShapeError(f"volume: expected (B, C, G1, G2) or (B, C, G1, G2, G3), got {got}")
    d = volume.dim() - 2
    b = volume.shape[0]
    if not isinstance(normal, torch.Tensor) or normal.shape != (b, d):
        raise InputShapeError(f"normal: expected ({b}, {d}), got {getattr(normal, 'shape', type(normal).__name__)}")
    if not isinstance(offset, torch.Tensor) or offset.shape != (b,):
        raise InputShapeError(f"offset: expected ({b},), got {getattr(offset, 'shape', type(offset).__name__)}")
    if not bound > 0:
        raise InputValueError(f"bound: expected > 0, got {bound}")
    norm = normal.norm(dim=-1, keepdim=True)
    n = normal / norm
    off = offset / norm.squeeze(-1) / bound  # in grid units u = x / bound
    n_g = n.flip(-1)  # grid_sample lists coordinates from the last axis
    eye = torch.eye(d, dtype=n.dtype, device=n.device)
    lin = eye - 2.0 * n_g.unsqueeze(-1) * n_g.unsqueeze(-2)  # (B, D, D)
    shift = -2.0 * off.unsqueeze(-1) * n_g  # (B, D)
    theta = torch.cat([lin, shift.unsqueeze(-1)], dim=-1).to(volume.dtype)  # (B, D, D + 1)
    grid = F.affine_grid(theta, list(volume.shape), align_corners=False)
    return F.grid_sample(volume, grid, mode=mode, padding_mode=padding_mode, align_corners=False)
