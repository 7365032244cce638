"""Soft-correspondence refinement of a reflection plane (an extension of thesis Ch. 7).

Algorithm 7 fits the plane to hard correspondences: each point gets exactly one mirror. When
the noise is comparable to the spacing of the points, a point's true mirror is one of several
points about equally close to its reflection, and the hard assignment picks the wrong one
often enough to bias the plane. This stage replaces the hard ``P`` by a soft one and fits the
plane by expectation-maximisation, which approaches the posterior mean over correspondences
that the hard fit only approximates by its mode (``docs/design/pointsymm.md``):

- E-step: for the pairs ``(i, j)``, ``j`` among the ``n_neighbors`` nearest points to the
  reflection of ``x_i`` (``j != i``), the kernel ``exp(-|S x_i - x_j|^2 / (2 s^2))``, which
  is symmetric in ``i, j`` because ``S`` is an isometric involution; balanced by symmetric
  Sinkhorn scaling into a doubly stochastic matrix (a soft perfect matching: every point is
  one mirror's worth of partner, as in the hard assignment);
- M-step: the least-squares reflection for the weighted pairs, in closed form
  (:func:`~torchsym.geometry.plane_from_pairs`), and the residual variance ``s^2`` (per
  coordinate) re-estimated from the weighted residuals, so the noise level need not be known.

EM stops once the normal moves less than ``tol_se`` standard errors of its own fit (the
step counted with what a linearly converging sequence still has to go), so the tolerance
follows the noise: tight on nearly exact symmetries, loose where the data cannot pin the
plane. ``s^2`` starts at the hard fit's residual variance; an exact symmetry (zero residuals) is
left as it is.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.geometry import plane_from_pairs
from torchsym.optim.convergence import remaining_factor

__all__ = ["SoftPlane", "normal_standard_error", "soft_refine_plane"]

# Residual variance, relative to the mean squared radius, below which the hard fit is an exact
# symmetry up to rounding and is returned as it is.
_EXACT_S2 = 1e-20

# Symmetric Sinkhorn sweeps per E-step.
_SINKHORN_SWEEPS = 50

# Largest ratio of successive EM steps trusted when extrapolating what is left to go.
_MAX_STEP_RATIO = 0.95


@dataclasses.dataclass(frozen=True)
class SoftPlane:
    """The refined plane ``normal . x + offset = 0`` (``normal (D,)``), the residual variance
    per coordinate ``s2`` and the EM iterations run."""

    normal: np.ndarray
    offset: float
    s2: float
    iterations: int
    converged: bool


def _reflect(x: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    return x - 2.0 * (x @ normal + offset)[:, None] * normal


def _pairs(x: np.ndarray, tree: cKDTree, normal: np.ndarray, offset: float, k: int):
    """Unordered candidate pairs ``(a, c)`` (``a < c``) and their squared residuals."""
    n = x.shape[0]
    dist, idx = tree.query(_reflect(x, normal, offset), k=min(k + 1, n))  # (N, k+1)
    dist, idx = dist.reshape(n, -1), idx.reshape(n, -1)
    rows = np.repeat(np.arange(n), idx.shape[1])
    cols, d2 = idx.ravel(), dist.ravel() ** 2
    other = (rows != cols) & (cols < n)
    rows, cols, d2 = rows[other], cols[other], d2[other]
    a, c = np.minimum(rows, cols), np.maximum(rows, cols)
    _, first = np.unique(a * n + c, return_index=True)  # |S x_a - x_c| = |S x_c - x_a|
    return a[first], c[first], d2[first]


def _balance(a: np.ndarray, c: np.ndarray, kernel: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Symmetric Sinkhorn scaling ``u`` making ``P_ac = K_ac u_a u_c`` doubly stochastic."""
    n = u.shape[0]
    for _ in range(_SINKHORN_SWEEPS):
        wu = np.bincount(a, kernel * u[c], n) + np.bincount(c, kernel * u[a], n)  # (N,)
        u = np.sqrt(u / np.maximum(wu, 1e-300))
    return u


def _e_step(x: np.ndarray, tree: cKDTree, normal: np.ndarray, offset: float, s2: float, k: int):
    """Pairs ``(a, c)`` and their balanced weights ``(P,)`` at residual variance ``s2``."""
    a, c, d2 = _pairs(x, tree, normal, offset, k)
    kernel = np.exp(-(d2 - d2.min()) / (2.0 * s2))
    u = _balance(a, c, kernel, np.ones(x.shape[0]))
    return a, c, kernel * u[a] * u[c]


