"""PRS-Net's symmetry distance loss through a precomputed closest-point grid.

PRS-Net (``IGLICT/PRS-Net``: ``models/network.py``, ``pointClosestCellIndex``,
``calDistence``, ``symLoss``) voxelises the shape on a ``G^3`` grid over
``[-bound, bound]^3`` (``G = 32``, ``bound = 0.5``) and stores, for every cell centre, the
closest point of the surface. The loss of a plane reflects the surface samples ``p_i``,
looks up the cell of each reflected point ``q_i`` (``round(clamp((q - c_0) G / (2 bound),
0, G - 1))`` with ``c_0 = -bound + bound / G`` the first cell centre) and sums
``|q_i - cp(cell)|^2 (1 - occupancy(cell))`` over the points (a reflected point that lands
in an occupied cell costs nothing); the batch mean is taken, and the planes summed.

Their ``calDistence`` is a custom autograd Function whose backward returns
``2 (q - cp) (1 - occ) / B`` for the reflected points: exactly what plain autograd gives
when the grid lookup (closest point and occupancy) is a constant. Here it is plain autograd
on a detached lookup (``tests/losses/test_prsnet.py`` shows the two agree). Their backward
also ignores the incoming gradient (it assumes ``1``); plain autograd does not.
Any ``D`` (PRS-Net's is 3).
"""

from __future__ import annotations

import torch

from torchsym.core.checks import check_int
from torchsym.errors import InputShapeError, InputValueError
from torchsym.geometry.volume import grid_cell_centres
from torchsym.losses._common import _shape, check_finite_here, check_planes_for, check_points, check_reduction, check_threshold, reduce
from torchsym.losses.symmetry_distance import nearest_neighbours, reflect_batch

__all__ = ["closest_point_grid", "grid_cell_index", "occupancy_grid", "prsnet_symmetry_loss"]


MAX_CELLS = 1 << 24  # cells of a grid (PRS-Net's 32^3 is 32,768)


def check_grid(grid_size: object, bound: object, dim: int | None = None) -> tuple[int, float]:
    """``grid_size`` an int >= 1 (with ``grid_size ** dim <= MAX_CELLS`` when ``dim`` is
    given) and ``bound`` a number > 0 whose square is a normal float32; raise
    :class:`InputValueError` naming the argument otherwise."""
    g = check_int(grid_size, "grid_size", minimum=1)
    if dim is not None and g**dim > MAX_CELLS:
        raise InputValueError(f"grid_size: expected grid_size ** {dim} <= {MAX_CELLS} cells, got {g} ({g ** dim} cells)")
    return g, check_threshold(bound, "bound")


def grid_cell_index(points: torch.Tensor, grid_size: int, bound: float = 0.5) -> torch.Tensor:
    """Per-axis index ``(..., D)`` int64 of the cell whose centre is nearest, clamped into the grid."""
    grid_size, bound = check_grid(grid_size, bound)
    c0 = -bound + bound / grid_size
    ind = (points - c0) * grid_size / (2 * bound)
    return torch.round(ind.nan_to_num(0.0).clamp(0, grid_size - 1)).long()


def _flat(index: torch.Tensor, grid_size: int) -> torch.Tensor:
    d = index.shape[-1]
    strides = grid_size ** torch.arange(d - 1, -1, -1, device=index.device)
    return (index * strides).sum(-1)


def occupancy_grid(points: torch.Tensor, grid_size: int = 32, bound: float = 0.5, mask: torch.Tensor | None = None) -> torch.Tensor:
    """``(B, G, ..., G)`` float 1 where a cell holds a valid point of ``points (B, N, D)``, else 0.

    PRS-Net voxelises the mesh; for surface samples dense enough for the grid this is the
    same set of cells (points outside the cube are clamped to its border cells). Raises
    :class:`InputValueError` for a ``grid_size`` that is not an int >= 1 with at most
    ``MAX_CELLS`` cells, or a ``bound`` not in [1e-18, 1e18].
    """
    w = check_points(points, mask)
    b, _, d = points.shape
    grid_size, bound = check_grid(grid_size, bound, d)
    flat = _flat(grid_cell_index(points.detach(), grid_size, bound), grid_size)  # (B, N)
    occ = torch.zeros(b, grid_size**d, dtype=points.dtype, device=points.device)
    occ.scatter_reduce_(1, flat, w.detach(), reduce="amax")
    return occ.reshape(b, *([grid_size] * d))


