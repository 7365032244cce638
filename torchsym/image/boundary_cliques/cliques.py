"""Dominant cliques of the pair graph and their axes (thesis Sec. 2.3.2, Eq. 2.11).

The dominant clique is the complement of a minimum vertex cover of the complement graph,
by the LP relaxation of Eq. 2.11, rounded at 0.5; it is removed and the search repeats.
When the rounded LP leaves no vertex (its optimum can be all one half), the clique is
grown greedily from the vertex of highest degree instead.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from torchsym.errors import InputValueError, SolverError
from torchsym.image.boundary_cliques.pairs import BoundaryPairs, wrap_half_turn
from torchsym.image.verification import Axis

__all__ = ["CLIQUE_SOLVERS", "CliqueAxes", "axis_of_pairs", "clique_axes", "dominant_clique"]

CLIQUE_SOLVERS = ("matching", "highs")


def _greedy_clique(adj: np.ndarray) -> np.ndarray:
    """A clique grown from the vertex of highest degree of ``adj (V, V)``, by degree."""
    deg = adj.sum(1)
    order = np.argsort(-deg, kind="stable")
    clique = [int(order[0])]
    cand = adj[order[0]].copy()
    for v in order[1:]:
        if cand[v]:
            clique.append(int(v))
            cand &= adj[v]
    return np.asarray(sorted(clique), dtype=np.int64)


def _vertex_cover_lp_zeros(n: int, cu: np.ndarray, cv: np.ndarray) -> np.ndarray:
    """Vertices at 0 in a half-integral optimum of the vertex-cover LP of the graph ``(n, edges cu-cv)``.

    Nemhauser & Trotter (1975): with the bipartite double cover (left copy ``u_L``, right
    copy ``v_R``, an edge ``u_L - v_R`` and ``v_L - u_R`` per edge ``u - v``) and a minimum
    vertex cover ``C`` of it, ``x_v = |C & {v_L, v_R}| / 2`` is an optimal LP solution.
    ``C`` comes from a maximum matching by König's construction (left vertices not
    reachable by alternating paths from the free left vertices, right vertices reachable).
    """
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import breadth_first_order, maximum_bipartite_matching

    r, c = np.concatenate([cu, cv]), np.concatenate([cv, cu])
    b = csr_matrix((np.ones(r.size, dtype=np.int8), (r, c)), shape=(n, n))
    match = maximum_bipartite_matching(b, perm_type="column")  # right partner of each left vertex, -1: free
    matched, free = np.nonzero(match >= 0)[0], np.nonzero(match < 0)[0]
    # alternating paths: source 2n -> free left; left u -> right n + v (edges); right -> its matched left
    rows = np.concatenate([r, n + match[matched], np.full(free.size, 2 * n)])
    cols = np.concatenate([n + c, matched, free])
    g = csr_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(2 * n + 1, 2 * n + 1))
    reach = np.zeros(2 * n + 1, dtype=bool)
    reach[breadth_first_order(g, 2 * n, directed=True, return_predecessors=False)] = True
    return reach[:n] & ~reach[n : 2 * n]  # v_L and v_R both outside the cover: x_v = 0


def _vertex_cover_highs_zeros(n: int, cu: np.ndarray, cv: np.ndarray) -> np.ndarray:
    """Vertices below 0.5 in HiGHS's optimum of the vertex-cover LP (Eq. 2.11) of ``(n, edges cu-cv)``."""
    from scipy.optimize import linprog
    from scipy.sparse import coo_matrix

    m = cu.size
    rows = np.concatenate([np.arange(m), np.arange(m)])
    a_ub = coo_matrix((-np.ones(2 * m), (rows, np.concatenate([cu, cv]))), shape=(m, n)).tocsr()
    res = linprog(np.ones(n), A_ub=a_ub, b_ub=-np.ones(m), bounds=(0.0, 1.0), method="highs")
    if res.status != 0:
        raise SolverError(f"adj: HiGHS could not solve the vertex-cover LP of {n} vertices and {m} edges ({res.message})")
    return res.x < 0.5


