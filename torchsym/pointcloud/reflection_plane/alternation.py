"""Thesis Algorithm 6: alternate mirror correspondences and the plane that fits them (Sec. 5.2.3).

Every function works on points normalised to a unit bounding-box diagonal and returns
planes as ``(normal (3,), offset ())``.
"""

from __future__ import annotations

import math

import torch

from torchsym.geometry.reflection import pair_fit_errors, plane_angle, plane_from_pairs, plane_from_reflection, reflect_points
from torchsym.matching.knn import KNNIndex, mutual_nearest
from torchsym.optim.convergence import remaining_factor
from torchsym.pointcloud.reflection_plane.settings import AlternationSettings

__all__ = ["alternate", "fit_pairs", "kept_pairs", "lower_quantile", "step_tolerances"]

#: quantile of the residuals that judges progress (extrapolation, stalls, the best plane)
PROGRESS_QUANTILE = 0.25


def lower_quantile(values: torch.Tensor, q: float) -> torch.Tensor:
    """The order statistic at quantile ``q`` of a 1-D tensor, rounded down (no interpolation;
    linear time, and no limit on the size unlike ``torch.quantile``)."""
    return values.kthvalue(max(1, int(q * (values.numel() - 1)) + 1)).values


def fit_pairs(points: torch.Tensor, nn_idx: torch.Tensor, keep: torch.Tensor, update: str, center: torch.Tensor):
    """The plane ``(normal (3,), offset ())`` fitted to the pairs ``(i, nn_idx[i])`` kept by ``keep (N,)``.

    ``update="reflection"``: the exact least-squares reflection (Eq. 5.6);
    ``"procrustes"``: Algorithm 6, steps 9-12, about ``center (3,)``.
    """
    p = points[keep]
    q = points[nn_idx[keep]]
    if update == "reflection":
        return plane_from_pairs(p, q)
    # S from the SVD of the cross-covariance about c, then c from
    # (I - S) c = (I - S)(S p + q) / 2 averaged; the plane is read off S.
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


def step_tolerances(
    points: torch.Tensor, mirrors: torch.Tensor, tol_angle: float, tol_offset: float, tol_se: float, weights=None
) -> tuple[float, float]:
    """The angle (degrees) and offset moves below which a step counts as converged: the
    absolute tolerances, or ``tol_se`` standard errors of the reflection fitted to the pairs
    ``points, mirrors (M, 3)`` (weights ``(M,)``; :func:`~torchsym.geometry.pair_fit_errors`),
    whichever is larger. A fit cannot locate the plane better than its residuals allow."""
    if tol_se <= 0 or points.shape[0] <= points.shape[1] + 1:
        return tol_angle, tol_offset
    se_angle, se_offset = pair_fit_errors(points, mirrors, weights)
    return max(tol_angle, tol_se * math.degrees(float(se_angle))), max(tol_offset, tol_se * float(se_offset))


def _evaluate(points: torch.Tensor, index: KNNIndex, normal: torch.Tensor, offset: torch.Tensor):
    """Residuals ``(N,)``, nearest indices ``(N,)`` and progress residual of a plane."""
    d, j = index.query(reflect_points(points, normal, offset))
    return d, j, lower_quantile(d, PROGRESS_QUANTILE)


