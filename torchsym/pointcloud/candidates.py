"""Candidate reflection planes of a point cloud: the initialisation of thesis Sec. 5.2.3.

Algorithm 5 scores a 10 x 10 grid of (theta_x, theta_y) rotation angles on a 500-point
sample by the Frobenius residual of nearest mirror images. ``init="grid"`` keeps that;
``init="sphere"`` scores a near-uniform set of normals with robust kernels and narrows
the best with a beam search (see :func:`initial_normals`).
"""

from __future__ import annotations

import math

import torch

from torchsym.geometry.reflection import angles_to_normal, reflect_points, tangent_basis
from torchsym.geometry.sampling import sphere_normals
from torchsym.matching.knn import KNNIndex

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
    """Offsets and costs of planes with the given normals through the sample's middle.

    Each plane passes through the median of the sample's projections on its normal: the
    centre of a symmetric 1-D distribution, robust to outliers and, unlike Algorithm 5's
    coordinate-wise median, unchanged by rotating the cloud. Mirror images of the sample
    are matched in the denser refinement subsample (against the sample itself, sampling
    gaps hide the difference between good and bad planes). The cost is the thesis's
    Frobenius norm (``sigmas=None``), or for each ``sigma`` minus the mean Welsch kernel
    ``exp(-d^2 / 2 sigma^2)`` of the residuals ``d``: bounded, so outliers cannot dominate
    it, and smooth, so a plane a few degrees off still scores (the median residual, tried
    first, ranked the true basin badly on shapes with strong partial symmetries).

    Searches stop at 4 sigma, where the kernel is below 1e-3. Kernels wider than the
    first are evaluated against ``coarse_index`` when given (a sparser set: the wide
    kernel does not need the density, and far searches in a small tree are cheap).

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


def initial_normals(
    sample: torch.Tensor,
    index: KNNIndex,
    *,
    init: str,
    n_directions: int,
    grid_step: float,
    beam: int,
    spacing: float,
    dtype: torch.dtype,
):
    """Candidate normals with offsets, ranked (Algorithm 5, refined by a beam search).

    ``init="grid"`` scores the thesis's (theta_x, theta_y) grid by the Frobenius residual
    and stops there. ``init="sphere"`` scores ``n_directions`` near-uniform normals with
    two Welsch kernels: a narrow one (2 point spacings), which outliers cannot fool, and a
    wide one (8 spacings), which still rewards a plane a few degrees off on clean thin
    shapes. Around the ``beam`` best by the narrow kernel, two rounds score six normals
    at half the previous radius each. The result interleaves the two rankings.

    Returns ``(normals (K, 3), offsets (K,), order)`` with ``order`` the candidates' indices,
    best first.
    """
    if init == "grid":
        normals = grid_normals(grid_step, torch.float64).to(device=sample.device, dtype=dtype)
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