def closest_point_grid(
    surface: torch.Tensor, grid_size: int = 32, bound: float = 0.5, mask: torch.Tensor | None = None, *, method: str = "auto"
) -> torch.Tensor:
    """``(B, G, ..., G, D)`` closest valid ``surface (B, M, D)`` point to every cell centre (no gradient).

    Raises :class:`InputShapeError` for a surface without points and
    :class:`InputValueError` for a bad ``grid_size`` or ``bound`` (see :func:`occupancy_grid`).
    """
    check_points(surface, mask, "surface")
    b, m, d = surface.shape
    grid_size, bound = check_grid(grid_size, bound, d)
    if m == 0:
        raise InputShapeError(f"surface: expected at least one point per cloud, got {tuple(surface.shape)}")
    centres = grid_cell_centres((grid_size,) * d, bound, dtype=surface.dtype, device=surface.device).reshape(1, -1, d)
    centres = centres.expand(b, -1, -1)
    idx = nearest_neighbours(centres, surface, mask, method=method)  # (B, G^D)
    cp = torch.gather(surface.detach(), 1, idx.unsqueeze(-1).expand(-1, -1, d))
    return cp.reshape(b, *([grid_size] * d), d)


def prsnet_symmetry_loss(
    points: torch.Tensor,
    normal: torch.Tensor,
    offset: torch.Tensor,
    closest_points: torch.Tensor,
    occupancy: torch.Tensor,
    mask: torch.Tensor | None = None,
    *,
    bound: float = 0.5,
    reduction: str = "none",
) -> torch.Tensor:
    """PRS-Net's reflection loss: ``sum_i |q_i - cp(cell(q_i))|^2 (1 - occ(cell(q_i)))`` per cloud and plane.

    Args:
        points: ``(B, N, D)`` surface samples (PRS-Net: 1,000 per shape).
        normal: ``(B, K, D)`` plane normals (normalised here), offset ``(B, K)``.
        closest_points: ``(B, G, ..., G, D)`` from :func:`closest_point_grid`.
        occupancy: ``(B, G, ..., G)`` in ``[0, 1]`` from :func:`occupancy_grid`.
        mask: ``(B, N)`` 1 for real samples.
        bound: half side of the grid's cube.
        reduction: ``"none"`` gives ``(B, K)`` sums over the points; PRS-Net's total is
            ``loss.sum(-1).mean()``; ``"mean"`` / ``"sum"`` reduce all entries.

    Returns:
        ``(B, K)`` (or scalar), differentiable in ``points``, ``normal`` and ``offset``;
        finite with finite gradients at a zero normal (the points reflect onto themselves);
        zeros for an empty batch.

    Raises:
        InputShapeError: shapes that do not match. InputValueError: NaN or infinite
        entries (CPU tensors outside ``torch.compile``), ``bound`` not in [1e-18, 1e18].
    """
    w = check_points(points, mask)
    b, n, d = points.shape
    normal, offset = check_planes_for(points, normal, offset)
    check_reduction(reduction)
    g = occupancy.shape[-1] if isinstance(occupancy, torch.Tensor) and occupancy.dim() > 1 else 0
    if g < 1 or occupancy.shape != (b, *([g] * d)) or occupancy.is_complex():
        raise InputShapeError(f"occupancy: expected (B, G, ..., G) with {d} grid axes and B = {b}, got {_shape(occupancy)}")
    if not isinstance(closest_points, torch.Tensor) or closest_points.shape != (*occupancy.shape, d) or not closest_points.is_floating_point():
        raise InputShapeError(f"closest_points: expected a floating {(*occupancy.shape, d)} tensor, got {_shape(closest_points)}")
    check_finite_here(closest_points, "closest_points")
    check_finite_here(occupancy.to(points.dtype), "occupancy")
    _, bound = check_grid(g, bound)
    k = normal.shape[1]
    if b * k * n == 0:
        return reduce(points.new_zeros(b, k) + 0.0 * (normal.sum() + offset.sum() + points.sum()), reduction)
    refl = reflect_batch(points, normal, offset).reshape(b, k * n, d)  # (B, K N, D)
    flat = _flat(grid_cell_index(refl.detach(), g, bound), g)  # (B, K N)
    cp = torch.gather(closest_points.reshape(b, -1, d).detach(), 1, flat.unsqueeze(-1).expand(-1, -1, d))
    free = 1.0 - torch.gather(occupancy.reshape(b, -1).detach().to(points.dtype), 1, flat)  # (B, K N)
    sq = ((refl - cp) ** 2).sum(-1) * free * w.repeat(1, k)
    return reduce(sq.reshape(b, k, n).sum(-1), reduction)
