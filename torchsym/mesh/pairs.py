"""Sparse pairs of intrinsically symmetric points and the signs of eigenfunctions.

Thesis Sec. 6.2.4 (pairing HKS feature points by a small integer program, Eq. 6.1, with a
large penalty for points whose eigenfunction sign vectors agree, Observation 1) and
Sec. 6.2.5 (an eigenfunction is even or odd as its restriction to the shortest geodesic
between two symmetric points is: ``s_i = sign(sum_j p_ij^T flip(p_ij))``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.optimize import Bounds, LinearConstraint, milp

from torchsym.errors import InputShapeError, SolverError
from torchsym.mesh.geodesic import shortest_paths

__all__ = ["eigenfunction_signs", "pair_affinity", "symmetric_pairs"]


def _relative_sqdist(x: np.ndarray, iu: np.ndarray, ju: np.ndarray) -> np.ndarray:
    num = ((x[iu] - x[ju]) ** 2).sum(axis=1)  # (P,)
    den = (x[iu] ** 2).sum(axis=1) + (x[ju] ** 2).sum(axis=1)  # (P,)
    return num / np.maximum(den, np.finfo(float).tiny)


def pair_affinity(
    hks: np.ndarray, evecs_at: np.ndarray, *, penalty: float = 1e6, spectral_weight: float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cost ``W`` of pairing every two of ``d`` feature points (Sec. 6.2.4).

    ``W[j, j'] = |h_j - h_j'|^2 + q psi(|s_j - s_j'|)`` where ``h`` is the HKS and ``s`` the
    vector of eigenfunction signs; ``psi`` is 1 when the sign vectors are equal (the points
    are neighbours, Observation 1). Both distances are taken relative to the descriptors'
    norms, so ``W`` does not depend on the mesh's scale, and a second, equally weighted
    term compares the squared eigenfunction values ``phi_i(x)^2`` (symmetric points have
    equal ``|phi_i|`` for every non-repeated eigenvalue; ``spectral_weight=0`` gives the
    thesis's affinity alone).

    Args:
        hks: ``(d, h)`` heat kernel signatures of the feature points.
        evecs_at: ``(d, k)`` eigenfunction values at the feature points.
        penalty: ``q``, the cost added for equal sign vectors.
        spectral_weight: weight of the ``phi^2`` term.

    Returns:
        ``iu (P,)``, ``ju (P,)`` the pairs ``j < j'`` and ``cost (P,)``.
    """
    d = hks.shape[0]
    if evecs_at.shape[0] != d:
        raise InputShapeError(f"evecs_at: expected ({d}, k) to match hks {hks.shape}, got {evecs_at.shape}")
    iu, ju = np.triu_indices(d, 1)
    cost = _relative_sqdist(hks, iu, ju)  # (P,)
    if spectral_weight > 0:
        cost = cost + spectral_weight * _relative_sqdist(evecs_at[:, 1:] ** 2, iu, ju)
    signs = np.sign(evecs_at)  # (d, k)
    same = (signs[iu] == signs[ju]).all(axis=1)  # (P,)
    return iu, ju, cost + penalty * same


def _consistent(pairs: np.ndarray, dist: np.ndarray, tol: float) -> bool:
    """True when every two pairs ``(a, a'), (b, b')`` have ``d(a, b) ~ d(a', b')`` and ``d(a, b') ~ d(a', b)``."""
    for x in range(pairs.shape[0]):
        for y in range(x + 1, pairs.shape[0]):
            (a, a2), (b, b2) = pairs[x], pairs[y]
            for d1, d2 in ((dist[a, b], dist[a2, b2]), (dist[a, b2], dist[a2, b])):
                if abs(d1 - d2) > tol * max(d1, d2, np.finfo(float).tiny):
                    return False
    return True