def dominant_clique(adj: np.ndarray, solver: str = "matching") -> tuple[np.ndarray, bool]:
    """The dominant clique of a graph by the LP relaxation of minimum vertex cover (Eq. 2.11).

    ``min 1^T x`` s.t. ``x_u + x_v >= 1`` for every edge ``(u, v)`` of the complement
    graph, ``0 <= x <= 1``; vertices with ``x < 0.5`` form an independent set of the
    complement, i.e. a clique of the graph. Each connected component of the graph is
    solved on its own and the largest clique is returned.

    Args:
        adj: ``(V, V)`` bool symmetric adjacency, no self loops.
        solver: ``"matching"`` (exact, via a maximum bipartite matching, default) or
            ``"highs"`` (``scipy.optimize.linprog``). Both reach the optimal value; the
            LP may have several optima and they may round different ones.

    Returns:
        ``(clique indices, used_lp)``; ``used_lp`` is False when a component's rounded LP
        was empty (all one half) and the greedy clique was used.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if solver not in CLIQUE_SOLVERS:
        raise InputValueError(f"solver: expected one of {', '.join(map(repr, CLIQUE_SOLVERS))}, got {solver!r}")
    zeros = _vertex_cover_lp_zeros if solver == "matching" else _vertex_cover_highs_zeros
    v = adj.shape[0]
    if v == 0 or not adj.any():
        return np.zeros(0, dtype=np.int64), True
    n_comp, labels = connected_components(coo_matrix(adj), directed=False)
    best, used_lp = np.zeros(0, dtype=np.int64), True
    sizes = np.bincount(labels, minlength=n_comp)
    for comp in np.argsort(-sizes, kind="stable"):
        nodes = np.nonzero(labels == comp)[0]
        if nodes.size <= max(1, best.size):
            break  # no larger clique can come from a smaller component
        sub = adj[np.ix_(nodes, nodes)]
        cu, cv = np.nonzero(np.triu(~sub, k=1))  # complement edges
        if cu.size == 0:
            clique, lp_ok = np.arange(nodes.size), True
        else:
            clique = np.nonzero(zeros(nodes.size, cu, cv))[0]
            lp_ok = clique.size > 0
            if not lp_ok:
                clique = _greedy_clique(sub)
        if clique.size > best.size:
            best, used_lp = nodes[clique], lp_ok
    return best, used_lp


def axis_of_pairs(pairs: np.ndarray) -> np.ndarray:
    """Line ``(a, b, c)`` through the mean midpoint, perpendicular to the mean chord."""
    chord = pairs[:, :2] - pairs[:, 2:]
    _, vecs = np.linalg.eigh(chord.T @ chord)
    sign = np.sign(chord @ vecs[:, -1])
    sign[sign == 0] = 1
    mean_chord = (chord * sign[:, None]).sum(0)
    normal = mean_chord / max(np.linalg.norm(mean_chord), 1e-12)
    mid = 0.5 * (pairs[:, :2] + pairs[:, 2:]).mean(0)
    return np.array([normal[0], normal[1], -normal @ mid])


@dataclasses.dataclass(frozen=True)
class CliqueAxes:
    """The axes of the dominant cliques.

    Attributes:
        axes: the scored axes, in the order found.
        fallbacks: cliques grown greedily because the rounded LP was empty.
        without_evidence: cliques whose axis scored 0 (not reported).
    """

    axes: list[Axis]
    fallbacks: int
    without_evidence: int


def clique_axes(
    pairs: BoundaryPairs,
    nodes: np.ndarray,
    adj: np.ndarray,
    score_axis: Callable[[np.ndarray, np.ndarray], Axis],
    *,
    max_axes: int,
    min_support: int,
    solver: str,
    gather_support: bool,
    theta: float,
    distance: float,
) -> CliqueAxes:
    """Up to ``max_axes`` dominant cliques of the graph ``adj (V, V)`` on the pairs ``nodes (V,)``.

    Each clique gives an axis (:func:`axis_of_pairs`); with ``gather_support`` every free
    pair symmetric about it (Eq. 2.9 below ``theta`` degrees, midpoint within ``distance``
    px) joins its support. ``score_axis(line, members)`` scores it; pairs it drops from
    ``members`` are free again. The search stops at a clique of fewer than ``min_support``.
    """
    th = math.radians(theta)
    sums32 = pairs.sums.astype(np.float32)
    free = np.ones(len(pairs), dtype=bool)  # pairs not yet supporting an axis
    axes, fallbacks, without_evidence = [], 0, 0
    for _ in range(max_axes if nodes.size >= min_support else 0):
        remaining = nodes[free[nodes]]
        pos = np.nonzero(free[nodes])[0]
        clique, used_lp = dominant_clique(adj[np.ix_(pos, pos)], solver)
        if clique.size < min_support:
            break
        fallbacks += int(not used_lp)
        members = remaining[clique]
        line = axis_of_pairs(pairs.pairs[members])
        if gather_support:
            t_axis = np.abs(wrap_half_turn(np.float32(2 * math.atan2(line[1], line[0])) - sums32)).mean(1)  # (M,)
            near = np.abs(pairs.mid @ line[:2] + line[2]) < distance
            members = np.union1d(np.nonzero(free & near & (2 * t_axis < th))[0], members)
        free[members] = False
        axis = score_axis(line, members)
        free[np.setdiff1d(members, axis.members)] = True  # cut at empty background: may support another axis
        if axis.score <= 0:  # the image is not mirrored about this clique's axis at all
            without_evidence += 1
            continue
        axes.append(axis)
    return CliqueAxes(axes, fallbacks, without_evidence)
