"""Nearest rows of an embedding: kd-trees, float32 brute force and the choice between them.

Building blocks of ZoomOut on a vertex sample (:mod:`torchsym.mesh.fmaps`): a point map
sends each vertex to the nearest row of ``Phi`` to its row of ``Phi C``. Exact searches
return the same rows whatever the structure; brute force in float32 can only pick a near
tie instead of the nearest row. Design notes: ``docs/design/intrinsic.md``.
"""

from __future__ import annotations

import threading
from functools import partial

import numpy as np
from scipy.spatial import cKDTree

from torchsym.core.parallel import run_branches, thread_budget

__all__ = ["Nearest", "SampledSearch", "argmin_profiles", "kdtree", "nearest_profiles", "profile_table"]

#: :class:`Nearest` goes by brute force when the queries' nearest rows lie beyond this many spacings
BRUTE_BEYOND = 3.0
#: approximation of the searches of every vertex after ZoomOut: each image at most ``1 + eps`` times as far as the nearest row
DENSE_EPS = 0.5


def kdtree(points: np.ndarray, balanced: bool = True) -> cKDTree:
    """scipy's kd-tree of ``points (N, D)``, leaves of 64 points below 30 dimensions (16 above).

    ``balanced=False`` splits cells at the middle of their longest side (scipy's
    ``balanced_tree``). Exact searches return the same points whatever the leaf size.
    """
    return cKDTree(points, leafsize=64 if points.shape[1] < 30 else 16, balanced_tree=balanced)


def profile_table(profiles: np.ndarray, dtype=np.float32) -> np.ndarray:
    """``profiles (V, A)`` augmented to ``[P | |p|^2]`` and transposed, ``(A + 1, V)`` in ``dtype``."""
    prof = np.asarray(profiles, dtype=np.float64)
    table = np.empty((prof.shape[1] + 1, prof.shape[0]), dtype=dtype)
    table[:-1] = prof.T
    table[-1] = np.einsum("ij,ij->i", prof, prof)
    return table


def argmin_profiles(queries: np.ndarray, table: np.ndarray, chunk: int = 512, values: bool = False):
    """For each row of ``queries (Q, A)`` the index ``(Q,)`` of the nearest profile of ``table`` (:func:`profile_table`).

    Brute force by ``|p|^2 - 2 q.p`` in the table's dtype, ``chunk`` queries at a time.
    With ``values``, also that minimum ``(Q,)`` (the squared distance less ``|q|^2``).
    """
    q = np.asarray(queries)
    out = np.empty(q.shape[0], dtype=np.int64)
    best = np.empty(q.shape[0], dtype=table.dtype)
    for start in range(0, q.shape[0], chunk):
        block = q[start : start + chunk]
        aug = np.empty((block.shape[0], table.shape[0]), dtype=table.dtype)  # (b, A + 1)
        np.multiply(block, -2.0, out=aug[:, :-1])
        aug[:, -1] = 1.0
        dist = aug @ table  # (b, V)
        idx = np.argmin(dist, axis=1)
        out[start : start + chunk] = idx
        if values:
            best[start : start + chunk] = dist[np.arange(idx.size), idx]
    return (out, best) if values else out


def nearest_profiles(queries: np.ndarray, profiles: np.ndarray, chunk: int = 512) -> np.ndarray:
    """For each row of ``queries (Q, A)`` the index ``(Q,)`` of the nearest row of ``profiles (V, A)``.

    Brute force in float32 (:func:`argmin_profiles`), for profiles of order 1 (distances
    on a unit-area mesh, eigenfunction embeddings), where the rounding only decides near ties.
    """
    return argmin_profiles(queries, profile_table(profiles), chunk)


