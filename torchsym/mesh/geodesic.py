"""Approximate geodesics: Dijkstra's algorithm on the edge graph (thesis Sec. 6.2.5).

Distances run along mesh edges, so they over-estimate the true geodesic distance by a
few percent; paths are vertex sequences, which is what the sign test of Sec. 6.2.5 needs.

The graphs are symmetric, with both directions of every edge stored
(:func:`~torchsym.mesh.operators.edge_graph`), so scipy's Dijkstra runs with
``directed=True``: the same distances, without the transposed copy of the graph that
``directed=False`` builds on every call.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

__all__ = ["geodesic_distances", "shortest_paths", "thin_points"]


def geodesic_distances(
    graph: sp.csr_matrix, sources: np.ndarray, *, limit: float = np.inf, chunk: int = 256
) -> np.ndarray:
    """Edge-graph distances from each source to every vertex, ``(S, V)``.

    Args:
        graph: ``(V, V)`` symmetric edge graph with lengths (:func:`~torchsym.mesh.operators.edge_graph`).
        sources: ``(S,)`` vertex indices.
        limit: stop searching beyond this distance (entries beyond it are ``inf``).
        chunk: sources per Dijkstra call, to bound memory.
    """
    sources = np.asarray(sources, dtype=np.int64).ravel()  # (S,)
    out = np.empty((sources.shape[0], graph.shape[0]))  # (S, V)
    for s in range(0, sources.shape[0], chunk):
        out[s : s + chunk] = dijkstra(graph, directed=True, indices=sources[s : s + chunk], limit=limit)
    return out


def shortest_paths(graph: sp.csr_matrix, pairs: np.ndarray) -> list[np.ndarray]:
    """Vertex sequences of the shortest edge paths between the two ends of each pair.

    Args:
        graph: ``(V, V)`` symmetric edge graph with lengths.
        pairs: ``(P, 2)`` vertex indices ``(start, end)``.

    Returns:
        ``P`` int64 arrays, each running from ``start`` to ``end`` inclusive; an empty
        array where ``end`` cannot be reached from ``start``.
    """
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)  # (P, 2)
    if pairs.shape[0] == 0:
        return []
    starts, inverse = np.unique(pairs[:, 0], return_inverse=True)
    _, pred = dijkstra(graph, directed=True, indices=starts, return_predecessors=True)  # (S, V)
    paths = []
    for row, end in zip(inverse, pairs[:, 1]):
        start = starts[row]
        seq = [int(end)]
        node = int(end)
        while node != start:
            node = int(pred[row, node])
            if node < 0:
                seq = []
                break
            seq.append(node)
        paths.append(np.asarray(seq[::-1], dtype=np.int64))
    return paths


def thin_points(graph: sp.csr_matrix, points: np.ndarray, radius: float) -> np.ndarray:
    """Keep, in order, each point farther than ``radius`` (edge-graph distance) from every kept one.

    Args:
        graph: ``(V, V)`` symmetric edge graph with lengths.
        points: ``(d,)`` vertex indices, most important first.
        radius: the smallest distance between two kept points; 0 keeps all.

    Returns:
        ``(d',)`` the kept indices, in their original order.
    """
    points = np.asarray(points, dtype=np.int64).ravel()
    if radius <= 0 or points.size < 2:
        return points
    dist = geodesic_distances(graph, points, limit=radius)  # (d, V)
    kept: list[int] = []
    for a in range(points.size):
        if all(dist[b, points[a]] >= radius for b in kept):
            kept.append(a)
    return points[kept]
