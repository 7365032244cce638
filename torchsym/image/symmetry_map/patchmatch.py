"""Symmetric PatchMatch (thesis Sec. 3.2.2, Algorithm 3) and the MMP and BMP schemes.

The field ``f`` lives on the descriptor grid (every ``stride``-th pixel,
:class:`~torchsym.image.symmetry_map.descriptors.DenseDescriptors`) as flat grid indices
``(Hg * Wg,)``; a candidate mirror position in pixels is rounded to the nearest grid
point. The cost of a grid point is ``|d_p - m_f(p)|^2`` (symmetric in ``p`` and ``q``).
Every step works on all grid points at once:

- *initialisation*: a random grid point for every grid point, then the cluster's left and
  right pixels ``L_h, R_h`` to each other;
- *propagation* (Eq. 3.3): per point, two random pairs ``(p_j, f(p_j))`` of the cluster;
  the reflections of ``p`` about their bisectors are the candidates, with ``f(p)``;
  with ``neighbours`` also PatchMatch's own propagation (Barnes et al. 2009, not in the
  thesis's Algorithm 3): the mirror of a grid neighbour ``p + delta`` moved by the
  reflected offset, ``f(p + delta) - L delta`` with ``L`` the reflection of the cluster's
  axis (the symmetry coherency of Sec. 3.2.1);
- *random search* (Eq. 3.4): ``e`` samples at distance ``rho ~ U(1, r)`` and angle
  ``psi ~ U(0, 2 pi)`` around the best so far, one sample index at a time over all points
  (a loop of ``e``, never over pixels); a sample replaces the estimate when it lowers the
  cost by more than ``min_gain`` (the thesis: by anything);
- *update* (Eqs. 3.5-3.6): ``f(p) = q`` and ``f(q) = p`` where that lowers ``q``'s cost.
  All points move at once (Jacobi order, not the thesis's pixel by pixel); when several
  ``p`` claim one ``q`` the lowest cost wins, ties to the highest index, so the result is
  the same on every run.

MMP and BMP (Sec. 3.2.2, "Other Schemes") reflect every point through up to
``max_bmp_pairs`` pairs of the cluster and take the mean reflection (MMP) or the one of
lowest cost (BMP; the thesis's ``argmax`` of the distance is read as ``argmin``).
"""

from __future__ import annotations

import dataclasses
import math

import torch

from torchsym.image.symmetry_map.descriptors import DenseDescriptors

__all__ = [
    "FieldState",
    "best_mirror_pixel",
    "candidate_cost",
    "expand_field",
    "grid_index",
    "grid_xy",
    "initial_field",
    "mean_mirror_pixel",
    "patchmatch_iteration",
    "reflect_through_pairs",
    "search_radius",
]


@dataclasses.dataclass(frozen=True)
class FieldState:
    """The field of one cluster during PatchMatch.

    Attributes:
        field: ``(Hg * Wg,)`` int64 flat grid index of each grid point's mirror.
        cost: ``(Hg * Wg,)`` float ``|d_p - m_f(p)|^2``.
    """

    field: torch.Tensor
    cost: torch.Tensor


def candidate_cost(desc: DenseDescriptors, q: torch.Tensor) -> torch.Tensor:
    """``|d_p - m_q|^2`` for every grid point ``p`` and its candidate ``q (Hg * Wg,)``."""
    dot = torch.einsum("nd,nd->n", desc.values, desc.mirrored.index_select(0, q))
    return (desc.sq_norms + desc.sq_norms.index_select(0, q) - 2 * dot).clamp_min(0)


def grid_index(desc: DenseDescriptors, xy: torch.Tensor) -> torch.Tensor:
    """Flat grid indices ``(N,)`` of the grid points nearest to pixel positions ``xy (N, 2)``, clamped into the image."""
    hg, wg = desc.grid_shape
    x = (xy[:, 0] / desc.stride).round().clamp(0, wg - 1).long()
    y = (xy[:, 1] / desc.stride).round().clamp(0, hg - 1).long()
    return y * wg + x


def grid_xy(desc: DenseDescriptors, index: torch.Tensor) -> torch.Tensor:
    """Pixel positions ``(N, 2)`` of flat grid indices ``(N,)``."""
    wg = desc.grid_shape[1]
    return torch.stack([index % wg, torch.div(index, wg, rounding_mode="floor")], 1).to(torch.float32) * desc.stride


def reflect_through_pairs(points: torch.Tensor, left: torch.Tensor, right: torch.Tensor) -> torch.Tensor:
    """Reflect ``points (N, 2)`` about the bisector of the pair ``(left (N, 2), right (N, 2))``, row by row."""
    chord = left - right
    n = chord / chord.norm(dim=1, keepdim=True).clamp_min(1e-6)
    mid = 0.5 * (left + right)
    s = ((points - mid) * n).sum(1, keepdim=True)
    return points - 2 * s * n


