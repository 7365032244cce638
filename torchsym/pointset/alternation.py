"""Algorithm 7's alternation: correspondences ``P`` for fixed ``(R, t)``, then ``(R, t)`` for
fixed ``P``, until ``P`` stops changing (thesis Sec. 7.2, steps 2-4)."""

from __future__ import annotations

import dataclasses
import functools
import logging

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.geometry import plane_from_pairs
from torchsym.manifolds import ProductManifold
from torchsym.optim import trust_region
from torchsym.pointset import transform as tf
from torchsym.pointset.assignment import mirror_assignment

__all__ = ["Alternation", "AlternationRun", "alternate", "assign", "best_run", "mirror_score", "reflect_points", "start_variables"]

logger = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class Alternation:
    """What every alternation on one normalised set shares.

    Attributes:
        points: ``(N, D)`` the points, centred and scaled to unit RMS radius.
        points_t: the same as a float64 tensor.
        tree: :class:`cKDTree` of ``points``.
        manifold: ``SO(2, D)^(D-1) x R^D`` (:func:`~torchsym.pointset.transform.rotation_manifold`).
        method: ``"exact"`` or ``"sparse"`` assignment.
        n_matches: most matched points (``2k`` of Sec. 7.4.4), None for all.
        n_neighbors: candidate mirrors per point of the sparse assignment.
        max_iters: most alternations.
        closed_form: fit step 3 in closed form (the least-squares reflection of the pairs,
            :func:`~torchsym.geometry.plane_from_pairs`) instead of the trust region.
    """

    points: np.ndarray
    points_t: torch.Tensor
    tree: cKDTree
    manifold: ProductManifold
    method: str
    n_matches: int | None
    n_neighbors: int
    max_iters: int
    closed_form: bool = False


@dataclasses.dataclass(frozen=True)
class AlternationRun:
    """The end of one alternation: ``var`` the rotations and translation, ``perm (N,)`` and
    ``dist2 (N,)`` its correspondences, ``total`` their summed squared distance."""

    total: float
    var: tuple
    perm: np.ndarray
    dist2: np.ndarray
    iterations: int
    converged: bool


def start_variables(normal: np.ndarray, point: np.ndarray) -> tuple:
    """``(R_1, .., R_{D-1}, t)`` of the plane with unit ``normal (D,)`` through ``point (D,)``."""
    return (*tf.rotations_from_normal(torch.from_numpy(normal)), torch.from_numpy(point).clone())


def reflect_points(x_np: np.ndarray, var) -> np.ndarray:
    """``(N, D)`` points reflected by the variables ``var = (R_1, .., R_{D-1}, t)``."""
    *rots, t = var
    s = tf.reflection_from_rotations(rots).numpy()
    t = t.numpy()
    return (x_np - t) @ s.T + t


def assign(problem: Alternation, var) -> tuple[np.ndarray, np.ndarray]:
    """Step 2: the mirror of every point under the reflection ``var`` (Sec. 7.2.3)."""
    return mirror_assignment(
        problem.points,
        reflect_points(problem.points, var),
        n_matches=problem.n_matches,
        method=problem.method,
        n_neighbors=problem.n_neighbors,
        tree=problem.tree,
    )


def _cost(v, st):
    return tf.reflection_cost(v, st)


def _egrad(v, st):
    return tf.egrad(v, st)


def _ehess(v, u, st):
    return tf.ehess(v, u, st)


def fit_reflection(problem: Alternation, var, perm: np.ndarray):
    """Step 3: ``(R, t)`` for fixed correspondences by the Riemannian trust region (Sec. 7.2.2),
    warm-started from ``var``; returns the new variables and the cost."""
    matched = perm >= 0
    if problem.closed_form:
        return _fit_closed_form(problem, var, perm)
    weights = torch.from_numpy(matched.astype(np.float64))
    mirrors = problem.points_t[torch.from_numpy(np.where(matched, perm, 0))]
    st = tf.pair_statistics(problem.points_t, mirrors, weights)
    res = trust_region(
        problem.manifold,
        functools.partial(_cost, st=st),
        var,
        egrad=functools.partial(_egrad, st=st),
        ehess=functools.partial(_ehess, st=st),
        min_grad_norm=1e-10 * max(1.0, float(st.w)),
        max_iter=100,
    )
    return res.x, res.cost


def _fit_closed_form(problem: Alternation, var, perm: np.ndarray):
    """Step 3 in closed form: the least-squares reflection of the matched pairs (the global
    minimum of Eq. 7.5 for fixed ``P``), its normal on the side of ``var``'s."""
    matched = perm >= 0
    x = problem.points_t[torch.from_numpy(matched)]
    y = problem.points_t[torch.from_numpy(perm[matched])]
    normal, offset = plane_from_pairs(x, y)
    *rots, _ = var
    if float(normal @ tf.normal_from_rotations(rots)) < 0:
        normal, offset = -normal, -offset
    new = start_variables(normal.numpy(), -float(offset) * normal.numpy())
    cost = float(((reflect_points(x.numpy(), new) - y.numpy()) ** 2).sum())
    return new, cost


def alternate(problem: Alternation, var) -> AlternationRun:
    """Steps 2-4 of Algorithm 7 from ``var``, until the correspondences stop changing."""
    perm, dist2 = assign(problem, var)
    converged, it = False, 0
    for it in range(1, problem.max_iters + 1):
        var, cost = fit_reflection(problem, var, perm)
        new_perm, dist2 = assign(problem, var)
        logger.debug("PointSymm iteration %d: cost %.6g, %d correspondences changed", it, cost, int((new_perm != perm).sum()))
        if np.array_equal(new_perm, perm):
            converged = True
            break
        perm = new_perm
    total = float(dist2[perm >= 0].sum())
    logger.debug("PointSymm start: cost %.6g after %d alternations", total, it)
    return AlternationRun(total, var, perm, dist2, it, converged)


def best_run(problem: Alternation, starts, best: AlternationRun | None = None) -> AlternationRun:
    """The alternation from each ``(normal, point)`` start; the one of least symmetry error
    (``best``, when given, wins ties)."""
    for start_normal, start_point in starts:
        run = alternate(problem, start_variables(start_normal, start_point))
        if best is None or run.total < best.total:
            best = run
    return best


def mirror_score(perm: np.ndarray, dist2: np.ndarray, h: float) -> float:
    """The scan's trigger (not the result's score): mean over all points of ``exp(-dist2 / (2 h^2))``, unmatched points counting 0; in [0, 1]."""
    matched = perm >= 0
    return float(np.where(matched, np.exp(-0.5 * np.where(matched, dist2, 0.0) / h**2), 0.0).mean())
