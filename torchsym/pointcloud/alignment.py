"""The alternating steps of thesis Algorithm 6 and the point-to-plane pre-alignment.

Every function works on points normalised to a unit bounding-box diagonal and returns
planes as ``(normal (3,), offset ())``.
"""

from __future__ import annotations

import math

import torch

from torchsym.geometry.reflection import (
    plane_angle,
    plane_from_pairs,
    plane_from_reflection,
    reflect_points,
    tangent_basis,
)
from torchsym.matching.knn import KNNIndex, mutual_nearest

__all__ = [
    "alternate",
    "kernel_refine",
    "kernel_score",
    "local_pca",
    "point_normals",
    "pre_align",
    "support",
    "surface_variation",
]

# Progress of Algorithm 6 (extrapolation, stall detection, the best plane kept) is judged
# by this quantile of the residuals. The median is an outlier's residual once outliers are
# half the cloud and stays flat while the surface aligns; the lower quartile still moves
# (at 200 % outliers it took the share of planes within 1 degree from 0.44 to 0.82).
PROGRESS_QUANTILE = 0.25


def local_pca(points: torch.Tensor, index: KNNIndex, k: int = 10) -> tuple[torch.Tensor, torch.Tensor]:
    """Eigenvalues ``(N, 3)`` (ascending) and eigenvectors ``(N, 3, 3)`` (columns) of the
    scatter matrix of each point's ``k`` nearest neighbours."""
    _, j = index.query(points, k=min(k, points.shape[0]))
    nb = points[j]  # (N, k, 3)
    nb = nb - nb.mean(1, keepdim=True)
    return torch.linalg.eigh(nb.transpose(1, 2) @ nb)


def point_normals(points: torch.Tensor, index: KNNIndex, k: int = 10) -> torch.Tensor:
    """``(N, 3)`` unit surface normals by PCA of each point's ``k`` nearest neighbours."""
    return local_pca(points, index, k)[1][:, :, 0]


def point_to_plane_step(x, q, nu, normal, offset, robust: bool):
    """One Gauss-Newton step for the plane minimising ``sum w_i (nu_i . (reflect(x_i) - q_i))^2``.

    The normal moves in its tangent plane (two parameters) and the offset freely. Weights
    are Cauchy's, ``1 / (1 + (r / s)^2)`` with ``s`` 2.5 times the median absolute
    residual, so outliers pull little; ``robust=False`` weighs all pairs 1.
    """
    dtype = x.dtype
    basis = tangent_basis(normal)  # (3, 2)
    signed = x @ normal + offset  # (N,)
    r = ((x - 2.0 * signed[:, None] * normal - q) * nu).sum(1)  # (N,)
    nun = nu @ normal
    jac = -2.0 * torch.cat([nun[:, None] * (x @ basis) + signed[:, None] * (nu @ basis), nun[:, None]], 1)  # (N, 3)
    if robust:
        s = 2.5 * r.abs().median().clamp_min(torch.finfo(dtype).eps)
        w = 1.0 / (1.0 + (r / s) ** 2)
    else:
        w = torch.ones_like(r)
    a = (jac * w[:, None]).T @ jac
    g = (jac * w[:, None]).T @ r
    step = -torch.linalg.lstsq(a + 1e-12 * torch.eye(3, dtype=dtype, device=x.device), g[:, None]).solution[:, 0]
    m = normal + basis @ step[:2]
    norm = m.norm()
    return m / norm, (offset + step[2]) / norm


def pre_align(queries, targets, index, nu, normal, offset, *, max_iter: int, tol_angle: float):
    """Point-to-plane Gauss-Newton from one start: mirror images of ``queries`` matched in
    ``targets`` (normals ``nu``); returns ``(normal, offset, iterations)``."""
    it = 0
    for it in range(1, max_iter + 1):
        _, j = index.query(reflect_points(queries, normal, offset))
        n_new, b_new = point_to_plane_step(queries, targets[j], nu[j], normal, offset, robust=True)
        if float((n_new * normal).sum()) < 0:
            n_new, b_new = -n_new, -b_new
        moved = float(plane_angle(n_new, normal)) * 180.0 / math.pi
        normal, offset = n_new, b_new
        if moved < tol_angle:
            break
    return normal, offset, it


def support(points, index, normal, offset, sigma: float):
    """Soft share of points whose mirror image lands near the set: the mean of
    ``exp(-d^2 / 2 sigma^2)`` over residuals ``d`` (a continuous inlier fraction), and the
    median residual."""
    d, _ = index.query(reflect_points(points, normal, offset))
    return float(torch.exp(-0.5 * (d / sigma) ** 2).mean()), float(d.median())


