"""Robust point-to-plane pre-alignment of a start, and the support that ranks starts.

An extension of thesis Sec. 5.2.3 (see ``docs/design/reflection_plane.md``). Points are
normalised to a unit bounding-box diagonal; planes are ``(normal (3,), offset ())``.
"""

from __future__ import annotations

import math

import torch

from torchsym.geometry.reflection import plane_angle, reflect_points, tangent_basis
from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.neighbourhood import SUPPORT_REACH, neighbourhood_pca
from torchsym.optim.convergence import remaining_factor

__all__ = ["local_pca", "point_normals", "point_to_plane_step", "pre_align", "support"]


def local_pca(points: torch.Tensor, index: KNNIndex, k: int = 10) -> tuple[torch.Tensor, torch.Tensor]:
    """Eigenvalues ``(N, 3)`` (ascending) and eigenvectors ``(N, 3, 3)`` (columns) of the
    scatter matrix of each point's ``k`` nearest neighbours."""
    return neighbourhood_pca(points, index, points, k)[1:]


def point_normals(points: torch.Tensor, index: KNNIndex, k: int = 10) -> torch.Tensor:
    """``(N, 3)`` unit surface normals by PCA of each point's ``k`` nearest neighbours."""
    return local_pca(points, index, k)[1][:, :, 0]


def point_to_plane_step(x, q, nu, normal, offset, robust: bool):
    """One Gauss-Newton step for the plane minimising ``sum w_i (nu_i . (reflect(x_i) - q_i))^2``.

    ``x, q, nu (N, 3)``: points, their matches and the matches' normals. The normal moves
    in its tangent plane, the offset freely; Cauchy weights with scale 2.5 x the median
    absolute residual (``robust=False``: all 1). Returns ``(normal (3,), offset (),
    standard error ())``: the standard error of the new normal in radians, from the
    Gauss-Newton covariance ``s^2 (J^T W J)^-1`` with ``s^2`` the weighted residual variance.
    """
    dtype = x.dtype
    basis = tangent_basis(normal)  # (3, 2)
    signed = x @ normal + offset  # (N,)
    nun = nu @ normal  # (N,)
    r = ((x - q) * nu).sum(1) - 2.0 * signed * nun  # (N,) = nu . (reflect(x) - q)
    jac = -2.0 * torch.cat([nun[:, None] * (x @ basis) + signed[:, None] * (nu @ basis), nun[:, None]], 1)  # (N, 3)
    if robust:
        s = 2.5 * r.abs().median().clamp_min(torch.finfo(dtype).eps)
        w = 1.0 / (1.0 + (r / s) ** 2)
    else:
        w = torch.ones_like(r)
    jw = jac * w[:, None]
    cov = torch.linalg.pinv(jw.T @ jac + 1e-12 * torch.eye(3, dtype=dtype, device=x.device))  # (3, 3)
    step = -(cov @ (jw.T @ r))  # (3,)
    m = normal + basis @ step[:2]
    norm = m.norm()
    # the largest eigenvalue of the normal's 2 x 2 covariance block, and s^2, from one transfer
    c00, c01, c11, energy, wsum = torch.stack([cov[0, 0], cov[0, 1], cov[1, 1], (w * r * r).sum(), w.sum()]).tolist()
    top = 0.5 * (c00 + c11) + math.sqrt(0.25 * (c00 - c11) ** 2 + c01 * c01)
    se = math.sqrt(energy / max(wsum - 3.0, 1.0) * max(top, 0.0))
    return m / norm, (offset + step[2]) / norm, se


def pre_align(queries, targets, index, nu, normal, offset, *, max_iters: int, tol_angle: float, tol_se: float = 0.0):
    """Point-to-plane Gauss-Newton from one start: mirror images of ``queries (Q, 3)``
    matched in ``targets (M, 3)`` (normals ``nu (M, 3)``, ``index`` over ``targets``),
    until the normal moves less than ``tol_angle`` degrees or ``tol_se`` standard errors of
    the step's fit, whichever is larger (the step counted with what is left to go,
    :func:`~torchsym.optim.convergence.remaining_factor`), or after
    ``max_iters`` steps.

    Returns ``(normal, offset, steps)``.
    """
    it = 0
    prev_step = None
    for it in range(1, max_iters + 1):
        _, j = index.query(reflect_points(queries, normal, offset))
        n_new, b_new, se = point_to_plane_step(queries, targets[j], nu[j], normal, offset, robust=True)
        if float((n_new * normal).sum()) < 0:
            n_new, b_new = -n_new, -b_new
        moved = float(plane_angle(n_new, normal)) * 180.0 / math.pi
        step = n_new - normal
        ahead = remaining_factor(step, prev_step) if tol_se > 0 else 1.0
        normal, offset, prev_step = n_new, b_new, step
        if moved * ahead < max(tol_angle, tol_se * math.degrees(se)):
            break
    return normal, offset, it




def support(points, index, normal, offset, sigma: float) -> tuple[float, float]:
    """Soft share of ``points (N, 3)`` whose mirror image lands near the set (mean of
    ``exp(-d^2 / 2 sigma^2)`` over residuals ``d``), and the median residual (inf when
    more than half lie beyond ``SUPPORT_REACH`` sigma, which are not searched for: far
    queries are the slow ones)."""
    d, _ = index.query(reflect_points(points, normal, offset), max_distance=SUPPORT_REACH * sigma)
    return float(torch.exp(-0.5 * (d / sigma) ** 2).mean()), float(d.median())
