"""Many planes aligned at once: batched point-to-plane Gauss-Newton (an extension of
thesis Sec. 5.2.3, the batched form of :func:`~torchsym.pointcloud.reflection_plane.prealign.pre_align`).

Every start is refined by the same robust point-to-plane steps as the one-plane
detector's pre-alignment, but all planes share each nearest-neighbour query, so ``K``
planes cost about one query of ``K x Q`` points per step instead of ``K`` queries.
Points are normalised (unit bounding-box diagonal); planes are ``normals (K, 3)``,
``offsets (K,)``.
"""

from __future__ import annotations

import math

import torch

from torchsym.geometry.reflection import tangent_basis
from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.neighbourhood import SUPPORT_REACH, neighbourhood_pca

__all__ = ["align_planes", "nearest_surface", "plane_supports", "reflect_in_planes", "surface_patches"]


def reflect_in_planes(points: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    """``(K, Q, 3)``: ``points (Q, 3)`` reflected in each plane ``normals (K, 3)``, ``offsets (K,)``."""
    signed = points @ normals.T + offsets  # (Q, K)
    return points[None] - 2.0 * signed.T[:, :, None] * normals[:, None, :]


def nearest_surface(targets: torch.Tensor, index: KNNIndex, target_normals: torch.Tensor):
    """A matcher for :func:`align_planes`: each point's nearest target ``(M, 3)`` and its
    surface normal ``target_normals (M, 3)``."""

    def match(moved: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        _, j = index.query(moved)
        return targets[j], target_normals[j]

    return match


def surface_patches(points: torch.Tensor, index: KNNIndex, k: int):
    """A matcher for :func:`align_planes`: the centroid of each point's ``k`` nearest
    ``points`` and their least-variance direction (the local surface, which the noise
    across it hardly draws towards the query)."""

    def match(moved: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        centroid, _, vecs = neighbourhood_pca(points, index, moved, k)
        return centroid, vecs[:, :, 0]

    return match


def _gauss_newton_step(x, q, nu, normals, offsets):
    """One robust point-to-plane step per plane: ``x (Q, 3)``, matches ``q, nu (K, Q, 3)``.
    Cauchy weights at 2.5 x each plane's median absolute residual, as ``point_to_plane_step``."""
    basis = tangent_basis(normals)  # (K, 3, 2)
    signed = x @ normals.T + offsets  # (Q, K)
    signed = signed.T  # (K, Q)
    nun = (nu * normals[:, None, :]).sum(-1)  # (K, Q)
    r = ((x[None] - q) * nu).sum(-1) - 2.0 * signed * nun  # (K, Q)
    xb = x[None] @ basis  # (K, Q, 2)
    nub = nu @ basis  # (K, Q, 2)
    jac = -2.0 * torch.cat([nun[..., None] * xb + signed[..., None] * nub, nun[..., None]], -1)  # (K, Q, 3)
    s = 2.5 * r.abs().median(1, keepdim=True).values.clamp_min(torch.finfo(x.dtype).eps)
    w = 1.0 / (1.0 + (r / s) ** 2)
    jw = jac * w[..., None]
    eye = torch.eye(3, dtype=x.dtype, device=x.device)
    h = jw.transpose(1, 2) @ jac + 1e-12 * eye  # (K, 3, 3)
    step = -(torch.linalg.pinv(h) @ (jw * r[..., None]).sum(1)[..., None])[..., 0]  # (K, 3)
    m = normals + (basis @ step[:, :2, None])[..., 0]
    norm = m.norm(dim=1)
    return m / norm[:, None], (offsets + step[:, 2]) / norm


def align_planes(queries, match, normals, offsets, *, max_iters: int, tol_angle: float):
    """Refine every plane ``normals (K, 3)``, ``offsets (K,)`` by robust point-to-plane
    Gauss-Newton steps: the mirror images of ``queries (Q, 3)`` are matched by
    ``match`` (:func:`nearest_surface` or :func:`surface_patches`; one call per step for
    all planes). Stops when no normal moves more than ``tol_angle`` degrees, or after
    ``max_iters`` steps.

    Returns ``(normals (K, 3), offsets (K,))``.
    """
    k, nq = normals.shape[0], queries.shape[0]
    if k == 0:
        return normals, offsets
    active = torch.ones(k, dtype=torch.bool, device=normals.device)
    cos_tol = math.cos(math.radians(tol_angle))
    for _ in range(max_iters):
        idx = active.nonzero()[:, 0]
        n, b = normals[idx], offsets[idx]
        q, nu = match(reflect_in_planes(queries, n, b).reshape(-1, 3))
        n_new, b_new = _gauss_newton_step(queries, q.reshape(-1, nq, 3), nu.reshape(-1, nq, 3), n, b)
        flip = (n_new * n).sum(1) < 0
        n_new = torch.where(flip[:, None], -n_new, n_new)
        b_new = torch.where(flip, -b_new, b_new)
        normals, offsets = normals.index_copy(0, idx, n_new), offsets.index_copy(0, idx, b_new)
        still = (n_new * n).sum(1).clamp(-1, 1) < cos_tol
        active = active.index_copy(0, idx, still)
        if not bool(active.any()):
            break
    return normals, offsets


def plane_supports(points, index: KNNIndex, normals, offsets, sigma: float) -> torch.Tensor:
    """``(K,)`` soft share of ``points (Q, 3)`` whose mirror image in each plane lands near
    the set behind ``index`` (mean of ``exp(-d^2 / 2 sigma^2)``), as the one-plane
    detector's ``support``, for all planes from one query."""
    moved = reflect_in_planes(points, normals, offsets).reshape(-1, 3)
    d, _ = index.query(moved, max_distance=SUPPORT_REACH * sigma)
    return torch.exp(-0.5 * (d.reshape(normals.shape[0], -1) / sigma) ** 2).mean(1)
