"""Kernel-correlation refinement of the plane, for clouds thickened by noise (an extension).

When almost no point has an exact mirror and noise has thickened the surface, the plane
is refined by maximising the kernel correlation of the cloud's dense part with its
reflection (see ``docs/design/reflection_plane.md``). Points are normalised to a unit
bounding-box diagonal; planes are ``(normal (3,), offset ())``.
"""

from __future__ import annotations

import math

import torch

from torchsym.geometry.reflection import plane_angle, reflect_points, reflection_fit, spread_normals
from torchsym.matching.knn import KNNIndex
from torchsym.geometry.sampling import sphere_normals
from torchsym.optim.convergence import remaining_factor
from torchsym.pointcloud.reflection_plane.prealign import local_pca

__all__ = ["kernel_refine", "kernel_score", "needs_kernel", "refine_by_kernel", "surface_variation"]


def surface_variation(
    points: torch.Tensor, index: KNNIndex, k: int = 10, *, eigenvalues: torch.Tensor | None = None
) -> float:
    """Median over ``points (N, 3)`` of ``l_min / (l_1 + l_2 + l_3)`` of the covariance of
    each point's ``k`` nearest neighbours (Pauly et al.): near 0 on a sampled surface,
    larger once noise thickens it. ``eigenvalues (N, 3)``: those of :func:`local_pca`."""
    lam = eigenvalues if eigenvalues is not None else local_pca(points, index, k)[0]  # (N, 3) ascending
    return float((lam[:, 0] / lam.sum(1).clamp_min(torch.finfo(lam.dtype).tiny)).median())


def kernel_score(points, index, normal, offset, width: float, k: int = 8):
    """Kernel correlation of ``points (N, 3)`` with their reflection: the mean over points of
    ``sum_j exp(-|S p_i - p_j|^2 / 2 width^2)`` over the ``k`` nearest ``p_j`` of each
    reflected point (Tsin and Kanade, truncated to ``k`` neighbours).

    ``normal (3,)``, ``offset ()`` give a float; ``normal (K, 3)``, ``offset (K,)`` give a
    ``(K,)`` tensor from one neighbour query.
    """
    moved = reflect_points(points, normal, offset)  # (..., N, 3)
    k = min(k, index.points.shape[0])
    d, _ = index.query(moved.reshape(-1, moved.shape[-1]), k=k)  # (... N, k)
    value = torch.exp(-0.5 * (d.reshape(*moved.shape[:-1], k) / width) ** 2).sum(-1).mean(-1)  # (...)
    return float(value) if value.dim() == 0 else value


def kernel_refine(
    points, index, normal, offset, width: float, *, k: int = 8, max_iters: int = 15, tol_angle: float = 0.01, tol_se: float = 0.0
):
    """Maximise :func:`kernel_score` from ``(normal, offset)`` by reweighted least squares.

    Each step pairs every point with the ``k`` nearest points to its reflection, weighted
    by ``exp(-d^2 / 2 width^2)``, and fits the least-squares reflection (Eq. 5.6) to the
    weighted pairs. Stops when the normal moves less than ``tol_angle`` degrees or
    ``tol_se`` standard errors of the weighted fit, whichever is larger, after ``max_iters``
    steps, or when every weight is 0.

    Returns:
        ``(normal, offset, steps)``: ``steps`` fits made.
    """
    k = min(k, index.points.shape[0])
    steps = 0
    prev_step = None
    for _ in range(max_iters):
        d, j = index.query(reflect_points(points, normal, offset), k=k)  # (N, k)
        w = torch.exp(-0.5 * (d / width) ** 2).reshape(-1)  # (N k,)
        if not bool(w.sum() > 0):
            break
        steps += 1
        src = points.repeat_interleave(k, dim=0)  # (N k, 3) each point k times
        dst, w = index.points[j.reshape(-1)].to(points.dtype), w.to(points.dtype)
        new_n, new_b, se, _ = reflection_fit(src, dst, w)
        if float(new_n @ normal) < 0:
            new_n, new_b = -new_n, -new_b
        moved = math.degrees(float(plane_angle(new_n, normal)))
        step = new_n - normal
        ahead = remaining_factor(step, prev_step) if tol_se > 0 else 1.0
        normal, offset, prev_step = new_n, new_b, step
        tol = max(tol_angle, tol_se * math.degrees(float(se)))
        if moved * ahead < tol:
            break
    return normal, offset, steps


def needs_kernel(dist, tol: float, points, index, eigenvalues, settings) -> bool:
    """Whether the kernel stage runs: ``settings.enabled``, fewer than ``max_exact_share``
    of the residuals ``dist (N,)`` below ``exact_factor * tol``, and the surface variation
    of ``points (M, 3)`` (local PCA ``eigenvalues (M, 3)`` when known) above ``min_variation``."""
    return (
        settings.enabled
        and float((dist < settings.exact_factor * tol).double().mean()) < settings.max_exact_share
        and surface_variation(points, index, eigenvalues=eigenvalues) > settings.min_variation
    )


def refine_by_kernel(
    points, index, normal, offset, starts, settings, *, n_directions: int, min_separation: float, tol_se: float = 0.0
):
    """The plane of highest kernel correlation of ``points (N, 3)`` (``index`` over them).

    Refines ``(normal, offset)``, the planes ``starts`` and the ``settings.n_scan_starts``
    best of ``n_directions`` sphere normals by kernel score (planes through the centroid,
    at least ``min_separation`` degrees apart) for ``settings.max_iters`` steps each, then
    the best to ``settings.final_max_iters``. The kernel width is ``settings.width_factor``
    x the median residual of ``(normal, offset)``; ``tol_se`` as in :func:`kernel_refine`.

    Returns ``(normal, offset, refined)``; ``refined`` is False (the plane unchanged) when
    that width is 0.
    """
    k = settings.n_neighbors
    width = settings.width_factor * float(index.query(reflect_points(points, normal, offset))[0].median())
    if not width > 0:
        return normal, offset, False
    centroid = points.mean(0)
    cand = sphere_normals(n_directions, dtype=points.dtype).to(points.device)
    values = kernel_score(points, index, cand, -(cand @ centroid), width, k=k)  # (n_directions,)
    best = spread_normals(cand, values.argsort(descending=True), settings.n_scan_starts, min_separation)
    scan = [(cand[j], -(cand[j] @ centroid)) for j in best]
    chosen = None
    for nk, bk in [(normal, offset), *starts, *scan]:
        nk, bk, _ = kernel_refine(
            points, index, nk, bk, width, k=k, max_iters=settings.max_iters, tol_angle=settings.tol_angle, tol_se=tol_se
        )
        value = kernel_score(points, index, nk, bk, width, k=k)
        if chosen is None or value > chosen[0]:
            chosen = (value, nk, bk)
    normal, offset, _ = kernel_refine(
        points, index, chosen[1], chosen[2], width, k=k, max_iters=settings.final_max_iters, tol_angle=settings.tol_angle,
        tol_se=tol_se,
    )
    return normal, offset, True