def surface_variation(
    points: torch.Tensor, index: KNNIndex, k: int = 10, *, eigenvalues: torch.Tensor | None = None
) -> float:
    """Median over points of ``l_min / (l_1 + l_2 + l_3)``, the eigenvalues of the covariance
    of each point's ``k`` nearest neighbours (Pauly et al.'s surface variation): near 0 on a
    sampled surface, about 0.13 once noise thickens it into a shell (thesis 5.2.4's
    perturbation from w = 20 on the benchmark's clouds; clean clouds there 0.005 to 0.08).
    ``eigenvalues``: those of :func:`local_pca`, when already computed."""
    lam = eigenvalues if eigenvalues is not None else local_pca(points, index, k)[0]  # (N, 3) ascending
    return float((lam[:, 0] / lam.sum(1).clamp_min(torch.finfo(lam.dtype).tiny)).median())


def kernel_score(points, index, normal, offset, width: float, k: int = 8):
    """Kernel correlation of a set with its reflection: the mean over points of
    ``sum_j exp(-|S p_i - p_j|^2 / 2 width^2)`` over the ``k`` nearest ``p_j`` of each
    reflected point (Tsin and Kanade's kernel correlation, truncated to ``k`` neighbours).

    On a noisy symmetric set every noisy mirror point lies within a few ``width`` of the
    reflected point, rarely nearest to it, so a nearest-neighbour residual compares each
    point with an arbitrary neighbour while the kernel sums over all of them.

    ``normal (3,)`` and ``offset ()`` give a float; ``normal (K, 3)`` and ``offset (K,)``
    score ``K`` planes with one neighbour query and give a ``(K,)`` tensor.
    """
    moved = reflect_points(points, normal, offset)  # (..., N, 3)
    k = min(k, index.points.shape[0])
    d, _ = index.query(moved.reshape(-1, moved.shape[-1]), k=k)  # (... N, k)
    value = torch.exp(-0.5 * (d.reshape(*moved.shape[:-1], k) / width) ** 2).sum(-1).mean(-1)  # (...)
    return float(value) if value.dim() == 0 else value


def kernel_refine(points, index, normal, offset, width: float, *, k: int = 8, max_iter: int = 15, tol_angle: float = 0.01):
    """Maximise :func:`kernel_score` from ``(normal, offset)`` by reweighted least squares.

    Each step pairs every point with the ``k`` nearest points to its reflection, weighted
    by ``exp(-d^2 / 2 width^2)``, and fits the least-squares reflection to the weighted
    pairs (:func:`~torchsym.geometry.reflection.plane_from_pairs`, Eq. 5.6): a
    minorise-maximise step (the weights are not normalised per point, unlike coherent
    point drift's EM), i.e. soft-assignment ICP for the symmetric case. Stops when the
    normal moves less than ``tol_angle`` degrees, or when every weight is 0.

    Returns:
        ``(normal, offset, steps)``: ``steps`` fits made.
    """
    k = min(k, index.points.shape[0])
    steps = 0
    for _ in range(max_iter):
        d, j = index.query(reflect_points(points, normal, offset), k=k)  # (N, k)
        w = torch.exp(-0.5 * (d / width) ** 2).reshape(-1)  # (N k,)
        if not bool(w.sum() > 0):
            break
        steps += 1
        src = points.repeat_interleave(k, dim=0)  # (N k, 3) each point k times
        new_n, new_b = plane_from_pairs(src, index.points[j.reshape(-1)].to(points.dtype), w.to(points.dtype))
        if float(new_n @ normal) < 0:
            new_n, new_b = -new_n, -new_b
        moved = math.degrees(float(plane_angle(new_n, normal)))
        normal, offset = new_n, new_b
        if moved < tol_angle:
            break
    return normal, offset, steps


def _lower_quantile(values: torch.Tensor, q: float) -> torch.Tensor:
    """The order statistic at quantile ``q`` of a 1-D tensor, rounded down (no interpolation).

    ``kthvalue`` selects in linear time; ``torch.quantile`` sorts and refuses more than
    2^24 values, which a polish on a large scan exceeds.
    """
    return values.kthvalue(max(1, int(q * (values.numel() - 1)) + 1)).values


def fit_pairs(points: torch.Tensor, nn_idx: torch.Tensor, keep: torch.Tensor, update: str, center: torch.Tensor):
    """Refit the plane to the kept pairs ``(i, nn_idx[i])``."""
    p = points[keep]
    q = points[nn_idx[keep]]
    if update == "reflection":
        return plane_from_pairs(p, q)
    # Thesis Algorithm 6, steps 9-12: S from the SVD of the cross-covariance about c,
    # then c from (I - S) c = (I - S)(S p + q) / 2 averaged; the plane is read off S.
    pc, qc = p - center, q - center
    w = qc.T @ pc  # (3, 3)
    u, _, vh = torch.linalg.svd(w)
    s = u @ vh
    if torch.det(s) > 0:  # closest orthogonal matrix with det -1
        u = u.clone()
        u[:, -1] = -u[:, -1]
        s = u @ vh
    n, _ = plane_from_reflection(s)
    # The c-step: only n . c is determined, by the mean of (n . (S p) + n . q) / 2.
    rhs = 0.5 * ((p @ s.T) + q).mean(0)
    c = center + n * ((rhs - center) @ n)
    return n, -(n * c).sum()