def kept_pairs(points: torch.Tensor, dist: torch.Tensor, nn_idx: torch.Tensor, max_residual: float) -> torch.Tensor:
    """``(N,)`` bool: the pairs one step fits, mutual and trimmed (Algorithm 6, steps 6-8).

    Trimmed at the median residual of the mutual pairs, and at ``max_residual`` (widened
    to 3x the lower quartile of the mutual residuals) while a tenth of the points stay.
    """
    mutual = mutual_nearest(nn_idx, nn_idx)  # same set both ways: free mutual test
    keep = mutual & (dist <= dist[mutual].median()) if bool(mutual.any()) else dist <= dist.median()
    if bool(mutual.any()):
        lower = lower_quantile(dist[mutual], 0.25)
        cut = max(max_residual, 3.0 * float(lower))
    else:
        cut = max_residual
    tight = keep & (dist <= cut)
    if int(tight.sum()) >= max(3, points.shape[0] // 10):
        keep = tight
    if int(keep.sum()) < 3:
        keep = dist <= dist.median()
    return keep


def alternate(
    points: torch.Tensor,
    index: KNNIndex,
    normal: torch.Tensor,
    offset: torch.Tensor,
    settings: AlternationSettings,
    *,
    max_iters: int | None = None,
    tol_angle: float | None = None,
    max_residual: float = float("inf"),
    tol_se: float = 0.0,
):
    """Algorithm 6 on ``points (N, 3)`` (queried against ``index`` over the same points).

    Each step pairs every point with the nearest neighbour of its mirror image, keeps the
    mutual, trimmed pairs and refits the plane (``settings.update``). With
    ``settings.accelerate`` a step is extrapolated (x2, x4, ...) while the progress
    residual (lower quartile of the residuals) falls. Ends when a step moves the normal
    less than ``tol_angle`` degrees and the offset less than ``tol_offset``, or (when larger)
    than ``tol_se`` standard errors of the fit (:func:`step_tolerances`), the step counted
    with what a linearly converging sequence still has to go (:func:`~torchsym.optim.convergence.remaining_factor`,
    with ``tol_se > 0``; converged), or
    after ``patience`` steps without a lower progress residual (the best plane is kept).
    ``max_iters`` and ``tol_angle`` default to the settings'.

    Returns:
        ``(normal (3,), offset (), iterations, converged, progress (), residuals (N,) or
        None, nearest (N,) or None)``: the residuals are those of the returned plane after
        a stall (then None) and of the plane before the last step after convergence.
    """
    max_iters = settings.max_iters if max_iters is None else max_iters
    tol_angle = settings.tol_angle if tol_angle is None else tol_angle
    converged = False
    it = 0
    dist, nn_idx, med = _evaluate(points, index, normal, offset)
    best = (normal, offset, med)
    stalled = 0
    prev_step = None
    for it in range(1, max_iters + 1):
        keep = kept_pairs(points, dist, nn_idx, max_residual)
        center = 0.5 * (points[keep] + points[nn_idx[keep]]).mean(0)
        n_new, b_new = fit_pairs(points, nn_idx, keep, settings.update, center)
        if float((n_new * normal).sum()) < 0:
            n_new, b_new = -n_new, -b_new
        d_angle = float(plane_angle(n_new, normal)) * 180.0 / math.pi
        d_off = float((b_new - offset).abs())
        tol_a, tol_b = step_tolerances(points[keep], points[nn_idx[keep]], tol_angle, settings.tol_offset, tol_se)
        step = n_new - normal
        ahead = remaining_factor(step, prev_step) if tol_se > 0 else 1.0
        prev_step = step
        if d_angle * ahead < tol_a and d_off * ahead < tol_b:
            # the residuals of the previous plane, which moved by at most the tolerances
            return n_new, b_new, it, True, med, dist, nn_idx
        d_new, j_new, m_new = _evaluate(points, index, n_new, b_new)
        if settings.accelerate and d_angle > tol_a:
            n_new, b_new, d_new, j_new, m_new = _extrapolate(points, index, normal, offset, n_new, b_new, d_new, j_new, m_new)
        normal, offset, dist, nn_idx, med = n_new, b_new, d_new, j_new, m_new
        if bool(med < best[2]):
            best, stalled = (normal, offset, med), 0
        else:
            stalled += 1
            if stalled >= settings.patience:
                normal, offset, med = best
                dist, nn_idx = None, None
                break
    return normal, offset, it, converged, med, dist, nn_idx


def _extrapolate(points, index, normal, offset, n_new, b_new, d_new, j_new, m_new):
    """The step from ``(normal, offset)`` to ``(n_new, b_new)`` taken 2, 4, ... 64 times
    while the progress residual keeps falling (Besl and McKay's accelerated ICP)."""
    dn, db = n_new - normal, b_new - offset
    alpha = 2.0
    while alpha <= 64.0:
        n_try = normal + alpha * dn
        scale = n_try.norm()
        n_try, b_try = n_try / scale, (offset + alpha * db) / scale
        d_try, j_try, m_try = _evaluate(points, index, n_try, b_try)
        if not bool(m_try < m_new):
            break
        n_new, b_new, d_new, j_new, m_new = n_try, b_try, d_try, j_try, m_try
        alpha *= 2.0
    return n_new, b_new, d_new, j_new, m_new