def _solve_pairing(cost: np.ndarray, incidence: sp.csr_matrix, n_pairs: int) -> np.ndarray | None:
    """Eq. 6.1: the ``n_pairs`` disjoint pairs of least total cost; None when infeasible."""
    n_var = cost.shape[0]
    res = milp(
        cost,
        constraints=[LinearConstraint(incidence, 0, 1), LinearConstraint(np.ones((1, n_var)), n_pairs, n_pairs)],
        integrality=np.ones(n_var),
        bounds=Bounds(0, 1),
    )
    if res.status == 2:  # infeasible
        return None
    if res.x is None:
        raise SolverError(f"symmetric_pairs: the pairing integer program failed ({res.message})")
    return np.flatnonzero(res.x > 0.5)


def symmetric_pairs(
    features: np.ndarray,
    hks: np.ndarray,
    evecs_at: np.ndarray,
    *,
    distances: np.ndarray | None = None,
    max_pairs: int = 5,
    max_cost: float = 0.5,
    distance_tol: float = 0.15,
    penalty: float = 1e6,
    spectral_weight: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Pair feature points by the integer program of Eq. 6.1 (Sec. 6.2.4).

    For ``c = 1, 2, ..., max_pairs`` solves Eq. 6.1 exactly (``scipy.optimize.milp``): the
    ``c`` disjoint pairs of least total affinity cost, each point in at most one pair. The
    answer is the largest ``c`` whose pairs all cost less than ``max_cost`` (so a pair of
    points with equal sign vectors, cost ``>= penalty``, is never taken) and, when
    ``distances`` are given, are consistent with an isometry: for every two pairs
    ``(a, a'), (b, b')``, ``d(a, b) = d(a', b')`` and ``d(a, b') = d(a', b)`` within
    ``distance_tol`` (relative), as Theorem 6.2.2's self-isometry requires.

    Args:
        features: ``(d,)`` vertex indices of the feature points.
        hks: ``(d, h)`` their heat kernel signatures.
        evecs_at: ``(d, k)`` eigenfunction values there.
        distances: ``(d, d)`` geodesic distances between the feature points, or None.
        max_pairs: ``c``, the most pairs returned.
        max_cost: no pair costing more is taken.
        distance_tol: relative tolerance of the isometry test.
        penalty: ``q`` (see :func:`pair_affinity`).
        spectral_weight: see :func:`pair_affinity`.

    Returns:
        ``pairs (P, 2)`` vertex indices with ``P <= max_pairs`` and their ``cost (P,)``.
    """
    d = features.shape[0]
    empty = np.zeros((0, 2), dtype=np.int64), np.zeros(0)
    if d < 2 or max_pairs < 1:
        return empty
    iu, ju, cost = pair_affinity(hks, evecs_at, penalty=penalty, spectral_weight=spectral_weight)
    n_var = iu.shape[0]
    incidence = sp.coo_matrix(
        (np.ones(2 * n_var), (np.concatenate([iu, ju]), np.tile(np.arange(n_var), 2))), shape=(d, n_var)
    ).tocsr()  # (d, P): Pi 1 <= 1
    best = np.zeros(0, dtype=np.int64)
    for c in range(1, min(max_pairs, d // 2) + 1):
        chosen = _solve_pairing(cost, incidence, c)
        if chosen is None or (cost[chosen] >= max_cost).any():
            break
        local = np.stack([iu[chosen], ju[chosen]], axis=1)  # (c, 2) indices into features
        if distances is not None and not _consistent(local, distances, distance_tol):
            break
        best = chosen
    order = best[np.argsort(cost[best], kind="stable")]
    pairs = np.stack([features[iu[order]], features[ju[order]]], axis=1).astype(np.int64)  # (P, 2)
    return pairs, cost[order]


def _resample(values: np.ndarray, points: np.ndarray, n_samples: int) -> tuple[np.ndarray, float]:
    """``values (L, k)`` along a polyline ``points (L, 3)`` at ``n_samples`` equal arc lengths, and its length."""
    if values.shape[0] == 1:
        return np.repeat(values, n_samples, axis=0), 0.0
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])  # (L,)
    t = np.linspace(0.0, arc[-1], n_samples)  # (n_samples,)
    return np.stack([np.interp(t, arc, values[:, i]) for i in range(values.shape[1])], axis=1), float(arc[-1])


def eigenfunction_signs(
    evecs: np.ndarray,
    vertices: np.ndarray,
    graph: sp.csr_matrix,
    pairs: np.ndarray,
    *,
    n_samples: int = 64,
    cross_pairs: bool = True,
    min_confidence: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The diagonal of the functional map ``C``: +1 for even, -1 for odd eigenfunctions (Sec. 6.2.5).

    ``s_i = sign(sum_j p_ij^T flip(p_ij))`` where ``p_ij`` is eigenfunction ``i`` along the
    shortest edge path between the two points of pair ``j`` (Proposition 6.2.3), sampled
    at ``n_samples`` equal arc lengths so that ``flip`` pairs points at equal distances
    from the two ends, and weighted by the path's length (the integral of
    ``phi_i(gamma(t)) phi_i(gamma(1 - t))`` over arc length). With ``cross_pairs``, every two pairs ``(a, a')`` and ``(b, b')``
    add ``q_i^T q'_i``, with ``q`` and ``q'`` the eigenfunction along the geodesics ``a -> b`` and
    ``a' -> b'``: the symmetry maps one geodesic onto the other (Theorem 6.2.2), so the
    restrictions agree up to the sign of the eigenfunction. This reaches eigenfunctions
    that vanish along every pair's own geodesic (an extension of the thesis's test).

    Args:
        evecs: ``(V, k)`` eigenfunctions.
        vertices: ``(V, 3)`` positions (for arc lengths).
        graph: ``(V, V)`` edge graph with lengths.
        pairs: ``(P, 2)`` vertex pairs.
        n_samples: samples per geodesic.
        cross_pairs: add the evidence of geodesics between pairs.
        min_confidence: eigenfunctions whose normalised evidence ``|score| / bound`` is
            below this get sign 0 (not used), where ``bound`` is the score a perfectly
            even function would reach; the thesis drops only those with a zero score
            (``min_confidence = 0``). Eigenfunctions of nearly repeated eigenvalues mix and
            are neither even nor odd; their confidence is low.

    Returns:
        ``signs (k,)`` in {-1, 0, +1} and ``confidence (k,)`` in [-1, 1], the evidence
        normalised by its bound (+1: perfectly even, -1: perfectly odd).
    """
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    score = np.zeros(evecs.shape[1])  # (k,)
    bound = np.zeros(evecs.shape[1])  # (k,) what score would be for a perfectly even function
    for path in shortest_paths(graph, pairs):
        if path.size:
            p, length = _resample(evecs[path], vertices[path], n_samples)  # (n_samples, k)
            score += (p * p[::-1]).mean(axis=0) * length
            bound += (p * p).mean(axis=0) * length
    if cross_pairs and pairs.shape[0] > 1:
        ia, ib = np.triu_indices(pairs.shape[0], 1)
        ends = np.concatenate([
            np.stack([pairs[ia, 0], pairs[ib, 0]], axis=1),  # a -> b
            np.stack([pairs[ia, 1], pairs[ib, 1]], axis=1),  # a' -> b'
            np.stack([pairs[ia, 0], pairs[ib, 1]], axis=1),  # a -> b'
            np.stack([pairs[ia, 1], pairs[ib, 0]], axis=1),  # a' -> b
        ])
        paths = shortest_paths(graph, ends)
        m = ia.shape[0]
        for j in range(m):
            for first, second in ((paths[j], paths[m + j]), (paths[2 * m + j], paths[3 * m + j])):
                if first.size and second.size:
                    q1, len1 = _resample(evecs[first], vertices[first], n_samples)  # (n_samples, k)
                    q2, len2 = _resample(evecs[second], vertices[second], n_samples)  # (n_samples, k)
                    score += (q1 * q2).mean(axis=0) * 0.5 * (len1 + len2)
                    bound += 0.5 * (q1 * q1 + q2 * q2).mean(axis=0) * 0.5 * (len1 + len2)
    confidence = score / np.maximum(bound, np.finfo(float).tiny)  # (k,) in [-1, 1]
    signs = np.sign(score)
    signs[np.abs(confidence) < min_confidence] = 0.0
    return signs, confidence