def alternate(
    points: torch.Tensor,
    index: KNNIndex,
    normal: torch.Tensor,
    offset: torch.Tensor,
    *,
    update: str,
    max_iter: int,
    tol_angle: float,
    tol_offset: float,
    accelerate: bool,
    patience: int = 5,
    max_residual: float = float("inf"),
):
    """Algorithm 6 on ``points`` (queried against ``index`` over the same points).

    Each step pairs every point with the nearest neighbour of its mirror image, keeps
    the mutual pairs whose residual is at most the median (the truncated L2 loss of
    Sec. 5.2.3), and refits the plane. Nearest-neighbour pairs slide along smooth
    surfaces, so far from the optimum the plane creeps by a near-constant small angle
    per step. With ``accelerate`` the step is extrapolated (x2, x4, ... as in Besl and
    McKay's accelerated ICP) while the progress residual (the ``PROGRESS_QUANTILE``
    quantile of all residuals) keeps falling; an extrapolated step is taken only when it
    lowers that residual.

    It ends when a step moves the normal less than ``tol_angle`` degrees and the offset
    less than ``tol_offset`` (converged; that last step is taken, and the residuals
    returned are those it was fitted from), or after ``patience`` steps without a lower progress
    residual (not converged; the best plane seen is returned).

    Returns ``(normal, offset, iterations, converged, progress residual, residuals,
    nearest indices)``. The last three are for the returned plane when the run stalled
    (then the residuals are None), and for the plane before the last step when it
    converged (that step moved it less than the tolerances).
    """

    def evaluate(n_: torch.Tensor, b_: torch.Tensor):
        d_, j_ = index.query(reflect_points(points, n_, b_))
        return d_, j_, _lower_quantile(d_, PROGRESS_QUANTILE)

    converged = False
    it = 0
    dist, nn_idx, med = evaluate(normal, offset)
    best = (normal, offset, med)
    stalled = 0
    for it in range(1, max_iter + 1):
        mutual = mutual_nearest(nn_idx, nn_idx)  # same set both ways: free mutual test
        # Trim at the median residual of the mutual pairs (thesis: of all pairs). Outliers
        # are rarely mutual, so with many of them the median over all pairs is an
        # outlier's residual and would keep outlier pairs in the fit.
        keep = mutual & (dist <= dist[mutual].median()) if bool(mutual.any()) else dist <= dist.median()
        # Pairs farther apart than `max_residual` (the inlier tolerance) are dropped too,
        # while at least a tenth of the points stay: at heavy outlier rates some outlier
        # pairs pass the median and bias the plane by degrees. The cut widens to 3x the
        # lower quartile of the mutual residuals while the plane is still off: a cut below
        # the surface pairs' own residuals keeps only pairs near the axis of the error,
        # which hardly constrain it, and the alternation stalls short of the optimum.
        if bool(mutual.any()):
            lower = _lower_quantile(dist[mutual], 0.25)
            cut = max(max_residual, 3.0 * float(lower))
        else:
            cut = max_residual
        tight = keep & (dist <= cut)
        if int(tight.sum()) >= max(3, points.shape[0] // 10):
            keep = tight
        if int(keep.sum()) < 3:
            keep = dist <= dist.median()
        center = 0.5 * (points[keep] + points[nn_idx[keep]]).mean(0)
        n_new, b_new = fit_pairs(points, nn_idx, keep, update, center)
        if float((n_new * normal).sum()) < 0:
            n_new, b_new = -n_new, -b_new
        d_angle = float(plane_angle(n_new, normal)) * 180.0 / math.pi
        d_off = float((b_new - offset).abs())
        if d_angle < tol_angle and d_off < tol_offset:
            # Converged: the step moved the plane less than the tolerances. The residuals
            # and neighbours returned are those of the previous plane (they moved by at
            # most the tolerances): one full nearest-neighbour query saved per run.
            return n_new, b_new, it, True, med, dist, nn_idx
        d_new, j_new, m_new = evaluate(n_new, b_new)
        if accelerate and float(plane_angle(n_new, normal)) * 180.0 / math.pi > 50 * tol_angle:
            dn, db = n_new - normal, b_new - offset
            alpha = 2.0
            while alpha <= 64.0:
                n_try = normal + alpha * dn
                scale = n_try.norm()
                n_try, b_try = n_try / scale, (offset + alpha * db) / scale
                d_try, j_try, m_try = evaluate(n_try, b_try)
                if not bool(m_try < m_new):
                    break
                n_new, b_new, d_new, j_new, m_new = n_try, b_try, d_try, j_try, m_try
                alpha *= 2.0
        normal, offset, dist, nn_idx, med = n_new, b_new, d_new, j_new, m_new
        # With outliers or noise the trimmed set can wander without settling: stop after
        # `patience` steps that do not lower the progress residual, keeping the best plane.
        if bool(med < best[2]):
            best, stalled = (normal, offset, med), 0
        else:
            stalled += 1
            if stalled >= patience:
                normal, offset, med = best
                dist, nn_idx = None, None
                break
    return normal, offset, it, converged, med, dist, nn_idx
