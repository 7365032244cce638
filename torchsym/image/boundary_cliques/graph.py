"""The graph of boundary pairs (thesis Sec. 2.3.2): an edge joins two pairs with one axis."""

from __future__ import annotations

import math

import numpy as np

from torchsym.image.boundary_cliques.pairs import BoundaryPairs, wrap_half_turn

__all__ = ["pair_graph"]


def pair_graph(pairs: BoundaryPairs, nodes: np.ndarray, *, theta: float, distance: float) -> np.ndarray:
    """``(V, V)`` bool adjacency of the pairs ``nodes (V,)`` of ``pairs``.

    An edge joins pairs ``i, j`` when each one's segments are symmetric about the other's
    axis (the integral of Eq. 2.9, summed both ways, below ``theta`` degrees) and each
    midpoint lies within ``distance`` px of the other's axis (Eq. 2.3). No self loops.
    """
    sums, beta, mid = pairs.sums[nodes], pairs.beta[nodes], pairs.mid[nodes]  # (V, ...)
    normal = np.stack([np.cos(beta), np.sin(beta)], 1)
    off = -(normal * mid).sum(1)
    # T[i, j]: Eq. 2.9 integral of pair j's segments reflected through pair i's axis
    tcost = np.abs(wrap_half_turn(2 * beta.astype(np.float32)[:, None, None] - sums.astype(np.float32)[None, :, :])).mean(2)  # (V, V)
    dist = np.abs(mid @ normal.T + off[None, :]).T  # (V, V): |n_i . m_j + c_i|
    adj = (tcost + tcost.T < math.radians(theta)) & (dist < distance) & (dist.T < distance)
    np.fill_diagonal(adj, False)
    return adj