class Nearest:
    """Nearest rows of ``points (N, D)``: an exact kd-tree search, or float32 brute force
    when the queries lie far from the points.

    Every 32nd query is answered first in float64; when their nearest points lie a median
    of more than :data:`BRUTE_BEYOND` spacings away (the median distance between
    neighbouring points, from 256 of them), every query goes by brute force, else by the
    kd-tree. The choice depends on the data alone, so it is deterministic.
    """

    def __init__(self, points: np.ndarray, spacing: float | None = None, tree: cKDTree | None = None):
        self.points = np.asarray(points, dtype=np.float64)
        self.dim = self.points.shape[1]
        self._tree = tree
        self._table32 = self._table64 = None  # profile_table's, built on the first brute-force search
        self._spacing = spacing

    @property
    def tree(self) -> cKDTree:
        if self._tree is None:
            self._tree = kdtree(self.points)
        return self._tree

    @property
    def spacing(self) -> float:
        """The median distance from a point to its nearest other point (from 256 points)."""
        if self._spacing is None:
            probe = self.points[:: max(1, self.points.shape[0] // 256)]
            gaps = self.tree.query(probe, k=2, workers=1)[0][:, 1] if self.points.shape[0] > 1 else np.zeros(1)
            self._spacing = float(np.median(gaps))
        return self._spacing

    def prepare(self) -> Nearest:
        """Build the kd-tree, the spacing and the brute-force tables now (before threads share them)."""
        _ = self.spacing
        if self._table32 is None:
            self._table64 = profile_table(self.points, np.float64)
            self._table32 = profile_table(self.points)
        return self

    def brute(self, queries: np.ndarray) -> np.ndarray:
        """Float32 brute force: for each row of ``queries (Q, D)`` the nearest point, ``(Q,)`` int64 (two threads)."""
        if self._table32 is None:
            self.prepare()
        if queries.shape[0] < 256:
            return argmin_profiles(queries, self._table32)
        half = queries.shape[0] // 2
        return np.concatenate(run_branches([partial(argmin_profiles, part, self._table32) for part in (queries[:half], queries[half:])]))

    def distances(self, queries: np.ndarray) -> np.ndarray:
        """Float64 brute force: for each row of ``queries (Q, D)`` the distance to the nearest point, ``(Q,)``."""
        if self._table64 is None:
            self.prepare()
        _, best = argmin_profiles(queries, self._table64, values=True)
        return np.sqrt(np.maximum(best + np.einsum("ij,ij->i", queries, queries), 0.0))

    def query(self, queries: np.ndarray) -> np.ndarray:
        """For each row of ``queries (Q, D)`` the index of the nearest point, ``(Q,)`` int64."""
        if float(np.median(self.distances(queries[::32]))) > BRUTE_BEYOND * self.spacing:
            return self.brute(queries)
        return self.tree.query(queries, k=1, workers=thread_budget())[1].astype(np.int64)


class SampledSearch:
    """Nearest rows of the eigenfunction embedding ``big (V, K)`` cut to its first ``kk`` columns,
    each search structure built once per ``kk`` (safe to share between threads).

    :meth:`dense` is the kd-tree over every vertex; :meth:`nearest` searches among
    ``targets`` only (sorted vertex indices; None: every vertex), as ZoomOut on a vertex
    subsample does (pyFM's ``subsample``).
    """

    def __init__(self, big: np.ndarray, targets: np.ndarray | None):
        self.big, self.targets = big, targets
        self._dense: dict[int, cKDTree] = {}
        self._sample: dict[int, Nearest] = {}
        self._lock = threading.Lock()

    def dense(self, kk: int) -> cKDTree:
        """The kd-tree of ``big[:, :kk]`` over every vertex."""
        kk = int(kk)
        with self._lock:
            if kk not in self._dense:
                self._dense[kk] = kdtree(self.big[:, :kk])
            return self._dense[kk]

    def sample(self, kk: int) -> Nearest:
        """The search among the targets' rows of ``big[:, :kk]`` (over every vertex: on :meth:`dense`'s tree)."""
        kk = int(kk)
        tree = self.dense(kk) if self.targets is None else None
        with self._lock:
            if kk not in self._sample:
                self._sample[kk] = Nearest(self.sample_points(self.big[:, :kk]), tree=tree).prepare()
            return self._sample[kk]

    def sample_points(self, points: np.ndarray) -> np.ndarray:
        """The rows of ``points (V, D)`` among which the sampled searches look."""
        return points if self.targets is None else points[self.targets]

    def to_vertices(self, index: np.ndarray) -> np.ndarray:
        """Vertex indices of positions in :meth:`sample_points`."""
        index = np.asarray(index, dtype=np.int64)
        return index if self.targets is None else self.targets[index]

    def map_every_vertex(self, fmap: np.ndarray, which: np.ndarray | None = None) -> np.ndarray:
        """The point map ``(V,)`` of ``fmap (kk, kk)``: each vertex to the vertex whose row of ``Phi``
        is nearest its row of ``Phi C``, approximately (:data:`DENSE_EPS`).

        With ``which`` (vertex indices), only those vertices' images, equal to those of the whole map.
        """
        kk = fmap.shape[0]
        queries = self.big[:, :kk] @ fmap  # (V, kk), for every vertex: a product of a subset may round otherwise
        if which is not None:
            queries = queries[which]
        return self.dense(kk).query(queries, k=1, eps=DENSE_EPS, workers=thread_budget())[1].astype(np.int64)

    def nearest(self, kk: int, queries: np.ndarray) -> np.ndarray:
        """For each row of ``queries (Q, kk)`` the vertex among the targets whose row of ``Phi`` is nearest (:class:`Nearest`)."""
        return self.to_vertices(self.sample(kk).query(queries))
