"""Candidate normals: thesis Algorithm 5 (Sec. 5.2.3), and a sphere of normals with a beam search.

``directions="grid"`` scores the thesis's 10 x 10 grid of ``(theta_x, theta_y)`` by the
Frobenius residual; ``directions="sphere"`` scores near-uniform normals with Welsch kernels
and narrows the best by a beam search (see ``docs/design/reflection_plane.md``).
"""

from __future__ import annotations

import math

import torch

from torchsym.geometry.reflection import angles_to_normal, reflect_points, tangent_basis
from torchsym.geometry.sampling import sphere_normals
from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.reflection_plane.settings import InitSettings

__all__ = ["grid_normals", "initial_normals", "score_normals", "sphere_normals"]


def grid_normals(step_deg: float, dtype: torch.dtype) -> torch.Tensor:
    """The (theta_x, theta_y) grid of Algorithm 5, as normals (Eq. 5.1)."""
    angles = torch.arange(-90.0, 90.0 + 1e-9, step_deg, dtype=dtype) * (math.pi / 180.0)
    tx, ty = torch.meshgrid(angles, angles, indexing="ij")
    return angles_to_normal(tx.reshape(-1), ty.reshape(-1))


def score_normals(
    sample: torch.Tensor,
    index: KNNIndex,
    normals: torch.Tensor,
    sigmas: tuple[float, ...] | None,
    coarse_index: KNNIndex | None = None,
):
    """Offsets and costs of planes with ``normals (K, 3)`` through the middle of ``sample (n2, 3)``.

    Each plane passes through the median of the sample's projections on its normal. The
    sample's mirror images are matched in ``index``. The cost is the thesis's Frobenius
    residual (``sigmas=None``), or for each ``sigma`` minus the mean Welsch kernel
    ``exp(-d^2 / 2 sigma^2)`` of the residuals, searched to 4 sigma; kernels after the
    first are evaluated against ``coarse_index`` when given.

    Returns ``offsets (K,)`` and a list of ``(K,)`` costs, one per sigma.
    """
    offsets = -(sample @ normals.T).median(0).values  # (K,)
    refl = reflect_points(sample.expand(normals.shape[0], -1, -1), normals, offsets).reshape(-1, 3)  # (K n2, 3)
    if sigmas is None:
        dist, _ = index.query(refl)
        return offsets, [dist.reshape(normals.shape[0], -1).pow(2).sum(1).sqrt()]
    costs = []
    for i, s in enumerate(sigmas):
        idx = coarse_index if (i > 0 and coarse_index is not None) else index
        dist, _ = idx.query(refl, max_distance=4.0 * s)
        costs.append(-torch.exp(-0.5 * dist.reshape(normals.shape[0], -1).pow(2) / (s * s)).mean(1))
    return offsets, costs


def initial_normals(sample: torch.Tensor, index: KNNIndex, settings: InitSettings, spacing: float):
    """Candidate normals with offsets, ranked (Algorithm 5, refined by a beam search).

    ``directions="grid"``: the thesis's grid, ranked by the Frobenius residual.
    ``directions="sphere"``: ``n_directions`` near-uniform normals scored by a narrow
    (2 spacings) and a wide (8 spacings) Welsch kernel; around the ``n_beam`` best by the
    narrow one, two rounds score six normals at half the previous radius each. The order
    interleaves the two rankings.

    Returns ``(normals (K, 3), offsets (K,), order (K',))``, ``order`` best first.
    """
    dtype = sample.dtype
    n_directions, beam = settings.n_directions, settings.n_beam
    if settings.directions == "grid":
        normals = grid_normals(settings.grid_step, torch.float64).to(device=sample.device, dtype=dtype)
        offsets, (cost,) = score_normals(sample, index, normals, None)
        return normals, offsets, cost.argsort()
    normals = sphere_normals(n_directions).to(device=sample.device, dtype=dtype)
    offsets, (cost, wide) = score_normals(
        sample, index, normals, (2.0 * spacing, 8.0 * spacing), coarse_index=KNNIndex(sample)
    )
    wide_order = wide.argsort()
    radius = math.sqrt(2.0 * math.pi / n_directions) * 0.5  # half the lattice spacing, radians
    ring = torch.linspace(0, 2 * math.pi, 7, dtype=dtype, device=sample.device)[:-1]
    for _ in range(2):
        top = cost.argsort()[:beam]
        base = normals[top]  # (B, 3)
        frame = tangent_basis(base)  # (B, 3, 2)
        u, v = frame[..., 0], frame[..., 1]
        step = math.tan(radius)
        new = base[:, None] + step * (torch.cos(ring)[None, :, None] * u[:, None] + torch.sin(ring)[None, :, None] * v[:, None])
        new = (new / new.norm(dim=-1, keepdim=True)).reshape(-1, 3)
        new_off, (new_cost,) = score_normals(sample, index, new, (2.0 * spacing,))
        normals = torch.cat([normals, new])
        offsets = torch.cat([offsets, new_off])
        cost = torch.cat([cost, new_cost])
        radius *= 0.5
    narrow_order = cost.argsort()
    order = torch.stack([narrow_order[: len(wide_order)], wide_order], 1).reshape(-1)
    return normals, offsets, order
