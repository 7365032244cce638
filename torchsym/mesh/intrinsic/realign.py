"""Step 14 (an extension): realign the map by distances to anchors, then ZoomOut.

An isometric involution keeps ``d(T a, T x) = d(a, x)``, so ``T x`` is the vertex whose
distances to the anchors' images match ``x``'s to the anchors (the geodesic coordinates of
Kim et al. 2011, here repairing a map), with geodesic and biharmonic (Lipman et al. 2010) distances.
"""

from __future__ import annotations

import dataclasses
import time
from functools import partial

import numpy as np

from torchsym.core import parallel
from torchsym.errors import InputValueError
from torchsym.mesh import fmaps
from torchsym.mesh.geodesic import geodesic_distances
from torchsym.mesh.intrinsic.refine import MapState
from torchsym.mesh.intrinsic.workspace import Workspace
from torchsym.mesh.nearest import nearest_profiles

__all__ = ["BiharmonicDistances", "anchor_realignment", "realign"]


class BiharmonicDistances:
    """Biharmonic distances (Lipman et al. 2010) in the eigenpairs ``evals (K,)``, ``evecs (V, K)``:
    called with ``sources (s,)`` gives ``(s, V)``."""

    def __init__(self, evals: np.ndarray, evecs: np.ndarray):
        self.psi = evecs[:, 1:] / np.maximum(evals[1:], np.finfo(float).tiny)  # (V', K-1)
        self.sq_norms = np.einsum("ij,ij->i", self.psi, self.psi)  # (V',)

    def __call__(self, sources: np.ndarray) -> np.ndarray:
        sq = self.sq_norms[sources][:, None] + self.sq_norms[None, :] - 2.0 * self.psi[sources] @ self.psi.T  # (s, V')
        return np.sqrt(np.maximum(sq, 0.0))


class _Profiles:
    """Rows of ``distances(sources)`` by source, each computed once."""

    def __init__(self, distances):
        self.distances, self.cache = distances, {}

    def __call__(self, sources: np.ndarray) -> np.ndarray:
        todo = np.array(sorted({int(s) for s in sources} - self.cache.keys()), dtype=np.int64)
        if todo.size:
            for s, row in zip(todo, self.distances(todo)):
                self.cache[int(s)] = row
        return np.stack([self.cache[int(s)] for s in sources])  # (A, V)


def anchor_realignment(distances, rows: np.ndarray, vertex_map: np.ndarray, anchors: np.ndarray, iters: int) -> np.ndarray:
    """Each vertex of ``rows (S,)`` (sorted, holding every anchor) to the vertex whose distances
    to the images of ``anchors (A,)`` under ``vertex_map (V,)`` are nearest its own to the anchors,
    ``iters`` rounds (float32 brute force). ``distances(sources)`` gives ``(len(sources), V)``.

    Returns:
        ``(S,)`` the new image of every vertex of ``rows``.

    Raises:
        InputValueError: ``rows`` not sorted and distinct, or missing an anchor.
    """
    profile = _Profiles(distances)
    where = np.searchsorted(rows, anchors)  # anchors are sampled vertices
    if not (np.all(rows[:-1] < rows[1:]) and np.array_equal(rows[np.minimum(where, rows.size - 1)], anchors)):
        raise InputValueError("rows, anchors: expected sorted distinct rows that hold every anchor")
    base = profile(anchors)[:, rows].T  # (S, A) the sampled vertices' distances to the anchors
    image = vertex_map[rows].copy()  # (S,)
    for _ in range(iters):
        image = nearest_profiles(base, profile(image[where]).T)
    return image


def _realigned(ws: Workspace, state: MapState, anchors: np.ndarray, kk: int, distances) -> tuple | None:
    """One realignment and two rounds of ZoomOut in ``kk``: its map, ``C`` and reversed share, or None."""
    rows = ws.rows
    start = anchor_realignment(distances, rows, state.vmap, anchors, ws.settings.realign.max_iters)
    image, fitted = fmaps.zoomout(ws.big, ws.area, rows, start, np.array([kk, kk]), ws.search, ws.settings.refine.involution, brute=True)
    if ws.probe.near_self(image) >= ws.settings.select.near_self:
        return None
    trial = ws.search.map_every_vertex(fitted)
    return trial, fitted, ws.reversed_share(trial)


def realign(ws: Workspace, state: MapState) -> tuple[MapState, list[str], float]:
    """Step 14 on a map reversing the orientation at under ``realign.below`` of the sample: the
    geodesic and the biharmonic realignment (on threads); the one reversing it at the most
    sampled vertices replaces ``state``'s map when that share beats the map's by ``realign.gain``.

    Returns:
        The map state after the step, its notes and the seconds taken.
    """
    tic = time.perf_counter()
    notes = []
    before = ws.reversed_share(state.vmap) if state.share is None else state.share  # steps 12 / 13 measured it
    if before < ws.settings.realign.below:
        kk = int(state.full.shape[0])
        biharmonic = BiharmonicDistances(ws.big_evals[:kk], ws.big[:, :kk])
        anchors = ws.rng.choice(ws.rows, size=min(ws.settings.realign.n_anchors, ws.rows.size), replace=False)  # (A,)
        # the tree of every vertex is built first; Dijkstra (holding the GIL) overlaps the biharmonic products
        ws.search.dense(kk)
        labels = ("geodesic", "biharmonic")
        branches = parallel.run_branches([
            partial(_realigned, ws, state, anchors, kk, partial(geodesic_distances, ws.graph)),
            partial(_realigned, ws, state, anchors, kk, biharmonic),
        ])
        best_share, found = before + ws.settings.realign.gain, None
        for label, branch in zip(labels, branches):
            if branch is not None and branch[2] > best_share:
                best_share, found = branch[2], (label, branch[0], branch[1])
        if found is not None:
            label, vmap, full = found
            state = dataclasses.replace(state, vmap=vmap, full=full)
            notes.append(
                f"realigned by {label} distances to {anchors.size} anchors: the map reverses the orientation "
                f"at {best_share:.0%} of the sampled vertices, against {before:.0%}"
            )
    return state, notes, time.perf_counter() - tic