def initial_field(desc: DenseDescriptors, left: torch.Tensor, right: torch.Tensor, generator: torch.Generator) -> FieldState:
    """Random mirrors, the cluster's pairs ``left (M, 2)``, ``right (M, 2)`` to each other (Algorithm 3, lines 3-4)."""
    hg, wg = desc.grid_shape
    field = torch.randint(0, hg * wg, (hg * wg,), generator=generator).to(desc.values.device)
    li, ri = grid_index(desc, left), grid_index(desc, right)
    field[li] = ri
    field[ri] = li
    return FieldState(field, candidate_cost(desc, field))


def search_radius(left: torch.Tensor, right: torch.Tensor, height: int, width: int, generator: torch.Generator) -> float:
    """The random-search radius ``r``: the spread of a pixel's reflections through the
    cluster's pairs (Sec. 3.2.2), the median over 256 random pixels of the 90th percentile
    distance to their median reflection, clamped to [3, 0.05 x diagonal] pixels."""
    pts = torch.rand(256, 2, generator=generator).to(left) * torch.tensor([width - 1, height - 1]).to(left)
    take = torch.randperm(left.shape[0], generator=generator)[:64].to(left.device)
    m = take.numel()
    refl = reflect_through_pairs(
        pts[:, None].expand(-1, m, -1).reshape(-1, 2),
        left[take][None].expand(256, -1, -1).reshape(-1, 2),
        right[take][None].expand(256, -1, -1).reshape(-1, 2),
    ).view(256, m, 2)
    centre = refl.median(1).values  # (256, 2)
    spread = (refl - centre[:, None]).norm(dim=2).quantile(0.9, dim=1).median()
    return float(min(max(float(spread), 3.0), 0.05 * math.hypot(height, width)))


def _claim(best: torch.Tensor, cost: torch.Tensor) -> FieldState:
    """Eqs. 3.5-3.6: ``f(p) = best_p``; ``f(best_p) = p`` where ``cost_p`` beats ``best_p``'s own cost."""
    n = best.shape[0]
    points = torch.arange(n, device=best.device)
    incoming = torch.full((n,), float("inf"), dtype=cost.dtype, device=cost.device)
    incoming = incoming.scatter_reduce(0, best, cost, reduce="amin")
    winner_mask = cost == incoming[best]
    winner = torch.full((n,), -1, dtype=torch.int64, device=best.device)
    winner = winner.scatter_reduce(0, best[winner_mask], points[winner_mask], reduce="amax")
    take = (winner >= 0) & (incoming < cost)
    return FieldState(torch.where(take, winner, best), torch.where(take, incoming, cost))


def _keep_better(best: torch.Tensor, best_cost: torch.Tensor, cand: torch.Tensor, desc: DenseDescriptors, margin: float = 0.0):
    c = candidate_cost(desc, cand)
    better = c < best_cost - margin
    return torch.where(better, cand, best), torch.where(better, c, best_cost)


def _neighbour_candidates(desc: DenseDescriptors, field: torch.Tensor, normal: torch.Tensor) -> list[torch.Tensor]:
    """``f(p + delta) - L delta`` for the 4 grid neighbours ``delta``, ``L = I - 2 n n^T``; a border point keeps ``f(p)``."""
    hg, wg = desc.grid_shape
    fxy = grid_xy(desc, field).view(hg, wg, 2)
    lin = torch.eye(2, device=fxy.device) - 2 * torch.outer(normal, normal).to(fxy)
    out = []
    for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        shifted = fxy.clone()
        src = fxy[max(dy, 0) : hg + min(dy, 0), max(dx, 0) : wg + min(dx, 0)]
        step = lin @ torch.tensor([dx, dy], dtype=fxy.dtype, device=fxy.device) * desc.stride
        shifted[max(-dy, 0) : hg + min(-dy, 0), max(-dx, 0) : wg + min(-dx, 0)] = src - step
        out.append(grid_index(desc, shifted.view(-1, 2)))
    return out


