"""The correspondence step of PointSymm: the mirror of every point (thesis Sec. 7.2.3).

For a fixed reflection the best correspondences solve a linear assignment problem (Claim
7.2.4) with cost ``|x_i' - x_j|^2``, solved exactly rather than by the thesis's relaxed LP:
``exact``, Jonker-Volgenant on the dense ``N x N`` cost (the cardinality limit of Sec. 7.4.4
exact too), or ``sparse``, a matching on each reflected point's ``n_neighbors`` nearest input
points plus a private "unmatched" option (LAPJVsp; exact once the reflection is roughly
right, the cardinality limit then approximate). See ``docs/design/pointsymm.md``.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import min_weight_full_bipartite_matching
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from torchsym.errors import InputValueError

__all__ = ["mirror_assignment"]


def mirror_assignment(
    points: np.ndarray,
    reflected: np.ndarray,
    *,
    n_matches: int | None = None,
    method: str = "exact",
    n_neighbors: int = 10,
    tree: cKDTree | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The mirror of every point under a fixed reflection.

    Args:
        points: ``(N, D)`` input points ``x_j``.
        reflected: ``(N, D)`` their reflections ``x_i'``.
        n_matches: at most this many points get a mirror (``2k`` of Sec. 7.4.4); None for all.
        method: ``"exact"`` (dense assignment) or ``"sparse"`` (nearest-neighbour graph).
        n_neighbors: candidate mirrors per point for ``"sparse"``.
        tree: a :class:`cKDTree` of ``points`` to reuse (``"sparse"`` only).

    Returns:
        ``perm (N,)`` int64 with ``perm[i] = j`` when ``x_j`` is the mirror of ``x_i`` and -1
        when ``x_i`` is unmatched, and ``dist2 (N,)`` the squared distances
        ``|x_i' - x_perm[i]|^2`` (``inf`` for unmatched points).
    """
    n = points.shape[0]
    m = n if n_matches is None else max(0, min(int(n_matches), n))
    perm = np.full(n, -1, dtype=np.int64)
    if m == 0:
        return perm, np.full(n, np.inf)
    if method == "exact":
        cost = cdist(reflected, points, "sqeuclidean")  # (N, N)
        if m < n:
            cost = np.concatenate([cost, np.zeros((n, n - m))], axis=1)  # (N, 2N - m)
        rows, cols = linear_sum_assignment(cost)
        real = cols < n
        perm[rows[real]] = cols[real]
    elif method == "sparse":
        k = max(1, min(int(n_neighbors), n))
        tree = cKDTree(points) if tree is None else tree
        dist, idx = tree.query(reflected, k=k)  # (N, k)
        dist, idx = dist.reshape(n, k), idx.reshape(n, k)
        d2 = dist * dist
        # Strictly positive weights (zero entries would read as missing edges); the private
        # "unmatched" column of each row costs more than any real edge.
        base = 1.0 + float(d2.max())
        big = 1e3 * base
        data = np.concatenate([d2 + base, np.full((n, 1), big)], axis=1).ravel()
        cols = np.concatenate([idx, n + np.arange(n)[:, None]], axis=1).ravel()
        rows = np.repeat(np.arange(n), k + 1)
        graph = csr_matrix((data, (rows, cols)), shape=(n, 2 * n))
        r, c = min_weight_full_bipartite_matching(graph)
        real = c < n
        perm[r[real]] = c[real]
    else:
        raise InputValueError(f"method: expected 'exact' or 'sparse', got {method!r}")
    dist2 = np.full(n, np.inf)
    ok = perm >= 0
    dist2[ok] = ((reflected[ok] - points[perm[ok]]) ** 2).sum(1)
    if method == "sparse" and int(ok.sum()) > m:
        drop = np.argsort(dist2, kind="stable")[m:]
        perm[drop] = -1
        dist2[drop] = np.inf
    return perm, dist2