def normal_standard_error(p: np.ndarray, q: np.ndarray, weight: np.ndarray, s2: float) -> float:
    """Standard error (radians) of the least-squares reflection normal of the pairs
    ``(p, q)`` (``(P, D)`` each, weights ``(P,)``) with residual variance ``s2`` per
    coordinate: ``1/4 sum w |S p - q|^2 = n^T M n`` with
    ``M = 1/4 sum w (|u|^2 I - u u^T) + sum w (m - mean m)(m - mean m)^T`` (chords ``u``,
    midpoints ``m``) is least at the normal, the eigenvector of ``M``'s smallest eigenvalue
    ``l_1``; tilting it by ``theta`` towards the next one costs ``(l_2 - l_1) theta^2``, so
    the Gaussian log likelihood ``-2 n^T M n / s2`` gives ``theta`` the variance
    ``s2 / (4 (l_2 - l_1))``."""
    p, q, w = torch.from_numpy(p), torch.from_numpy(q), torch.from_numpy(weight)  # torch: its own thread setting
    u, m = p - q, 0.5 * (p + q)
    mc = m - (w @ m) / w.sum().clamp_min(1e-300)
    mat = 0.25 * ((w @ (u * u).sum(1)) * torch.eye(u.shape[1], dtype=u.dtype) - (u * w[:, None]).T @ u) + (mc * w[:, None]).T @ mc
    low = torch.linalg.eigvalsh(mat)[:2]
    return float(np.sqrt(s2 / max(4.0 * float(low[1] - low[0]), 1e-300)))


def soft_refine_plane(
    points: np.ndarray, normal: np.ndarray, offset: float, s2: float, *,
    tree: cKDTree | None = None, n_neighbors: int = 16, max_iters: int = 100, tol_se: float = 0.005,
) -> SoftPlane:
    """EM on soft, Sinkhorn-balanced correspondences from the plane ``(normal, offset)``.

    Args:
        points: ``(N, D)`` points (PointSymm passes them centred, unit RMS radius).
        normal: ``(D,)`` unit normal of the starting plane; ``offset`` its offset.
        s2: starting residual variance per coordinate (the hard fit's); at rounding level
            (``<= 1e-20`` times the mean squared norm of the points) the start is returned
            unchanged (an exact symmetry).
        tree: a :class:`cKDTree` of ``points`` to reuse.
        n_neighbors: candidate mirrors per point.
        max_iters: most EM iterations.
        tol_se: stop when the normal moves less than this many standard errors of its fit
            (:func:`normal_standard_error`), the step times ``1 / (1 - r)``, ``r`` the ratio
            of successive steps (clipped to [0, 0.95]).

    Returns:
        :class:`SoftPlane`, its normal on the side of the starting one.
    """
    x = np.asarray(points, dtype=np.float64)
    n_pts, dim = x.shape
    normal, offset = np.asarray(normal, dtype=np.float64), float(offset)
    if not s2 > _EXACT_S2 * float((x**2).sum(1).mean()) or n_pts < 3:
        return SoftPlane(normal, offset, max(float(s2), 0.0), 0, True)
    tree = cKDTree(x) if tree is None else tree
    converged, it, previous = False, 0, None
    for it in range(1, max_iters + 1):
        if it == 1:  # anneal: start as wide as the candidates' residuals
            s2 = max(s2, float(np.median(_pairs(x, tree, normal, offset, n_neighbors)[2])) / dim)
        a, c, weight = _e_step(x, tree, normal, offset, s2, n_neighbors)  # E-step
        new_normal, new_offset = plane_from_pairs(  # M-step
            torch.from_numpy(x[a]), torch.from_numpy(x[c]), torch.from_numpy(weight)
        )
        new_normal, new_offset = new_normal.numpy(), float(new_offset)
        if new_normal @ normal < 0:
            new_normal, new_offset = -new_normal, -new_offset
        r2 = ((_reflect(x[a], new_normal, new_offset) - x[c]) ** 2).sum(1)
        s2 = max(float((weight * r2).sum() / (weight.sum() * dim)), 1e-300)
        step = new_normal - normal
        normal, offset = new_normal, new_offset
        moved = 2.0 * float(np.arcsin(min(1.0, 0.5 * float(np.linalg.norm(step)))))  # radians
        ahead = remaining_factor(step, previous, max_ratio=_MAX_STEP_RATIO)
        previous = step
        if moved * ahead <= tol_se * normal_standard_error(x[a], x[c], weight, s2):
            converged = True
            break
    return SoftPlane(normal, offset, s2, it, converged)