def patchmatch_iteration(
    state: FieldState,
    desc: DenseDescriptors,
    left_index: torch.Tensor,
    normal: torch.Tensor,
    radius: float,
    n_samples: int,
    generator: torch.Generator,
    *,
    neighbours: bool = True,
    min_gain: float = 0.0,
) -> FieldState:
    """One IRS iteration over all grid points: propagation (Eq. 3.3), random search (Eq. 3.4),
    symmetric update (Eqs. 3.5-3.6).

    Args:
        state: the current field and costs.
        desc: the dense descriptors of the cluster's axis frame.
        left_index: ``(M,)`` flat grid indices of the cluster's left pixels ``L_h``.
        normal: ``(2,)`` unit normal of the cluster's axis (for the neighbour propagation).
        radius: the random-search radius ``r`` in pixels.
        n_samples: the random-search samples ``e``.
        generator: the source of randomness (``torch.Generator``).
        neighbours: also propagate from the 4 grid neighbours.
        min_gain: a random-search sample replaces the estimate only when it lowers the
            cost by more than this.
    """
    n = state.field.shape[0]
    device = desc.values.device
    xy = grid_xy(desc, torch.arange(n, device=device))  # (N, 2)
    best, best_cost = state.field, state.cost
    m = left_index.numel()
    for _ in range(2):  # propagation through two random pairs (p_j, f(p_j))
        j = left_index[torch.randint(0, m, (n,), generator=generator).to(device)]
        cand = grid_index(desc, reflect_through_pairs(xy, grid_xy(desc, j), grid_xy(desc, state.field[j])))
        best, best_cost = _keep_better(best, best_cost, cand, desc)
    if neighbours:
        for cand in _neighbour_candidates(desc, state.field, normal):
            best, best_cost = _keep_better(best, best_cost, cand, desc)
    centre = grid_xy(desc, best)
    for _ in range(n_samples):  # random search around the propagated estimate
        rho = 1 + (radius - 1) * torch.rand(n, generator=generator).to(device)
        psi = 2 * math.pi * torch.rand(n, generator=generator).to(device)
        cand = grid_index(desc, centre + torch.stack([rho * torch.cos(psi), rho * torch.sin(psi)], 1))
        best, best_cost = _keep_better(best, best_cost, cand, desc, min_gain)
    return _claim(best, best_cost)


def _pair_subset(left: torch.Tensor, right: torch.Tensor, max_pairs: int, generator: torch.Generator):
    take = torch.randperm(left.shape[0], generator=generator)[:max_pairs].to(left.device)
    return left[take], right[take]


def mean_mirror_pixel(
    desc: DenseDescriptors, left: torch.Tensor, right: torch.Tensor, max_pairs: int, generator: torch.Generator
) -> FieldState:
    """MMP: each point's mirror is the mean of its reflections through the cluster's pairs."""
    hg, wg = desc.grid_shape
    xy = grid_xy(desc, torch.arange(hg * wg, device=desc.values.device))
    left, right = _pair_subset(left, right, max_pairs, generator)
    total = torch.zeros_like(xy)
    for i in range(left.shape[0]):
        total += reflect_through_pairs(xy, left[i].expand_as(xy), right[i].expand_as(xy))
    field = grid_index(desc, total / max(left.shape[0], 1))
    return FieldState(field, candidate_cost(desc, field))


def best_mirror_pixel(
    desc: DenseDescriptors, left: torch.Tensor, right: torch.Tensor, max_pairs: int, generator: torch.Generator
) -> FieldState:
    """BMP: each point's mirror is its reflection through a cluster pair of lowest cost."""
    hg, wg = desc.grid_shape
    points = torch.arange(hg * wg, device=desc.values.device)
    xy = grid_xy(desc, points)
    left, right = _pair_subset(left, right, max_pairs, generator)
    best = points.clone()
    best_cost = torch.full((hg * wg,), float("inf"), dtype=desc.values.dtype, device=points.device)
    for i in range(left.shape[0]):
        cand = grid_index(desc, reflect_through_pairs(xy, left[i].expand_as(xy), right[i].expand_as(xy)))
        best, best_cost = _keep_better(best, best_cost, cand, desc)
    return FieldState(best, best_cost)


def expand_field(desc: DenseDescriptors, state: FieldState, normal: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """The field at every pixel from the field on the grid, by symmetry coherency (Sec. 3.2.1):
    ``f(p) = f(g) + L (p - g)`` with ``g`` the grid point nearest to ``p`` and ``L = I - 2 n n^T``.

    Returns:
        ``nmrf (H, W, 2)`` float pixel positions (clamped into the image) and ``cost (H * W,)``.
    """
    h, w = desc.height, desc.width
    device = desc.values.device
    ys, xs = torch.meshgrid(torch.arange(h, device=device), torch.arange(w, device=device), indexing="ij")
    p = torch.stack([xs.reshape(-1), ys.reshape(-1)], 1).to(torch.float32)  # (H*W, 2)
    g = grid_index(desc, p)
    lin = torch.eye(2, device=device) - 2 * torch.outer(normal, normal).to(device=device, dtype=torch.float32)
    f = grid_xy(desc, state.field[g]) + (p - grid_xy(desc, g)) @ lin.T
    f = torch.stack([f[:, 0].clamp(0, w - 1), f[:, 1].clamp(0, h - 1)], 1)
    return f.view(h, w, 2), state.cost[g]
