"""The correspondence step of PointSymm: the mirror of every point (thesis Sec. 7.2.3).

For a fixed reflection the best correspondences ``P`` solve a linear assignment problem
(Claim 7.2.4): row ``i`` is the reflected point ``x_i'``, column ``j`` the input point ``x_j``,
and the cost of ``P_ij = 1`` is ``|x_i' - x_j|^2``. The thesis relaxes the integer program to
an LP solved by Karmarkar's algorithm (``O(n^3.5)``) and rounds it; we solve the assignment
problem exactly instead, which is both optimal and faster:

- ``exact``: the Jonker-Volgenant algorithm of :func:`scipy.optimize.linear_sum_assignment`
  on the dense ``N x N`` cost matrix (``O(N^3)`` worst case, far less on near-permutation
  costs). The cardinality limit ``e^T P e <= 2k`` of Sec. 7.4.4 (at most ``m = 2k`` matched
  points, for missing parts) is exact too: ``N - m`` zero-cost "unmatched" columns are added,
  so the solver keeps the ``m`` matches whose total cost is least.
- ``sparse``: each reflected point may only match one of its ``n_neighbors`` nearest input
  points (found with :class:`scipy.spatial.cKDTree`), plus a private "unmatched" option that
  costs more than any real edge; solved by
  :func:`scipy.sparse.csgraph.min_weight_full_bipartite_matching` (LAPJVsp). This is the
  exact optimum whenever every point's true mirror is among its reflection's nearest
  neighbours, i.e. once the reflection is roughly right; the cardinality limit is then
  applied by keeping the ``m`` cheapest matches.
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
