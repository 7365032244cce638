"""Intrinsic reflection symmetry of a triangle mesh with functional maps (thesis Ch. 6).

:func:`intrinsic_symmetry` runs the whole method of Sec. 6.2: Laplace-Beltrami
eigenpairs (6.2.3), HKS feature points and their pairing (6.2.4), the signs of the
eigenfunctions from geodesics between pairs, giving the diagonal functional map ``C``
(6.2.5, Theorem 6.2.1), the eigenfunction correction ``R`` on SO(k) (6.2.6, Eq. 6.4) and
the dense map by nearest neighbours in the spectral embedding (6.2.7).
:class:`IntrinsicSymmetry` is its module form, registered as ``intrinsic_symmetry``.

Beyond the thesis, the map can come from one of several hypotheses: the thesis's pairs,
pairs on the HKS alone, and an orientation-reversing functional map fitted to the dense
HKS (:mod:`torchsym.mesh.orientation`). They are compared on a vertex sample after
ZoomOut refinement by tests of an isometric involution; the thesis's map is replaced only
when another one also distorts geodesics less. A map that still keeps the orientation
over a region is realigned by distances to anchors (step 14).
"""

from __future__ import annotations

import copy
import dataclasses
import logging
import math
import threading
import time
from functools import partial
from pathlib import Path
from typing import Any, Literal

import numpy as np
import scipy.linalg
import torch
from scipy.spatial import cKDTree
from threadpoolctl import threadpool_limits
from torch import nn

from torchsym.core.checks import check_in_range, check_int, check_positive
from torchsym.core.parallel import run_branches
from torchsym.core.random import draw_seed, make_generator, random_subset
from torchsym.core.registry import register_solver
from torchsym.core.results import Result, on_input_device
from torchsym.errors import InputValueError
from torchsym.mesh.correction import correct_eigenfunctions
from torchsym.mesh.geodesic import geodesic_distances, thin_points
from torchsym.mesh.hks import heat_kernel_signature, hks_feature_points, hks_times
from torchsym.mesh.mesh import Mesh
from torchsym.mesh.operators import (
    consistently_wound,
    edge_face_counts,
    edge_graph,
    face_areas,
    laplacian_eigen,
    mass_matrix,
    ring_neighbourhood,
)
from torchsym.mesh.orientation import (
    OrientationTest,
    anticommutation_penalty,
    orientation_operators,
    orientation_reversing_map,
    reduce_descriptors,
    tangent_frames,
)
from torchsym.mesh.pairs import eigenfunction_signs, symmetric_pairs
from torchsym.mesh.repair import close_holes
from torchsym.mesh.validate import validate_mesh

__all__ = [
    "IntrinsicSymmetry",
    "IntrinsicSymmetryResult",
    "intrinsic_symmetry",
    "map_consistency",
    "map_quality",
    "pointwise_to_functional",
    "symmetry_colors",
]

logger = logging.getLogger(__name__)


def symmetry_colors(vertices: np.ndarray, vertex_map: np.ndarray) -> np.ndarray:
    """Per-vertex RGB in [0, 1] such that a vertex and its symmetric vertex share a colour.

    The colour comes from the position averaged with the mirror's position, so it is
    symmetric by construction and varies smoothly over the surface; vertices without a
    mirror (``-1``) are grey.

    Args:
        vertices: ``(V, 3)`` positions.
        vertex_map: ``(V,)`` int symmetric vertex of each vertex, ``-1`` for none.

    Returns:
        ``(V, 3)`` float colours.
    """
    v = np.asarray(vertices, dtype=np.float64)
    ok = vertex_map >= 0  # (V,)
    mid = v.copy()
    mid[ok] = 0.5 * (v[ok] + v[vertex_map[ok]])  # (V, 3)
    lo, hi = mid[ok].min(axis=0) if ok.any() else v.min(axis=0), mid[ok].max(axis=0) if ok.any() else v.max(axis=0)
    rgb = (mid - lo) / np.maximum(hi - lo, np.finfo(float).tiny)  # (V, 3)
    rgb = 0.15 + 0.7 * np.clip(rgb, 0.0, 1.0)
    rgb[~ok] = 0.5
    return rgb


def _same(value: Any) -> Any:
    return value


class _Deferred:
    """A value computed on first use (once, whichever thread asks first), then kept.

    Pickled and deep-copied as its value (computed then), so a result that holds one
    pickles and copies as a plain one.
    """

    def __init__(self, compute):
        self._compute, self._value, self._lock = compute, None, threading.Lock()

    def value(self) -> Any:
        with self._lock:
            if self._compute is not None:
                self._value, self._compute = self._compute(), None
            return self._value

    def __reduce__(self) -> tuple:
        return _same, (self.value(),)

    def __deepcopy__(self, memo: dict) -> Any:
        return copy.deepcopy(self.value(), memo)

    def __repr__(self) -> str:
        return "<searched when first read>" if self._compute is not None else repr(self._value)


@dataclasses.dataclass(frozen=True)
class IntrinsicSymmetryResult(Result):
    """The intrinsic reflection symmetry of a mesh (thesis Ch. 6).

    Attributes:
        map: ``(V,)`` int64, for every input vertex (input order) the index of its
            intrinsically symmetric vertex; ``-1`` for vertices of dropped components.
        functional_map: ``(k, k)`` the functional map ``C`` of the chosen hypothesis
            (before any ``refine_iters`` rounds, which work in a larger basis): for the
            thesis's pairs the diagonal ``diag(s)`` (+1 even, -1 odd eigenfunction, 0
            unused) in the corrected basis ``Phi R``; for the orientation-reversing
            hypothesis the full ``C`` in ``Phi`` (``R = I``), see
            :func:`~torchsym.mesh.orientation.orientation_reversing_map`.
        rotation: ``(k, k)`` the eigenfunction correction ``R`` in SO(k) (identity when
            the correction is off).
        map_before_refine: ``(V,)`` int64, the dense map (Sec. 6.2.7) from ``C`` and
            ``R`` of the chosen hypothesis, before the ZoomOut rounds (equal to ``map`` when
            ``refine_iters == 0``); input order, ``-1`` for dropped vertices. Where the
            ZoomOut rounds' map replaced it, it is only reported, and it comes from an
            approximate nearest-neighbour search: each image at most 1.5 times as far as
            the nearest candidate (``cKDTree.query(eps=0.5)``; in the embedding, or in
            space for the extrinsic hypothesis). On the benchmark's twisted 12,900-vertex
            mannequin-devil that search returned the nearest row for 89 % of the vertices,
            1.0008 times as far on average, in 0.06 s against 0.30 s. There it is
            searched when first read, outside the solver's ``timings`` (any read: the
            attribute, ``repr``, ``==``, :meth:`to_dict`, :meth:`to`, pickling or copying;
            on a GPU input the result's move to the device reads it inside the call): a
            caller who reads only ``map`` does not pay for it. Where it is the result
            (``refine_iters = 0``, or no hypothesis could be refined) the search is exact
            and runs in the call.
        refined_functional_map: ``(k_r, k_r)`` the functional map of the last ZoomOut
            round in the first ``k_r`` Laplace-Beltrami eigenfunctions ``Phi`` (``polish_k``
            when step 13's polished map was kept, else ``refine_k``)
            of the solved component, fitted on the selection's vertex sample: ``map`` is
            the nearest row of ``Phi`` to each row of ``Phi C_r``, by an approximate search
            (each image at most 1.5 times as far as the nearest row; see
            ``_DENSE_EPS`` in the module). ``(0, 0)`` when ``refine_iters == 0``.
        eigenvalues: ``(k,)`` Laplace-Beltrami eigenvalues of the mesh scaled to unit area.
        pairs: ``(P, 2)`` int64 sparse pairs of symmetric feature points (input indices)
            of the chosen pairing (the thesis's pairing when the orientation hypothesis
            was chosen).
        feature_points: ``(d,)`` int64 HKS feature points (input indices).
        timings: seconds per stage (``validate``, ``eigen``, ``features``, ``pairs``,
            ``signs``, ``correction``, ``map``, summed over the pairing hypotheses,
            ``orientation``, ``select``, ``extrinsic`` when that hypothesis was tried,
            ``refine``, ``orientation_check`` when step 12 ran, ``polish`` and ``realign``
            when steps 13 and 14 ran) and ``total``. Stages that ran side by side on
            threads (``features`` with the non-spectral work beside ``eigen``,
            ``orientation`` and part of ``select`` beside ``signs`` to ``map``) each count
            their own time, so the stages can add up to more than ``total``. ``map`` holds
            the thesis's dense map only where it is the result (see ``map_before_refine``).
        num_components: connected components of the input mesh.
        dropped_vertices: input vertices outside the component that was solved.
        correction_converged: whether every trust-region run of the chosen hypothesis
            stopped on its own tests (True when the correction is off, or for the
            orientation-reversing hypothesis, which has no correction).
        hypothesis: which hypothesis gave the map: ``"pairs"`` (the thesis's method),
            ``"hks_pairs"`` (pairs on HKS alone), ``"orientation"`` (the
            orientation-reversing functional map) or ``"extrinsic"`` (the vertices'
            mirror plane, step 10 of :func:`intrinsic_symmetry`).
        holes_closed: holes covered by a patch of new triangles before the spectrum was
            computed (``fill_holes``, :func:`~torchsym.mesh.repair.close_holes`; 0 for a
            closed mesh or when every boundary was left open, with a note saying why).
        notes: what the solver did that a caller should know (e.g. dropped components).
    """

    map: torch.Tensor
    functional_map: torch.Tensor
    rotation: torch.Tensor
    map_before_refine: torch.Tensor | _Deferred
    refined_functional_map: torch.Tensor
    eigenvalues: torch.Tensor
    pairs: torch.Tensor
    feature_points: torch.Tensor
    timings: dict[str, float]
    num_components: int
    dropped_vertices: int
    correction_converged: bool
    hypothesis: str = "pairs"
    holes_closed: int = 0
    notes: tuple[str, ...] = ()

    def __getattribute__(self, name: str) -> Any:
        value = object.__getattribute__(self, name)
        if name == "map_before_refine" and isinstance(value, _Deferred):
            value = value.value()
            object.__setattr__(self, name, value)  # a plain tensor from now on
        return value

    def write_artifacts(self, data: Any, out_dir: Path, stem: str) -> list[Path]:
        """Write ``{stem}_symmetry.ply`` (symmetric vertices share a colour) and ``{stem}_map.npy``."""
        from torchsym.io.write import write_mesh

        out_dir = Path(out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
        vmap = self.map.detach().cpu().numpy()
        paths = []
        if isinstance(data, Mesh):
            verts = data.vertices.detach().cpu().double().numpy()
            colors = symmetry_colors(verts, vmap)
            paths.append(write_mesh(out_dir / f"{stem}_symmetry.ply", data, colors=colors))
        npy = out_dir / f"{stem}_map.npy"
        np.save(npy, vmap)
        paths.append(npy)
        return paths


def map_consistency(tree: cKDTree, emb: np.ndarray, signs: np.ndarray, rows: np.ndarray, approx: float = 0.0) -> float:
    """How far the point map of ``C = diag(signs)`` is from realising ``C`` itself.

    The map sends vertex ``i`` to the nearest row of ``emb`` (the tree's points) to
    ``signs * emb[i]``, which is the dense map of Sec. 6.2.7 (a sign flip is an isometry of
    the embedding). The functional map that this point map induces, fitted by least squares
    on the vertices ``rows``, equals ``diag(signs)`` when the signs describe a real
    symmetry; a wrong sign leaves part of the shape without a consistent image and the fit
    drifts from it. Returns the Frobenius norm of the difference. ``approx > 0`` lets the
    nearest-neighbour search return points up to ``1 + approx`` times too far, which is
    several times faster in ``k`` dimensions where wrong signs put queries far from the data.
    """
    _, target = tree.query(emb[rows] * signs, k=1, eps=approx, workers=-1)
    return _consistency(emb, signs, rows, target)


def _consistency(emb: np.ndarray, signs: np.ndarray, rows: np.ndarray, target: np.ndarray) -> float:
    """:func:`map_consistency` of the map that sends ``rows`` to ``target``."""
    fitted = np.linalg.lstsq(emb[rows], emb[target], rcond=None)[0]  # (k, k)
    return float(np.linalg.norm(fitted - np.diag(signs)))


def pointwise_to_functional(phi: np.ndarray, area: np.ndarray, vertex_map: np.ndarray) -> np.ndarray:
    """The functional map ``C = Phi^T A Phi[T]`` of a point map ``T`` in the basis ``Phi``.

    ``Phi`` ``(V, k)`` holds area-orthonormal eigenfunctions and ``A`` the lumped areas
    ``(V,)``; column ``j`` of ``C`` holds the coefficients of ``phi_j o T``, so that
    ``Phi[T] ~ Phi C`` and ``T(i)`` is recovered as the row of ``Phi`` nearest to row ``i``
    of ``Phi C`` (ZoomOut's two half-steps).
    """
    return phi.T @ (area[:, None] * phi[vertex_map])


def map_quality(evecs: np.ndarray, area: np.ndarray, vertex_map: np.ndarray) -> float:
    """How far a point map is from an isometric involution, seen through its functional map.

    ``C = Phi^T A Phi[T]`` (``Phi`` area-orthonormal eigenfunctions, ``A`` lumped areas) is
    orthogonal for an isometry and squares to the identity for an involution; the result is
    ``|C^T C - I|_F + |C C - I|_F``, 0 for an exact intrinsic symmetry. The identity map
    scores 0 too, so callers must rule it out (:func:`intrinsic_symmetry` does: no odd
    eigenfunction, or most vertices left in place; it scores maps on a vertex sample).
    """
    return _involution_defect(pointwise_to_functional(evecs, area, vertex_map))


_HYPOTHESIS_TEXT = {
    "pairs": "thesis's pairs",
    "hks_pairs": "pairs on HKS alone (spectral_weight 0)",
    "orientation": "orientation-reversing functional map",
    "extrinsic": "extrinsic reflection plane of the vertices",
}


@dataclasses.dataclass
class _Candidate:
    """One hypothesis of the symmetry: its map sends vertex ``i`` to the row of ``target`` nearest ``query[i]``."""

    name: str
    pairs: np.ndarray
    fmap: np.ndarray
    rotation: np.ndarray
    converged: bool
    target: np.ndarray
    query: np.ndarray
    usable: bool
    notes: list[str]
    refined: np.ndarray | None = None
    start: np.ndarray | None = None


def _kdtree(points: np.ndarray, balanced: bool = True) -> cKDTree:
    """scipy's kd-tree of ``points (N, D)``, with leaves of 64 points below 30 dimensions (16 above).

    Exact searches return the same points whatever the leaf size; only their speed changes
    (approximate ones, ``eps > 0``, do not: :func:`_sign_hypotheses` keeps scipy's default). The queries of
    maps that are still inexact (a hypothesis before ZoomOut, early rounds) lie far from
    the points and visit most leaves, where larger leaves cost less: on the benchmark's
    twisted 12,900-vertex mannequin-devil the solver took 2.33 s against 2.65 s with the
    default 16 (``bench_mesh.py`` timing rows), with the same maps on all 244 benchmark
    meshes, and the 5,000-vertex FAUST / TOSCA shapes about 1 % less; in 40 dimensions 64
    was slower than 16 there. Approximate searches (``eps > 0``: ``map_before_refine`` and
    the maps of every vertex after ZoomOut) may return other points in another tree.
    ``balanced=False`` splits cells at the middle of their longest side instead of at the
    median (scipy's ``balanced_tree``); ``map_before_refine``'s search in 13 dimensions
    then took 0.06 s against 0.10 s on that mesh.
    """
    return cKDTree(points, leafsize=64 if points.shape[1] < 30 else 16, balanced_tree=balanced)


def _even_subset(points: np.ndarray, rows: np.ndarray, m: int, rng: np.random.Generator) -> np.ndarray:
    """Sorted vertex indices, at most ``m`` (and all of ``rows``): ``rows`` and vertices spread evenly over the surface.

    ``rows`` and one vertex (a random one) from each occupied cell of a cubic grid over
    ``points (V, 3)`` (a unit-area mesh), the cell side found by bisection so that the
    union holds at most ``m`` vertices (more only when ``rows`` alone does). An even
    spread keeps every vertex near a kept one; a uniformly random subset of the same size
    leaves gaps, and on the benchmark's twisted 12,900-vertex
    mannequin-devil it raised the functional defect of step 9 from 0.42 (every vertex) to
    0.48 at 6,000 vertices and 0.50 at 4,000 (where step 10's limit, 0.5, made the solver
    try the extrinsic plane), against 0.41-0.44 for this subset at 3,000-6,000.
    pymeshlab's Poisson-disk simplification (``generate_simplified_point_cloud``) also keeps
    input vertices, but its count is loose (4,444 asked 6,000 and 3,292 asked 3,000 on that
    mesh) and it cannot be told to keep ``rows``; the grid costs one :func:`numpy.unique`
    per bisection step (about 10 ms at 12,900 vertices).
    """
    rows = np.unique(rows)
    if rows.size >= m:
        return rows
    order = rng.permutation(points.shape[0])
    q = points[order] - points.min(axis=0)
    span = float(q.max())

    def subset(h: float) -> np.ndarray:
        cells = np.floor(q / h).astype(np.int64)  # (V, 3), each below 2^20
        keys = (cells[:, 0] << 40) | (cells[:, 1] << 20) | cells[:, 2]
        return np.union1d(rows, order[np.unique(keys, return_index=True)[1]])

    # a surface of area a holds about a / h^2 cells of side h; the mesh has unit area, and
    # rows fill part of the m
    free = m - rows.size
    lo, hi = max(0.25 / math.sqrt(m), span / 2.0**19), max(4.0 / math.sqrt(free), span / 2.0**19)
    for _ in range(8):
        mid = math.sqrt(lo * hi)
        if subset(mid).size > m:
            lo = mid
        else:
            hi = mid
    out = subset(hi)
    return out if out.size <= m else rows


_BRUTE_BEYOND = 3.0  # _Nearest: brute force when the queries' nearest points lie beyond this many spacings


class _Nearest:
    """Nearest rows of ``points (N, D)``: by an exact kd-tree search, or by brute force when the queries lie far from the points.

    The sampled rounds of steps 9-13 search ``N`` of about 1,000-6,000 rows for 1,000
    queries. A kd-tree answers a query near its nearest point quickly, but the queries of a
    map that is still inexact can lie far from the points and visit most of its leaves.
    So every 32nd query is first answered by brute force; when their nearest points lie a
    median of more than ``_BRUTE_BEYOND`` times the points' spacing away (the median distance
    between neighbouring points, from 256 of them), all queries are, else the kd-tree
    answers them. Brute force is :func:`_argmin_profiles` (``argmin_j |p_j|^2 - 2 q.p_j``,
    the points' table built once), in float32 (the probes' distances in float64), the
    queries split between two threads. Its rounding, about ``1e-7`` of ``|p|^2``,
    can only pick a near tie instead of the nearest point, for queries that lie beyond 3
    spacings anyway: on 18 benchmark meshes (FAUST, TOSCA, synthetic) two maps changed, at
    0.3 % and 0.1 % of the vertices, against float64 (twice as slow: the twisted
    mannequin-devil below took 0.81 s against 0.77 s, interleaved in one process). The
    choice between the two searches, made from the data alone, is deterministic.

    Over the sampled rounds of 32 benchmark meshes (FAUST, TOSCA, synthetic; 659 searches)
    the kd-tree took 0.69x the time of brute force (on two threads) where the probes' median
    lay within 2 spacings, 0.9-1.0x within 2-6, and 1.5-2.2x beyond; on the twisted
    12,900-vertex mannequin-devil the searches of its farthest hypothesis (a median 5-23
    spacings away, 1,000 queries among 5,975 rows) took 12-16 ms on the kd-tree and 6-7 ms
    by brute force.
    """

    def __init__(self, points: np.ndarray, spacing: float | None = None, tree: cKDTree | None = None):
        self.points = np.asarray(points, dtype=np.float64)
        self.dim = self.points.shape[1]
        self._tree = tree
        self._table32 = self._table64 = None  # _profile_table's, built on the first brute-force search
        self._spacing = spacing

    @property
    def tree(self) -> cKDTree:
        if self._tree is None:
            self._tree = _kdtree(self.points)
        return self._tree

    @property
    def spacing(self) -> float:
        """The median distance from a point to its nearest other point (from 256 points)."""
        if self._spacing is None:
            probe = self.points[:: max(1, self.points.shape[0] // 256)]
            gaps = self.tree.query(probe, k=2, workers=1)[0][:, 1] if self.points.shape[0] > 1 else np.zeros(1)
            self._spacing = float(np.median(gaps))
        return self._spacing

    def prepare(self) -> _Nearest:
        """Build the kd-tree, the spacing and the brute-force tables now (before threads share them)."""
        _ = self.spacing
        if self._table32 is None:
            self._table64 = _profile_table(self.points, np.float64)
            self._table32 = _profile_table(self.points)
        return self

    def brute(self, queries: np.ndarray) -> np.ndarray:
        """Brute force in float32 (:func:`_argmin_profiles`): for each row of ``queries (Q, D)`` the nearest point, ``(Q,)`` int64."""
        if self._table32 is None:
            self.prepare()
        if queries.shape[0] < 256:
            return _argmin_profiles(queries, self._table32)
        half = queries.shape[0] // 2
        return np.concatenate(run_branches([partial(_argmin_profiles, part, self._table32) for part in (queries[:half], queries[half:])]))

    def distances(self, queries: np.ndarray) -> np.ndarray:
        """Brute force in float64: for each row of ``queries (Q, D)`` the distance to the nearest point."""
        if self._table64 is None:
            self.prepare()
        _, best = _argmin_profiles(queries, self._table64, values=True)
        return np.sqrt(np.maximum(best + np.einsum("ij,ij->i", queries, queries), 0.0))

    def query(self, queries: np.ndarray) -> np.ndarray:
        """For each row of ``queries (Q, D)`` the index of the nearest point, ``(Q,)`` int64."""
        if float(np.median(self.distances(queries[::32]))) > _BRUTE_BEYOND * self.spacing:
            return self.brute(queries)
        return self.tree.query(queries, k=1, workers=-1)[1].astype(np.int64)


class _Searches:
    """Nearest rows of the eigenfunction embedding ``big[:, :kk]``, each search structure built once per ``kk``.

    :meth:`dense` is the kd-tree over every vertex, for the maps of every vertex. :meth:`nearest`
    answers the sampled rounds (ZoomOut on the vertex sample, steps 9-13) by :class:`_Nearest`
    among ``targets`` only (sorted vertex indices holding the sample,
    :func:`_even_subset`; None: every vertex), as ZoomOut on a vertex subsample does
    (pyFM's ``subsample``): the sampled rounds then search a fraction of the vertices,
    and only the maps of every vertex search them all.
    """

    def __init__(self, big: np.ndarray, targets: np.ndarray | None):
        self.big, self.targets = big, targets
        self._dense: dict[int, cKDTree] = {}
        self._sample: dict[int, _Nearest] = {}
        self._lock = threading.Lock()  # branches on threads (run_branches) share the structures

    def dense(self, kk: int) -> cKDTree:
        kk = int(kk)
        with self._lock:
            if kk not in self._dense:
                self._dense[kk] = _kdtree(self.big[:, :kk])
            return self._dense[kk]

    def sample(self, kk: int) -> _Nearest:
        """The search among the targets' rows of ``big[:, :kk]`` (over every vertex: on :meth:`dense`'s tree)."""
        kk = int(kk)
        tree = self.dense(kk) if self.targets is None else None
        with self._lock:
            if kk not in self._sample:
                self._sample[kk] = _Nearest(self.sample_points(self.big[:, :kk]), tree=tree).prepare()
            return self._sample[kk]

    def sample_points(self, points: np.ndarray) -> np.ndarray:
        """The rows of ``points (V, D)`` among which the sampled rounds search."""
        return points if self.targets is None else points[self.targets]

    def to_vertices(self, index: np.ndarray) -> np.ndarray:
        """Vertex indices of positions in :meth:`sample_points`."""
        index = np.asarray(index, dtype=np.int64)
        return index if self.targets is None else self.targets[index]

    def map_every_vertex(self, fmap: np.ndarray, which: np.ndarray | None = None) -> np.ndarray:
        """The point map of ``fmap (kk, kk)``: each vertex to the vertex whose row of ``Phi`` is nearest its row of ``Phi C``.

        Approximate (``eps = _DENSE_EPS``): each image at most ``1 + eps`` times as far as
        the nearest row. With ``which`` (vertex indices), only those vertices' images, the
        same as those of the whole map (each search is its own).
        """
        kk = fmap.shape[0]
        queries = self.big[:, :kk] @ fmap  # (V, kk), for every vertex: a product of a subset may round otherwise
        if which is not None:
            queries = queries[which]
        return self.dense(kk).query(queries, k=1, eps=_DENSE_EPS, workers=-1)[1].astype(np.int64)

    def nearest(self, kk: int, queries: np.ndarray) -> np.ndarray:
        """For each row of ``queries (Q, kk)`` the vertex among the targets whose row of ``Phi`` is nearest (:class:`_Nearest`)."""
        return self.to_vertices(self.sample(kk).query(queries))


def _fit_functional(phi_rows: np.ndarray, phi_image: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Least-squares functional map ``C`` with ``Phi[rows] C ~ Phi[T(rows)]``, area-weighted.

    On every vertex with area weights this is ``Phi^T A Phi[T]`` (:func:`pointwise_to_functional`);
    on a vertex sample the least-squares form also corrects for the sampled basis not
    being orthonormal.
    """
    root = np.sqrt(weights)[:, None]
    return np.linalg.lstsq(root * phi_rows, root * phi_image, rcond=None)[0]


def _involution_defect(fmap: np.ndarray) -> float:
    """``|C^T C - I|_F + |C C - I|_F``: 0 for the functional map of an isometric involution."""
    eye = np.eye(fmap.shape[0])
    return float(np.linalg.norm(fmap.T @ fmap - eye) + np.linalg.norm(fmap @ fmap - eye))


def nearest_involution(fmap: np.ndarray) -> np.ndarray:
    """The symmetric orthogonal matrix nearest ``fmap`` (Frobenius norm): ``Q sign(L) Q^T``.

    ``(C + C^T) / 2 = Q L Q^T``. Such an ``S`` has ``S^T S = S S = I``: the functional map
    of an isometric involution in an orthonormal basis. It is the nearest to ``C`` itself,
    not only to its symmetric part: for symmetric ``S``,
    ``|C - S|^2 = |sym C - S|^2 + |skew C|^2``, and among symmetric orthogonal matrices
    the first term is smallest for ``S = Q sign(L) Q^T`` (von Neumann's trace inequality).
    An eigenvalue exactly 0 makes the answer non-unique; it is given the sign +1.
    """
    lam, q = np.linalg.eigh(0.5 * (fmap + fmap.T))
    return (q * np.where(lam >= 0, 1.0, -1.0)) @ q.T


def _zoomout_fit(phi: np.ndarray, area: np.ndarray, rows: np.ndarray, image: np.ndarray, factor) -> np.ndarray:
    """One fit of ZoomOut: ``C`` with ``Phi[rows] C ~ Phi[image]``, plain (``factor`` None) or with the orientation penalty.

    ``factor``: the Cholesky factor of :func:`_oriented_fits` for ``phi``'s ``kk`` columns.
    """
    if factor is None:
        return _fit_functional(phi[rows], phi[image], area[rows])  # (kk, kk)
    kk = phi.shape[1]
    weights = area[rows] / area[rows].sum()
    rhs = phi[rows].T @ (weights[:, None] * phi[image])  # (kk, kk)
    return scipy.linalg.cho_solve(factor, rhs.reshape(-1)).reshape(kk, kk)


def _sampled_zoomout(
    big: np.ndarray, area: np.ndarray, rows: np.ndarray, image: np.ndarray, ks: np.ndarray, trees: _Searches,
    involution: bool = True, oriented: dict | None = None, brute: bool = False,
) -> tuple[np.ndarray, np.ndarray | None]:
    """ZoomOut (Melzi et al. 2019) on the vertex sample ``rows``: returns the sample's image and the last ``C``.

    Each round fits ``C`` in the first ``kk`` eigenfunctions from the sample's current
    images (:func:`_fit_functional`), and maps each sampled vertex to the nearest row of
    ``Phi`` to its row of ``Phi C``. With ``involution``, ``C`` is first averaged with the
    fit of the inverse map (each sample's preimage: the vertex whose row of ``Phi C`` is
    nearest the sample's row of ``Phi``; an involution is its own inverse, so both fit
    the same ``C``, and the average counters the many-to-one collapse of
    nearest-neighbour maps) and then replaced by the nearest isometric involution
    (:func:`nearest_involution`). With 1,000 samples, plain ZoomOut here matched full ZoomOut to
    0.1 point of correspondence rate on FAUST, TOSCA and the synthetic meshes, at a
    fraction of the nearest-neighbour queries.

    With ``oriented`` (:func:`_oriented_fits`: for each ``kk`` of ``ks`` the factorised
    normal equations of the fit with the orientation penalty) each fit minimises instead
    ``|Phi[rows] C - Phi[T(rows)]|_A^2 / a + w sum_p |C O_p + O_p C|^2 / s``: the
    functional map of an intrinsic reflection anticommutes with the orientation operator
    ``O_p`` of every descriptor it preserves (Ren et al. 2018), while the maps plain
    ZoomOut settles on may keep the orientation over whole regions.

    With ``brute`` (step 14's rounds, far from a settled map, where the kd-trees in ``kk``
    dimensions visit most of their leaves) the searches are :func:`_nearest_profiles`
    (no kd-tree), each image among ``trees``'s targets and each preimage among the sample only.

    Every search here is among ``trees``'s targets, a subset of the vertices on a large
    mesh (``search_vertices`` of :func:`intrinsic_symmetry`), and exact but for near ties
    where queries far from the points go by float32 brute force (:class:`_Nearest`).
    """
    fitted = None
    for kk in ks:
        phi = big[:, :kk]  # (V, kk)
        factor = None if oriented is None else oriented[int(kk)]
        fitted = _zoomout_fit(phi, area, rows, image, factor)
        if involution:
            # the inverse map too: each sample's preimage is the vertex whose row of Phi C
            # is nearest its row of Phi; for an involution T^-1 = T, so both fit the same C
            if brute:
                pre = rows[_nearest_profiles(phi[rows], phi[rows] @ fitted)]
            else:
                # (C is near an orthogonal matrix, which keeps the spacing of the points)
                pre = trees.to_vertices(_Nearest(trees.sample_points(phi) @ fitted, trees.sample(kk).spacing).query(phi[rows]))
            fitted = nearest_involution(0.5 * (fitted + _zoomout_fit(phi, area, rows, pre, factor)))
        if brute:
            image = trees.to_vertices(_nearest_profiles(phi[rows] @ fitted, trees.sample_points(phi)))
        else:
            image = trees.nearest(kk, phi[rows] @ fitted)
    return image, fitted


def _oriented_fits(
    big: np.ndarray, area: np.ndarray, rows: np.ndarray, ks: np.ndarray, ops: np.ndarray, weights: tuple[float, ...]
) -> list[dict]:
    """Cholesky factors of the normal equations of ZoomOut's fit with the orientation penalty.

    For each weight ``w`` of ``weights`` a dict ``{kk: factor}`` over ``ks``. The fit of
    :func:`_sampled_zoomout` minimises over ``C`` (``kk x kk``)
    ``|Phi[rows] C - Phi[T(rows)]|_A^2 / a + w sum_p |C O_p + O_p C|^2 / s`` with
    ``A`` the sample's lumped areas, ``a`` their sum and ``s`` the penalty's mean under a
    uniformly random orthogonal ``C`` (:func:`~torchsym.mesh.orientation.anticommutation_penalty`):
    in ``vec(C)`` (row major) the matrix is ``G kron I + w P`` with
    ``G = Phi[rows]^T A Phi[rows] / a``, the same for every hypothesis and every round
    at one ``kk``, so it is factorised once (``kk^2`` unknowns: dense, ``kk^4`` memory and
    ``kk^6`` time, which is why :func:`intrinsic_symmetry` skips the check above
    ``refine_k = 50``). ``ops``: ``(p, K, K)`` orientation operators in the first
    ``K >= max(ks)`` eigenfunctions; those of the first ``kk`` are their leading blocks.

    Raises:
        numpy.linalg.LinAlgError: a matrix that is numerically not positive definite.
    """
    sample = area[rows] / area[rows].sum()
    out: list[dict] = [{} for _ in weights]
    for kk in np.unique(ks):
        phi = big[rows, :kk]  # (S, kk)
        data = np.kron(phi.T @ (sample[:, None] * phi), np.eye(kk))  # (kk^2, kk^2)
        penalty = anticommutation_penalty(ops[:, :kk, :kk])
        for table, weight in zip(out, weights):
            table[int(kk)] = scipy.linalg.cho_factor(data + weight * penalty)
    return out


# Share of vertices a map may leave near themselves (GeodesicProbe.near_self). The true
# symmetries of the benchmark's meshes leave 11-42 % (FAUST 17-24 %, TOSCA's cats, dogs and
# horses about 30 %, a camel 42 %); the partial identities seen there 66-100 %.
_NEAR_SELF_LIMIT = 0.6
_WEAK_DEFECT = 0.5
# a low-scoring plane's refined map replaces the weak intrinsic one when each of its tests is
# at most this share of the weak map's (step 10); the same 0.6 as "clearly more consistent"
# for the sign hypotheses of step 7
_EXTRINSIC_CLEARLY = 0.6
# Orientation test of the final map (step 12 of intrinsic_symmetry): on FAUST and TOSCA
# the true symmetries reverse the orientation at 65-85 % of the vertices, the FAUST maps
# that turn the torso half a turn keep it at 65-80 %.
_KEEPS_ORIENTATION = 0.5  # re-refine a map that reverses it at fewer vertices than this
_REVERSES_ORIENTATION = 0.6  # and take a re-refined map that reverses it at this many
_ORIENTATION_SCALES = (0.1, 1.0)  # penalty weights tried, times refine_orientation
# A re-refined map must move more of the shape than step 9 asks (_NEAR_SELF_LIMIT): the true
# symmetries leave 11-42 % near themselves, while on TOSCA's cat9, where no hypothesis passed,
# the penalty also produced half identities (55 %, rate 0.13-0.19) that passed the other tests.
_REORIENTED_NEAR_SELF = 0.5
# When no hypothesis passed step 9, the re-refined maps of step 12 may distort geodesics up
# to this many times step 9's limit. The limit keeps a wrong map from replacing a passing
# one; here the alternative is the thesis's map unrefined, which failed the tests. TOSCA's
# cat9, a pose far from isometric, is the case: its ground-truth map distorts the sampled
# geodesics by 0.18 (1.5 x 0.12), its re-refined map by 0.14 (rate 0.576 unrefined -> 0.752;
# 1.25x and 2x gave the same map, and cat6, the benchmark's other rescued mesh, kept its own).
_RESCUE_DISTORTION = 1.5
_ORIENTATION_MAX_K = 50
# map_before_refine, when ZoomOut's map replaced it, by an approximate search: each image at
# most 1 + this times as far as the nearest (see IntrinsicSymmetryResult.map_before_refine)
_COARSE_EPS = 0.5
# The maps of every vertex after ZoomOut (steps 11-14) by an approximate search, each image
# at most 1 + this times as far as the nearest row (cKDTree's eps). On the twisted
# 12,900-vertex mannequin-devil such a search in 40 eigenfunctions returned the nearest row
# for 98 % of the vertices, 1.0002 times as far on average, in 0.11 s against 0.26 s (0.06
# against 0.11 s in 25), and the solver took 1.46-1.62 s (three bench_mesh runs, BLAS then
# on two threads) against 1.71 s.
# In the benchmark's run every rate of FAUST and TOSCA stayed within 0.1 point (8 and 5
# shapes moved, by up to 0.08 point); with holes FAUST tr_reg_076 rose 0.979 -> 0.995 and
# tr_reg_096 fell 0.975 -> 0.973. Not kept: the same eps in the sample's searches (1.38 s) broke TOSCA's
# cat10 (0.98 -> 0.25) and cat9 (0.75 -> 0.68), in the preimage searches alone cat9 (0.44);
# unbalanced trees here (a further 0.03 s) cost dog10 0.99 -> 0.88. The sample's rounds steer
# ZoomOut; these searches read out a map that has settled, though steps 12-14 still test it
# (which is how another tree moved dog10).
_DENSE_EPS = 0.5
# Step 13 keeps the map polished in polish_k eigenfunctions unless its share of sampled
# vertices where the orientation is reversed falls by more than this: on FAUST the polished
# maps that lost 2-4 points of correspondence rate (a hand or the arms swapped) fell by
# 0.08-0.10, the ones that gained rose or fell by under 0.04.
_POLISH_ORIENTATION_DROP = 0.05
# Step 14 keeps a realigned map only if it reverses the orientation at more than this many
# points more of the sampled vertices (a scratch replay on TOSCA: the cats whose heads it
# repaired rose by 5-15 points; the maps it spoiled, cat6 and victoria2, by at most 1).
_REALIGN_GAIN = 0.02
# and runs only on maps that reverse it at fewer of them than this: the maps it repaired on
# TOSCA reversed it at 67-78 %; an exact mirror symmetry reverses it at 100 %.
_REALIGN_BELOW = 0.9


class GeodesicProbe:
    """Sampled geodesic tests of a self map on the unit-area mesh.

    :meth:`distortion`: ``mean |d(x, y) - d(T x, T y)| / mean d(x, y)`` with ``x`` over
    ``n_sources`` vertices and ``y`` over ``n_targets`` vertices, both drawn from ``rows``
    (the vertices where the maps are known); an isometry scores 0.

    :meth:`near_self`: the share of ``n_balls`` vertices of ``rows`` that the map leaves
    within ``radius`` of themselves (the correspondence-rate tolerance of thesis Sec.
    6.3.2, ``sqrt(1 / (20 pi))`` on a unit-area mesh). A reflection moves all but a band
    along its symmetry curve (17-24 % of the vertices on FAUST, up to 42 % on a thin
    camel); a map that leaves most of the shape in place is (partly) the identity, which
    the other tests would score as a perfect isometry. Geodesic, not Euclidean: the legs of a cat are close in space but
    far on the surface.

    Distances are Dijkstra's on the edge graph.
    """

    def __init__(
        self,
        graph,
        rows: np.ndarray,
        rng: np.random.Generator,
        n_sources: int = 16,
        n_targets: int = 400,
        n_balls: int = 100,
        radius: float = math.sqrt(1.0 / (20.0 * math.pi)),
    ):
        pick = rng.permutation(rows.size)
        self.src = pick[: min(n_sources, rows.size)]  # positions in rows
        self.dst = pick[: min(n_targets, rows.size)]
        self.ball_rows = pick[: min(n_balls, rows.size)]
        self.graph, self.rows, self.radius = graph, rows, radius
        self.base = geodesic_distances(graph, rows[self.src])[:, rows[self.dst]]  # (s, t)
        self.scale = max(float(np.mean(self.base)), np.finfo(float).tiny)
        self.balls = geodesic_distances(graph, rows[self.ball_rows], limit=radius)  # (b, V), inf beyond

    def distortion(self, image: np.ndarray) -> float:
        """``image``: ``(S,)`` the map's value at each of ``rows``."""
        mapped = geodesic_distances(self.graph, image[self.src])[:, image[self.dst]]  # (s, t)
        return float(np.mean(np.abs(mapped - self.base)) / self.scale)

    def near_self(self, image: np.ndarray) -> float:
        """``image``: ``(S,)`` the map's value at each of ``rows``."""
        moved = self.balls[np.arange(self.ball_rows.size), image[self.ball_rows]]  # (b,)
        return float(np.mean(moved < self.radius))


def _profile_table(profiles: np.ndarray, dtype=np.float32) -> np.ndarray:
    """``profiles (V, A)`` augmented to ``[P | |p|^2]`` and transposed, ``(A + 1, V)`` in ``dtype``: what :func:`_argmin_profiles` searches."""
    prof = np.asarray(profiles, dtype=np.float64)
    table = np.empty((prof.shape[1] + 1, prof.shape[0]), dtype=dtype)
    table[:-1] = prof.T
    table[-1] = np.einsum("ij,ij->i", prof, prof)
    return table


def _argmin_profiles(queries: np.ndarray, table: np.ndarray, chunk: int = 512, values: bool = False):
    """For each row of ``queries (Q, A)`` the index of the nearest profile of ``table`` (:func:`_profile_table`).

    Brute force: each block of ``chunk`` queries is augmented to ``[-2 q | 1]``, so that one
    product in the table's dtype gives ``|p|^2 - 2 q.p``, the squared distances less
    ``|q|^2``. With ``values``, also that minimum ``(Q,)``.
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


def _nearest_profiles(queries: np.ndarray, profiles: np.ndarray, chunk: int = 512) -> np.ndarray:
    """For each row of ``queries (Q, A)`` the index of the nearest row of ``profiles (V, A)``.

    Brute force by ``|p|^2 - 2 q.p`` in float32 (:func:`_argmin_profiles`): with
    ``A`` about 64 a kd-tree visits most of its leaves, and the products are several times
    faster. The rounding can pick a near tie instead of the nearest row when the rows share
    a large common offset against their spread; the callers' profiles (distances on a
    unit-area mesh, eigenfunction embeddings) are of order 1.
    :class:`~torchsym.matching.KNNIndex` with ``method="brute"`` is exact (float64,
    re-ranked) but 2-3x slower on these blocks, and step 14 makes 14 such searches per mesh.
    """
    return _argmin_profiles(queries, _profile_table(profiles), chunk)


def _anchor_realignment(
    distances, rows: np.ndarray, vertex_map: np.ndarray, anchors: np.ndarray, iters: int,
) -> np.ndarray:
    """Step 14's spatial realignment: each sampled vertex to the vertex whose distances to the anchors' images match its own.

    An isometric involution ``T`` keeps distances: ``d(T a, T x) = d(a, x)`` for every
    anchor ``a``. So ``T x`` is the vertex ``y`` whose profile of distances to the images
    ``T a`` is nearest the profile of ``x`` to the anchors (the geodesic coordinates of
    Kim et al. 2011's blended intrinsic maps, used here to repair a map rather than to
    build one). Each round re-reads the images of the anchors (a subset of ``rows``) from
    the new map. ``distances(sources)`` gives ``(len(sources), V)``; rows for repeated
    sources are cached, since the images settle after the first round.

    ``rows`` must be sorted and hold every anchor (the anchors are found in it by
    :func:`numpy.searchsorted`). The profiles are compared in float32
    (:func:`_nearest_profiles`): distances on the unit-area mesh are of order 1, where the
    rounding only decides between near ties.

    Returns:
        ``(S,)`` the new image of every vertex of ``rows``.
    """
    cache: dict[int, np.ndarray] = {}

    def profile(sources: np.ndarray) -> np.ndarray:
        todo = np.array(sorted({int(s) for s in sources} - cache.keys()), dtype=np.int64)
        if todo.size:
            for s, row in zip(todo, distances(todo)):
                cache[int(s)] = row
        return np.stack([cache[int(s)] for s in sources])  # (A, V)

    where = np.searchsorted(rows, anchors)  # anchors are sampled vertices
    if not (np.all(rows[:-1] < rows[1:]) and np.array_equal(rows[np.minimum(where, rows.size - 1)], anchors)):
        raise InputValueError("rows, anchors: expected sorted distinct rows that hold every anchor")
    base = profile(anchors)[:, rows].T  # (S, A) the sampled vertices' distances to the anchors
    image = vertex_map[rows].copy()  # (S,)
    for _ in range(iters):
        image = _nearest_profiles(base, profile(image[where]).T)
    return image


def _extrinsic_candidate(
    v: np.ndarray, evecs: np.ndarray, area: np.ndarray, pairs: np.ndarray, n_samples: int, seed: int
) -> tuple[_Candidate, float]:
    """The map of the vertices' best mirror plane (an extension): each vertex to the vertex
    nearest its mirror image, and the plane's symmetry score.

    The plane is :func:`~torchsym.pointcloud.detect_reflection_plane`'s on at most
    ``n_samples`` vertices (its own seed, so the other hypotheses draw the same samples
    with or without it). A shape in a near-symmetric pose maps onto itself under the plane's
    reflection, and a reflection that maps a surface onto itself is an isometry of it.
    """
    from torchsym.pointcloud.reflection_plane import detect_reflection_plane

    gen = torch.Generator().manual_seed(seed)
    pts = torch.from_numpy(v)
    if v.shape[0] > n_samples:
        pts = pts[random_subset(v.shape[0], n_samples, gen)]
    plane = detect_reflection_plane(pts, kernel={"enabled": False}, generator=gen)
    nrm, off = plane.normal.numpy(), float(plane.offset)
    mirrored = v - 2.0 * (v @ nrm + off)[:, None] * nrm  # (V, 3)
    vmap = _kdtree(v).query(mirrored, k=1, workers=-1)[1].astype(np.int64)
    cand = _Candidate(
        "extrinsic", pairs, pointwise_to_functional(evecs, area, vmap), np.eye(evecs.shape[1]), True, v, mirrored, True, []
    )
    return cand, float(plane.score)


def _rank_choice(table: np.ndarray, max_distortion: float = math.inf) -> int:
    """The row with the smallest sum of ranks over the columns (ties: the earlier row).

    Rows of ``inf`` (unusable hypotheses) rank last; when every row is ``inf`` the first
    wins. A winner other than row 0 must also have a last column (the geodesic
    distortion) below ``max_distortion`` and below row 0's, or row 0 is kept.
    """
    n = table.shape[0]
    ranks = np.zeros(n)
    for col in table.T:
        order = np.argsort(col, kind="stable")
        ranks[order] += np.arange(n)
    ranks[~np.isfinite(table).all(axis=1)] = np.inf
    if not np.isfinite(ranks).any():
        return 0
    best = int(np.argmin(ranks))
    distortion = table[:, -1]
    return best if best == 0 or distortion[best] < min(max_distortion, distortion[0]) else 0


def _sign_sample(
    n: int, rng: np.random.Generator, points: np.ndarray | None, max_points: int
) -> tuple[np.ndarray, np.ndarray | None]:
    """:func:`_sign_hypotheses`'s 800 sorted vertices, and the even subset holding them that the images are sought among (None: all)."""
    rows = np.sort(rng.choice(n, size=min(n, 800), replace=False))
    keep = _even_subset(points, rows, max_points, rng) if points is not None and n > max_points else None
    return rows, keep


def _sign_hypotheses(
    emb: np.ndarray,
    signs: np.ndarray,
    confidence: np.ndarray,
    n_flip: int,
    margin: float,
    rng: np.random.Generator | tuple[np.ndarray, np.ndarray | None],
    accept: float = 0.1,
    points: np.ndarray | None = None,
    max_points: int = 6000,
) -> tuple[np.ndarray, float, float]:
    """Try both signs of the ``n_flip`` least-confident eigenfunctions; keep the most consistent.

    Returns the chosen signs and the consistency (:func:`map_consistency`) of the thesis's
    signs and of the chosen ones. The thesis's signs are kept without a search when their
    consistency is already below ``accept`` (on FAUST and TOSCA, maps with a correspondence
    rate above 95 % score 0.03-0.06, failed ones 0.15-0.4), and replaced only by a sign
    vector whose consistency is below ``margin`` times theirs. With ``points`` (the unit-area
    vertices) on more than ``max_points`` vertices, the images are sought among
    ``max_points`` of them (:func:`_even_subset`, as ``search_vertices`` of
    :func:`intrinsic_symmetry`). ``rng``: the generator of the vertex sample, or the sample
    it gives (:func:`_sign_sample`), drawn ahead.
    """
    use = np.nonzero(signs != 0)[0]
    use = use[use != 0]  # the constant eigenfunction is always even
    flip = use[np.argsort(np.abs(confidence[use]), kind="stable")[:n_flip]]
    cols = signs != 0
    sub_emb = emb[:, cols]
    rows, keep = _sign_sample(emb.shape[0], rng, points, max_points) if isinstance(rng, np.random.Generator) else rng
    if keep is not None:  # the images among an even subset that holds the rows
        sub_emb, rows = sub_emb[keep], np.searchsorted(keep, rows)
    tree = cKDTree(sub_emb)  # default leaves: its searches are approximate (eps), so the leaf size would change them
    # the thesis's signs' map: by the exact tree search, or by brute force where it lies far from the rows (:class:`_Nearest`)
    base = _consistency(sub_emb, signs[cols], rows, _Nearest(sub_emb, tree=tree).query(sub_emb[rows] * signs[cols]))
    if base < accept:
        return signs, base, base
    base = map_consistency(tree, sub_emb, signs[cols], rows, approx=1.0)  # compared like with like
    best, best_q = signs, base
    for mask in range(1, 2 ** flip.size):
        trial = signs.copy()
        chosen = flip[[(mask >> b) & 1 == 1 for b in range(flip.size)]]
        trial[chosen] *= -1.0
        q = map_consistency(tree, sub_emb, trial[cols], rows, approx=1.0)
        if q < best_q:
            best, best_q = trial, q
    if best_q >= margin * base:
        return signs, base, base
    return best, base, best_q


@on_input_device
# The dense linear algebra after the eigendecomposition is small (at most V x 40 times
# 40 x 40), and the nearest-neighbour searches that dominate run on every core
# (``workers=-1``); idle BLAS threads that spin between the small products took a core
# from those searches: on the benchmark's twisted 12,900-vertex mannequin-devil the solver
# took 1.45-1.55 s with scipy's default two BLAS threads and 1.25-1.30 s with one (median
# of 5 runs each, 2-core machine; single-threaded searches gained nothing until then).
@threadpool_limits.wrap(limits=1, user_api="blas")
def intrinsic_symmetry(
    mesh: Mesh,
    *,
    n_eigen: int = 13,
    n_times: int = 50,
    max_features: int = 25,
    feature_radius: float = 0.15,
    max_pairs: int = 5,
    max_pair_cost: float = 0.5,
    penalty: float = 1e6,
    spectral_weight: float = 1.0,
    cross_pairs: bool = True,
    min_confidence: float = 0.0,
    sign_hypotheses: int = 3,
    pairing_hypotheses: bool = True,
    orientation_hypothesis: bool = True,
    extrinsic_hypothesis: bool = True,
    extrinsic_min_score: float = 0.75,
    extrinsic_samples: int = 3000,
    select_samples: int = 1000,
    search_vertices: int = 6000,
    max_distortion: float = 0.12,
    max_distortion_open: float = 0.12,
    correct: bool = True,
    mu: float = 0.01,
    max_iter: int = 50,
    refine_iters: int = 4,
    refine_k: int = 25,
    refine_involution: bool = True,
    refine_orientation: float = 300.0,
    polish_k: int = 40,
    polish_iters: int = 3,
    realign_anchors: int = 64,
    realign_iters: int = 3,
    components: Literal["largest", "refuse"] = "largest",
    fill_holes: bool = True,
    generator: torch.Generator | None = None,
) -> IntrinsicSymmetryResult:
    """Find the intrinsically symmetric vertex of every vertex of ``mesh`` (thesis Sec. 6.2).

    1. Validate the mesh and keep its largest component (:func:`validate_mesh`); with
       ``fill_holes``, cover its holes with new triangles (:func:`~torchsym.mesh.repair.close_holes`,
       an extension); scale it to unit area so that every setting below is scale free.
    2. The ``n_eigen`` smallest eigenpairs of the cotangent Laplacian (Sec. 6.2.3).
    3. HKS feature points: local maxima over the 2-ring of the HKS at
       ``t = 4 ln 10 / lambda_2`` (Sec. 6.2.4), the ``max_features`` strongest.
    4. Up to ``max_pairs`` symmetric pairs of feature points by the integer program of
       Eq. 6.1 on HKS (``n_times`` scales) and sign-vector affinities, checked for
       consistency with an isometry (:func:`symmetric_pairs`); with
       ``pairing_hypotheses`` also on HKS alone, and steps 5-7 run for both.
    5. ``C = diag(s)`` from the eigenfunctions' restrictions to geodesics between pairs
       (Sec. 6.2.5) and, with ``cross_pairs``, between two pairs.
    6. With ``correct``, the rotation ``R`` of Eq. 6.4 (``mu``) by the Riemannian trust-region
       method, with the pairs' delta functions as ``F`` and ``G`` (Sec. 6.2.6).
    7. The dense map: nearest neighbour of each row of ``Phi R`` among the rows of
       ``Phi R C`` (Sec. 6.2.7; approximate where step 11's map replaces it, see
       ``map_before_refine``). With ``sign_hypotheses = m > 0`` (an extension) the
       ``2^m`` sign vectors that differ from the thesis's in its ``m`` least-confident
       eigenfunctions are tried first, each scored by how well its point map realises its
       own ``C`` (:func:`map_consistency`, on 800 seeded vertices); one replaces the
       thesis's signs only when it is clearly (``< 0.6x``) more consistent. The search runs
       only when the thesis's map is itself inconsistent; it costs ``2^m`` approximate
       nearest-neighbour queries of 800 points (among ``search_vertices`` vertices on a
       larger mesh).
    8. With ``orientation_hypothesis`` (an extension), a third map from the
       orientation-reversing functional map fitted to the dense HKS
       (:func:`~torchsym.mesh.orientation.orientation_reversing_map`, Ren et al. 2018).
    9. Choice of a hypothesis on ``select_samples`` seeded vertices: each map is refined
       there by ZoomOut and scored by three tests of an isometric involution: the
       defect ``|C^T C - I| + |C C - I|`` of its functional map in ``k`` and in
       ``refine_k`` eigenfunctions, and its geodesic distortion (16 x 400 sampled
       distances). The smallest sum of ranks wins, but a hypothesis other than the
       thesis's must also distort geodesics less than the thesis's map does and less than
       ``max_distortion`` (``max_distortion_open`` on a mesh with boundary): the geodesic
       test is the direct one, while the functional defects also reward other
       near-isometric involutions of nearly ambiguous shapes.
       Maps that leave 60 % of 100 sampled vertices within the correspondence tolerance
       of themselves (partly the identity, before or after refinement) never win.
    10. With ``extrinsic_hypothesis`` (an extension), when the chosen map is weak (its
        functional defect in ``k`` over 0.5, or no hypothesis passed the tests): the map of
        the vertices' best mirror plane (:func:`~torchsym.pointcloud.detect_reflection_plane`
        on ``extrinsic_samples`` vertices; each vertex to the vertex nearest its mirror
        image), refined and tested as in step 9, replaces it when the plane's symmetry
        score is at least ``extrinsic_min_score`` (times one less the share of the area
        that step 1's patches cover: a vertex whose mirror lies in a hole has no partner),
        or when each of the refined map's three tests is at most 0.6 times the weak
        map's (finite) one, and the map passes the tests (no partial
        identity, distortion under ``max_distortion``); the result then holds the
        thesis's pairs (possibly none), the functional map of the plane's point map in
        ``Phi`` and ``R = I``. A surface
        that a reflection maps onto itself has that reflection as an intrinsic symmetry;
        the intrinsic hypotheses fail on shapes with holes, whose eigenfunctions the
        asymmetric holes bend, and there many shapes are still in a near-symmetric pose.
    11. ``refine_iters`` rounds of ZoomOut (Melzi et al. 2019, an extension): the
        functional map of the current point map in a basis growing from ``k`` to
        ``refine_k`` eigenfunctions, averaged with that of its inverse map and made an
        orthogonal involution (``refine_involution``), and the point map it implies. The rounds run on the
        selection's vertex sample and the last one maps every vertex (there, and in the
        maps of every vertex of steps 12-14, by an approximate nearest-neighbour search:
        each image at most 1.5 times as far in the embedding as the nearest row; the
        sample's searches are exact among the vertices they search, see
        ``search_vertices``).
    12. With ``refine_orientation > 0`` (an extension), an orientation test of the final map
        (:func:`~torchsym.mesh.orientation.orientation_reversal` on the vertex sample): a
        reflection reverses the surface's orientation, so a map that reverses it at fewer
        than half of the sampled vertices is refined again by ZoomOut with an orientation
        penalty (Ren et al. 2018: the functional map of an intrinsic reflection
        anticommutes with the orientation operator of every descriptor it preserves, here
        the HKS), from the hypothesis's map with the basis growing and from the refined map
        in ``refine_k`` eigenfunctions, each with the penalty weight ``refine_orientation``
        and a tenth of it. Of the maps that distort geodesics less than the limit of step 9
        (``max_distortion``, or ``max_distortion_open`` with boundary) and leave under
        half of the sampled vertices near themselves (step 9 allows 60 %), the one that
        reverses the orientation at the most vertices (at least 60 %; ties: the later)
        replaces the result. When no hypothesis passed the tests of step 9, the same
        search starts from every hypothesis's own map, and the limit on the distortion is
        1.5 times that of step 9 (the alternative is the thesis's map unrefined; a map
        above step 9's limit is flagged in the notes). Skipped when the faces are not
        consistently wound (:func:`~torchsym.mesh.operators.consistently_wound`) or ``refine_k > 50``.
    13. With ``polish_iters > 0`` and ``polish_k > refine_k`` (an extension), ``polish_iters``
        more rounds of involutive ZoomOut from the final map on the vertex sample, the
        basis growing from ``refine_k`` to ``polish_k`` eigenfunctions, and the last
        round maps every vertex. The polished map is kept unless it reverses the
        orientation at more than 5 points fewer of the sampled vertices than the map it
        came from (on meshes not consistently wound: unless it distorts geodesics more),
        or leaves 60 % of them near themselves. Skipped when step 9 returned the thesis's
        map unrefined.
    14. With ``realign_anchors > 0`` and ``realign_iters > 0`` (an extension), on a map that
        reverses the orientation at fewer than 90 % of the sampled vertices: a spatial
        realignment. ``realign_anchors`` sampled vertices are anchors; an isometric
        involution keeps ``d(T a, T x) = d(a, x)``, so each sampled vertex goes to the
        vertex whose distances to the anchors' images are nearest its own distances to the
        anchors (:func:`_anchor_realignment`, ``realign_iters`` rounds), once with
        edge-graph geodesic distances and once with biharmonic distances (Lipman et al.
        2010) in the final basis. Each result is refined by two rounds of ZoomOut in that
        basis (involutive with ``refine_involution``), searching from the vertex sample. The one that reverses the orientation at the most sampled vertices
        replaces the map when that share is more than 2 points above the map's own and it
        leaves under 60 % of them near themselves. Skipped when step 9 returned the
        thesis's map unrefined, and when the faces are not consistently wound (with a
        note). The final basis is ``polish_k`` eigenfunctions when step 13's map was kept,
        else ``refine_k``.

    Threads: the call holds numpy's BLAS to one thread (``threadpoolctl``, restored on
    return; process-wide, like every BLAS setting) and runs each kd-tree search on every
    core (``workers=-1``): at 12,900 vertices on a 2-core machine that took about 15 %
    less time than two BLAS threads with single-threaded searches (1.30 against 1.52 s).
    Independent branches run on threads (:func:`~torchsym.core.parallel.run_branches`,
    one per core): beside the eigensolver (ARPACK, single-threaded), what needs no
    eigenpair (the edge graph, 2-rings, areas, boundary and winding tests, and step 9's
    vertex sample with the orientation test's frames on it, for each seed that step 9 may
    draw: see below); the orientation hypothesis's map (step 8) with step 9's geodesic probe
    and the sampled searches beside the pairing hypotheses (steps 5-7); the
    hypotheses' refinements of step 9; the trials of step 12 and the geodesic and
    biharmonic realignments of step 14, whose Dijkstra searches hold the GIL while the
    other branch's products run. Each branch touches only its own data, and the choices
    are made afterwards in the fixed order, so the result is the same bits as run one after
    another. Step 9's sample is drawn from the generator after the eigensolver's draw and
    the sign hypotheses' (one per pairing with pairs), so its seed is known only after
    step 4: each possible seed is read ahead from a copy of the generator, and the true
    one's sample is used. In ``benchmarks/bench_mesh.py``, with every map the same, the
    median time per FAUST / TOSCA shape went from 0.73 / 0.89 to 0.52 / 0.65 s (step
    14's, on every 8th shape, from 0.28 to 0.16 s) and the twisted 12,900-vertex
    mannequin-devil's from 1.25 to 0.98 s with the branches of steps 8-14; the branches
    beside the eigensolver, with the sampled searches' choice of brute force
    (:class:`_Nearest`), took it to 0.89 s (0.99 s before, in the same interleaved runs),
    and with ``map_before_refine`` searched when first read and that brute force in
    float32, the latest benchmark run measured 0.78 s, 2.9x the eigendecomposition alone
    (0.26 s), and 0.49 / 0.61 s per FAUST / TOSCA shape.

    Args:
        mesh: the input :class:`Mesh` (any pose, may have holes).
        n_eigen: ``k``, eigenfunctions used (thesis: 13).
        n_times: ``h``, HKS time scales (thesis: 50).
        max_features: most feature points kept, strongest first (thesis: ``d <= 25``).
        feature_radius: feature points closer than this (edge-graph distance on the
            unit-area mesh) to a stronger one are dropped, so that pairs spread over the
            shape instead of crowding on one hand (0 keeps every local maximum).
        max_pairs: ``c``, most sparse pairs.
        max_pair_cost: pairs with a larger affinity cost are not taken.
        penalty: ``q`` of Sec. 6.2.4.
        spectral_weight: weight of the ``phi^2`` term of the affinity (0: HKS only).
        cross_pairs: also read signs from geodesics between two pairs
            (:func:`eigenfunction_signs`).
        sign_hypotheses: least-confident eigenfunctions whose both signs are tried (see
            step 7; 0 is the thesis's rule). On FAUST and TOSCA (every 2nd shape,
            ``benchmarks/bench_mesh.py``) the default 3 raised the correspondence rate from
            93.3 % to 93.7 % and from 87.3 % to 88.6 %.
        pairing_hypotheses: also pair the feature points on HKS alone (``spectral_weight``
            0) as a second hypothesis for step 9 (a pairing without pairs never wins). The
            ``phi^2`` term of the affinity helps on most shapes but misleads where the
            low eigenfunctions are bent out of symmetry: on the benchmark's synthetic bent
            meshes this took the rate from 70.6 % to 75.1 % (FAUST and TOSCA within 0.1
            point; with holes FAUST 46.0 -> 49.3 %, TOSCA 41.1 -> 37.4 %; measured when the
            two were compared by :func:`map_quality` alone). Costs a second run of steps
            4-7, about 0.1 s on 5,000 vertices.
        orientation_hypothesis: add the orientation-reversing functional map as a
            hypothesis (step 8). The thesis's map fails where its few sparse pairs are
            wrong or an eigenspace is nearly repeated; the dense fit has no such single
            point of failure but is less accurate where it succeeds. With the choice of
            step 9, on the benchmark (every 2nd FAUST/TOSCA shape,
            ``benchmarks/bench_mesh.py --step 2``) the rate went from 76.9 % to 91.2 % on
            the synthetic meshes, 91.1 % to 92.1 % on TOSCA, and stayed at 94.9 % on FAUST.
            Costs about 0.05 s at 12,900 vertices.
        extrinsic_hypothesis: try the extrinsic mirror plane when the intrinsic
            hypotheses are weak (step 10). On the benchmark's meshes with 10 % of the area
            punched out (every 4th FAUST / TOSCA shape, ``benchmarks/bench_mesh.py``) the
            rate went from 54.9 to 77.6 % on FAUST and 84.6 to 88.4 % on TOSCA, 72.4 to
            76.6 % on the synthetic meshes; on the closed FAUST and TOSCA shapes it is never
            tried or changes nothing (97.0 / 95.6 %), on the closed synthetic ones 91.5 ->
            91.4 %. It costs nothing where the intrinsic map is strong. The threshold 0.5
            on the defect was the best of 0.3-1.2 over all six sets. A fixed score limit of
            0.7 gained on the holed sets as the scaled 0.75 does but lost on closed FAUST
            (96.7 %); 0.6 lost on both; scaling by twice the patch share lost on holed FAUST.
        extrinsic_min_score: least symmetry score of the plane
            (:attr:`~torchsym.pointcloud.ReflectionPlaneResult.score`) for its map to be used,
            unless the refined map clearly beats the weak intrinsic one on every test (step
            10). A plane that is no extrinsic symmetry of a bent shape can still start
            ZoomOut near the intrinsic one: on the benchmark's holed synthetic camel (plane
            score 0.39) the refined plane map scored 0.65 / 1.03 / 0.049 against the
            thesis's 2.26 / 3.24 / 0.26 and reached 100 % against 3.6 %, and no other of the
            244 benchmark meshes changed (a scratch replay). Two guards come from that
            replay: the weak map must have finite tests (TOSCA's cat6, whose hypotheses all
            failed, is rescued by step 12 at 98.9 %, the plane map would give 84.7 %), and
            every test must be clearly better (the holed TOSCA horse7's plane map scored
            0.78 / 0.59 / 0.58 times the thesis's and fell from 89.7 % to 75.3 %).
        extrinsic_samples: most vertices the plane is fitted to.
        select_samples: vertices on which the hypotheses are refined and compared (step 9);
            raised to ``4 * refine_k`` when smaller, with a note, so that the
            least-squares fits stay determined.
            With 1,000, ZoomOut on the sample matched full ZoomOut to 0.1 point of
            correspondence rate on FAUST, TOSCA and the synthetic meshes.
        search_vertices: on a mesh with more vertices than this, the searches on the vertex
            sample (steps 7 and 9-14) look for images and preimages among this many vertices
            only (at least twice the sample, raised with a note): the sample and vertices
            spread evenly over the surface (:func:`_even_subset`, on a generator of its own),
            as ZoomOut on a vertex subsample does (pyFM's ``subsample``); the maps of every
            vertex still search every vertex. Those searches, of maps still far from exact,
            took most of the time on large meshes: on the benchmark's twisted 12,900-vertex
            mannequin-devil (``benchmarks/bench_mesh.py`` timing rows) the hypothesis
            selection took 0.43-0.45 s against 0.73 s, and the whole solver, with the
            approximate searches of the maps of every vertex, 1.46-1.62 s (three runs;
            1.30 s since BLAS runs on one thread) against 2.33 s. Snapped to the
            subset, the sample's images lie a little off the true ones, so the tests of
            step 9 (tuned on meshes searched whole) can score a map worse: on an exactly
            symmetric 2,562-vertex test shape searched through 1,200 vertices the functional
            defect rose from 0 to 0.15, while the twisted mannequin-devil's was 0.41 against
            0.42. A replay of the benchmark's synthetic meshes above 6,000 vertices, with
            and without holes, gave the same rates to 0.002; FAUST and TOSCA (up to 5,004
            vertices) are untouched. 3,000 was faster but changed the choice of step 9 on
            5,000-vertex shapes (FAUST ``tr_reg_047`` 0.99 -> 0.75, TOSCA cat10 0.98 ->
            0.25, cat9 0.75 -> 0.69, measured while the subset still shared the generator of
            the geodesic probe's vertices).
        max_distortion: largest sampled geodesic distortion (a mean relative error of
            distances) with which a hypothesis may replace the thesis's pairs. True
            symmetries score 0.02-0.05 on FAUST and about 0.1 on TOSCA's cats, whose
            poses are far from isometric; there a wrong orientation-reversing map (front
            legs to hind legs) once scored as well as the true one. Used on closed
            meshes. With the current refinement (involutive ZoomOut), 0.12 against the
            earlier 0.08 took TOSCA's every 2nd shape (``bench_mesh.py --step 2``) from
            93.6 to 94.3 % (dog10: the orientation map, 0.118, replaced the thesis's pairs,
            0.148: rate 0.56 -> 0.82) and left the other half of TOSCA, both halves of
            FAUST and the synthetic meshes unchanged (dropping the limit cost 1.2 points on
            TOSCA's other half). Step 12's search on a mesh where no
            hypothesis passed allows 1.5 times this (``max_distortion_open`` likewise).
        max_distortion_open: the same limit for meshes with boundary edges (holes,
            cut-off parts). A boundary is in general asymmetric and bends the geodesics
            that pass near it, so even the true symmetry distorts the sampled distances
            more. On the benchmark's meshes with 10 % of the area punched out, 0.12
            against 0.08 took the rate from 26.7 to 34.6 % (synthetic), 51.6 to 54.3 %
            (FAUST) and kept TOSCA's 40.8 % (measured before the involutive ZoomOut, when
            0.12 on closed TOSCA shapes still cost 2.4 points, hence two settings).
        correct: run the eigenfunction correction (Sec. 6.2.6).
        min_confidence: eigenfunctions whose sign evidence is weaker than this are left
            out of ``C`` (see :func:`eigenfunction_signs`; 0 is the thesis's rule).
        refine_iters: rounds of ZoomOut after the dense map (an extension; 0 is the thesis's
            method). Each round fits the functional map of the current point map,
            ``C = Phi^T A Phi[T]`` (``A`` the lumped areas; by area-weighted least squares
            on the vertex sample of step 9), in a basis of ``k_r``
            eigenfunctions, ``k_r`` rising evenly from ``n_eigen`` to ``refine_k``, and maps
            each sampled vertex to the nearest row of ``Phi`` to its row of ``Phi C``; the
            last round's ``C`` maps every vertex (step 11). The thesis's
            diagonal ``C`` in 13 eigenfunctions cannot follow shapes that are only nearly
            isometric (on FAUST the true ``C`` has mean ``|C_ii|`` 0.6-0.8); the free ``C``
            in a larger basis can. With the default 4 rounds to 25 eigenfunctions the
            correspondence rate rose from 93.7 % to 94.9 % on FAUST and from 88.6 % to
            90.8 % on TOSCA (every 2nd shape, ``benchmarks/bench_mesh.py``), for
            ``refine_k - n_eigen`` more eigenpairs and a few nearest-neighbour searches.
        refine_k: eigenfunctions of the last ZoomOut round (at least ``n_eigen``; also the
            number of eigenpairs computed in step 2, so it changes the solver's basis
            within repeated eigenvalues too).
        refine_involution: use in each ZoomOut round that the map is its own inverse:
            average the functional maps fitted from the map and from its inverse (as
            bijective ZoomOut does for two shapes, Ren et al. 2021), and replace the
            average by the nearest symmetric orthogonal matrix (:func:`nearest_involution`)
            before mapping: the functional map of an intrinsic reflection is an
            orthogonal involution, and plain ZoomOut, made for maps between two shapes,
            does not know it. Against plain ZoomOut the correspondence rate rose from
            94.9 % to 95.7 % on FAUST, 92.1 % to 93.6 % on TOSCA (mesh rate 92.1 % to
            94.7 %) and 91.2 % to 91.4 % on the synthetic meshes (every 2nd shape,
            ``benchmarks/bench_mesh.py``); with holes 34.5 % to 46.5 % (synthetic),
            54.3 % to 55.4 % (FAUST, 13 shapes) and 40.8 % to 39.6 % (TOSCA, 10 shapes).
            The inverse fit costs one kd-tree over ``Phi C`` per round and refined
            hypothesis: about 20 ms per call on the 12,900-vertex timing mesh (one
            hypothesis refined), up to about 0.1-0.2 s when all three are.
        refine_orientation: weight of the orientation penalty of step 12 (0 skips the test).
            Every test of step 9 is blind to one failure: on FAUST's pose 8 (``tr_reg_018``,
            ``028``, ...) the chosen map turns the torso half a turn about its axis, sending
            the chest to the back. The limbs are thin, so they still land within the
            tolerance and the map scores as a good isometric involution, but it keeps the
            surface's orientation at 65-80 % of the vertices where a reflection reverses
            it. Neither a larger basis (ZoomOut to 100 eigenfunctions: 0.74 -> 0.68 on
            ``tr_reg_018``) nor the orientation penalty in every refinement of step 9 (TOSCA
            95.6 -> 93.4 %: on cats it made wrong maps win the choice) helped; the test
            after the choice did. On the benchmark (``benchmarks/bench_mesh.py``, every
            shape) the correspondence rate rose from 97.0 to 98.5 % on FAUST (mesh rate 94 ->
            100 %: seven shapes from 0.65-0.76 to 0.78-0.99), 95.6 to 96.4 % on TOSCA (mesh
            rate 97.4 -> 98.7 %; david1 0.84 -> 0.93, dog10 0.82 -> 0.92, and cat6 0.54 ->
            0.92, where no hypothesis had passed step 9), with holes 77.6 to 78.4 % (FAUST)
            and 88.4 to 90.3 % (TOSCA, mesh rate 89.5 -> 100 %); the synthetic sets were
            unchanged. The accepting share 0.6, the near-self limit 0.5 and the weights (300
            and 30 against 30 or 300 alone) were chosen on this benchmark: accepting any
            improvement cost a holed dino 0.79 -> 0.72 (0.48 -> 0.51), the near-self limit
            of step 9 (0.6) cost cat9 0.53 -> 0.19. Costs 12 ms per 1,000 sampled vertices,
            and about 0.3 s where the map fails the test (four to eight ZoomOut runs,
            orientation operators in ``refine_k`` eigenfunctions).
        polish_k: eigenfunctions of the last round of step 13 (an extension; at most
            ``refine_k`` skips the step; also raises the eigenpairs computed in step 2).
            Step 9 chooses in ``refine_k``: a larger basis there (``refine_k = 40``) made
            wrong maps win (cat10 0.83 -> 0.32) and the orientation penalty of step 12 grows
            as its fourth power. After the choice the larger basis follows the finer
            non-isometric deformation. With ``polish_k = 40`` in 3 rounds, on the benchmark
            (``benchmarks/bench_mesh.py --faust-tosca``, every shape; its column "without
            polish" runs ``polish_iters = 0`` side by side) the correspondence rate rose from 98.8 to
            99.1 % on FAUST (``tr_reg_054`` 0.97 -> 1.00, ``067`` 0.95 -> 0.99; worst loss
            ``048`` 0.86 -> 0.83), 97.3 to 97.7 % on TOSCA (cat6 0.94 -> 0.99, michael18
            0.94 -> 0.99; dog10 0.94 -> 0.88), 91.6 to 92.1 % on the synthetic meshes, and
            with holes 79.1 to 80.0 % (FAUST), 92.2 to 92.6 % (TOSCA; but michael9 0.78 ->
            0.75, mesh rate 100 -> 95 %) and 77.0 to 77.1 % (synthetic). Without the
            orientation test (replayed on saved maps) FAUST rose only to 98.9 %:
            ``tr_reg_000``, ``005`` and ``065`` lost 4 points each (a hand or an arm to the
            wrong side) while their orientation reversal fell from 77-78 % to 67-69 %; the
            maps that gained fell by at most 0.04. On those maps 6 rounds to 40 gave 97.6 % on
            TOSCA, 5 to 50 97.7 %, 7 to 60 97.6 %. Costs ``polish_k - refine_k`` more
            eigenpairs and three ZoomOut rounds.
        polish_iters: rounds of step 13 (0 skips it).
        realign_anchors: anchors of step 14 (an extension; 0 skips it). ZoomOut fits a
            functional map in 40 eigenfunctions (``polish_k``), which barely vary across a small part
            joined to the body by a narrow neck: on TOSCA's cats the chosen maps sent the
            head onto itself or slid it (cat10 0.85, cat4 0.88, cat5 0.94), and no larger
            basis repaired it (ZoomOut to 100: cat10 0.87). Distances from anchors all over
            the body do reach across the neck. On the benchmark
            (``benchmarks/bench_mesh.py --faust-tosca``, every shape; its column "without
            realign" runs ``realign_anchors = 0`` side by side) the correspondence rate
            rose from 97.7 to 98.2 % on TOSCA (cat10 0.85 -> 0.98, cat4 0.88 -> 0.98,
            cat5 0.94 -> 0.99 by geodesic distances, dog10 0.88 -> 0.99 by biharmonic
            ones; cat3 0.95 -> 0.92), from 99.1 to 99.2 % on FAUST (``tr_reg_017`` 0.94 ->
            0.98) and stayed at 92.1 % on the synthetic meshes; with holes from 92.6 to 93.6
            % on TOSCA (mesh rate 94.7 -> 100 %), 77.1 to 77.6 % on the synthetic meshes, but
            80.0 to 79.4 % on FAUST (``tr_reg_084`` 0.44 -> 0.35). In a scratch replay the
            realignments that spoiled a map (cat6 0.99 -> 0.92, victoria2 0.91 -> 0.84)
            reversed the orientation at no more than 1 point more, hence the 2-point margin.
            Costs 0.5-1 s at 5,000 vertices where it runs (four Dijkstra runs from 64
            sources, two nearest-vertex searches of every vertex in the final basis; the
            median time per TOSCA shape rose from 1.5 to 2.2 s); an exact mirror symmetry
            reverses the orientation everywhere and skips it.
        realign_iters: rounds of the realignment of step 14 (0 skips the step).
        mu: weight of the pairing term of Eq. 6.4. The eigenvalue terms use the
            eigenvalues of the unit-area mesh divided by ``lambda_k``, so that the cost
            does not depend on scale; in these units 0.01 worked best on a development
            split of FAUST/TOSCA (the thesis's ``mu = 1`` is in its meshes' own units).
        max_iter: trust-region iterations per correction.
        components: ``"largest"`` or ``"refuse"`` (see :func:`validate_mesh`).
        fill_holes: solve on the mesh with every boundary loop covered by new triangles
            between its vertices (MeshLab's hole filling; no vertex added or moved, so the
            map is still one of the input's vertices). Holes at asymmetric places bend the
            eigenfunctions and the HKS out of symmetry, and the pairing of Sec. 6.2.4 then
            finds too few pairs. On the benchmark's meshes with 10 % of the area punched
            out in 3 discs (``benchmarks/bench_mesh.py``, every 4th FAUST and TOSCA shape)
            the correspondence rate went from 46.5 to 72.4 % (synthetic, 12 meshes: 7
            better, none worse by more than 5 points), 44.9 to 54.9 % (FAUST, 25: 11
            better, 4 worse, 0.74 -> 0.40 on one) and 59.1 to 84.6 % (TOSCA, 19: 12
            better, none worse), and the median time fell (fewer hypotheses fail their
            tests). Costs 15 to 30 ms at 5,000 to 13,000 vertices; closed meshes are
            untouched. Boundaries whose
            patch would exceed a tenth of the area (the outline of an open surface) stay
            open; a small natural boundary (a scan cut at the neck) is covered, which
            suits a symmetric cut.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        An :class:`IntrinsicSymmetryResult`.

    Raises:
        InputValueError: a broken mesh (see :func:`validate_mesh`) or bad settings.
        InputShapeError: not a mesh, or fewer than ``n_eigen + 1`` vertices.
        SolverError: the eigensolver or the pairing program failed.
    """
    n_eigen = check_int(n_eigen, "n_eigen", minimum=3)
    n_times = check_int(n_times, "n_times", minimum=1)
    max_features = check_int(max_features, "max_features", minimum=2)
    max_pairs = check_int(max_pairs, "max_pairs", minimum=1)
    max_iter = check_int(max_iter, "max_iter", minimum=1)
    refine_iters = check_int(refine_iters, "refine_iters", minimum=0)
    if not isinstance(refine_involution, bool):
        raise InputValueError(f"refine_involution: expected True or False, got {refine_involution!r}")
    refine_k = max(check_int(refine_k, "refine_k", minimum=1), n_eigen) if refine_iters else n_eigen
    sign_hypotheses = check_int(sign_hypotheses, "sign_hypotheses", minimum=0)
    select_samples = check_int(select_samples, "select_samples", minimum=50)
    search_vertices = check_int(search_vertices, "search_vertices", minimum=50)
    max_distortion = check_positive(max_distortion, "max_distortion")
    max_distortion_open = check_positive(max_distortion_open, "max_distortion_open")
    refine_orientation = check_positive(refine_orientation, "refine_orientation", allow_zero=True)
    polish_iters = check_int(polish_iters, "polish_iters", minimum=0)
    polish_k = check_int(polish_k, "polish_k", minimum=1)
    polish = bool(refine_iters) and polish_iters > 0 and polish_k > refine_k
    realign_anchors = check_int(realign_anchors, "realign_anchors", minimum=0)
    realign_iters = check_int(realign_iters, "realign_iters", minimum=0)
    realign = bool(refine_iters) and realign_anchors > 0 and realign_iters > 0
    for flag_name, flag in (
        ("pairing_hypotheses", pairing_hypotheses), ("orientation_hypothesis", orientation_hypothesis), ("fill_holes", fill_holes),
        ("extrinsic_hypothesis", extrinsic_hypothesis),
    ):
        if not isinstance(flag, bool):
            raise InputValueError(f"{flag_name}: expected True or False, got {flag!r}")
    max_pair_cost = check_positive(max_pair_cost, "max_pair_cost")
    extrinsic_min_score = check_in_range(extrinsic_min_score, "extrinsic_min_score", 0.0, 1.0)
    extrinsic_samples = check_int(extrinsic_samples, "extrinsic_samples", minimum=10)
    feature_radius = check_positive(feature_radius, "feature_radius", allow_zero=True)
    penalty = check_positive(penalty, "penalty")
    spectral_weight = check_positive(spectral_weight, "spectral_weight", allow_zero=True)
    min_confidence = check_positive(min_confidence, "min_confidence", allow_zero=True)
    mu = check_positive(mu, "mu", allow_zero=True)
    gen = make_generator(generator)
    timings: dict[str, float] = {}
    notes: list[str] = []
    t_start = tic = time.perf_counter()

    checked = validate_mesh(mesh, components=components, min_vertices=n_eigen + 1)
    if checked.dropped_vertices:
        notes.append(
            f"kept the largest of {checked.num_components} connected components; "
            f"{checked.dropped_vertices} vertices dropped (map = -1 there)"
        )
    v = checked.mesh.vertices.detach().cpu().double().numpy()  # (V', 3)
    f = checked.mesh.faces.detach().cpu().numpy()  # (F', 3)
    holes_closed = 0
    patch_share = 0.0  # share of the (closed) surface's area that the hole patches cover
    if fill_holes:
        n_faces = f.shape[0]
        filling = close_holes(v, f)
        f, holes_closed = filling.faces, filling.holes_closed  # (F'', 3) the input's triangles first
        if holes_closed:
            notes.append(
                f"closed {holes_closed} holes with {f.shape[0] - n_faces} new triangles before computing the "
                "spectrum (fill_holes)"
            )
        notes.extend(f"fill_holes: {note}" for note in filling.notes)
    tri_area = face_areas(v, f)  # (F,)
    if holes_closed:
        patch_share = float(tri_area[n_faces:].sum() / tri_area.sum())
    v = (v - v.mean(axis=0)) / math.sqrt(tri_area.sum())  # unit area
    n = v.shape[0]
    timings["validate"], tic = time.perf_counter() - tic, time.perf_counter()

    if refine_k >= n:
        notes.append(f"refine_k lowered from {refine_k} to {n - 1}, one less than the {n} vertices")
        refine_k = max(n_eigen, n - 1)
    if polish and polish_k >= n:
        notes.append(f"polish_k lowered from {polish_k} to {n - 1}, one less than the {n} vertices")
        polish_k = n - 1
        polish = polish_k > refine_k
    n_big = polish_k if polish else refine_k
    weights = [spectral_weight]
    if pairing_hypotheses and spectral_weight != 0.0:
        weights.append(0.0)
    # step 9's vertex sample, and the vertices its searches run among
    top_k = polish_k if polish else refine_k
    n_rows = min(n, max(select_samples, 4 * top_k))  # the least-squares fits have top_k unknowns per column
    n_targets = max(search_vertices, 2 * n_rows)
    ks = np.linspace(n_eigen, refine_k, refine_iters + 1).round().astype(int)[1:] if refine_iters else np.zeros(0, int)
    schedule = np.linspace(refine_k, polish_k, polish_iters + 1).round().astype(int)[1:] if polish else np.zeros(0, int)

    def draw_sample(seed: int, graph, two_ring, frames) -> tuple:
        # the sample, from the seed of its generator, and the orientation test's frames on it
        tic = time.perf_counter()
        rng = np.random.default_rng(seed)
        rows = np.sort(rng.choice(n, size=n_rows, replace=False))  # (S,)
        targets = None
        if n > search_vertices:
            # a generator of its own, so that the draws below do not depend on search_vertices
            targets = _even_subset(v, rows, n_targets, np.random.default_rng(rng.bit_generator.seed_seq.spawn(1)[0]))
        orient = OrientationTest(v, f, rows, two_ring, frames) if frames is not None else None
        return seed, rng, rows, targets, orient, time.perf_counter() - tic

    # the sample's seed is the generator's draw after the eigensolver's and the sign
    # hypotheses' (one for each pairing with pairs, step 7), so it is known only after step
    # 4. Each possible seed is read from a copy of the generator, and each one's sample
    # drawn on the core that ARPACK (single-threaded) leaves idle; the true seed's is used
    # (the same bits as drawn after step 4). Not the geodesic probe: scipy's Dijkstra holds
    # the GIL, which ARPACK's Python loop needs at every step.
    ahead = torch.Generator(device=gen.device)
    ahead.set_state(gen.get_state())
    guesses = [draw_seed(ahead) for _ in range(2 + (len(weights) if sign_hypotheses else 0))][1:]
    # the same for the sign hypotheses' samples (step 7): pairing i draws the seed after the
    # eigensolver's and the earlier pairings' with pairs
    sign_guesses = guesses[: len(weights)] if sign_hypotheses else []

    def eigen() -> tuple[np.ndarray, np.ndarray, float]:
        tic = time.perf_counter()
        return *laplacian_eigen(v, f, n_big, generator=gen), time.perf_counter() - tic  # (K,), (V', K)

    def topology() -> tuple:
        # what needs no eigenpair, beside the eigensolver
        tic = time.perf_counter()
        graph = edge_graph(v, f)
        two_ring = ring_neighbourhood(f, n, rings=2)  # (V', V'), also step 12's neighbourhoods
        area = mass_matrix(v, f).diagonal()  # (V',)
        has_boundary = bool((edge_face_counts(f)[1] == 1).any())
        wound = bool(refine_iters) and (refine_orientation > 0 or polish or realign) and consistently_wound(f)
        frames = tangent_frames(v, f) if wound else None  # the orientation test's, the same for every sample
        t_topology = time.perf_counter() - tic
        samples = [draw_sample(g, graph, two_ring, frames) for g in guesses]
        sign_samples = {g: _sign_sample(n, np.random.default_rng(g), v, search_vertices) for g in sign_guesses}
        return graph, two_ring, area, has_boundary, wound, frames, t_topology, samples, sign_samples

    (big_evals, big, t_eigen), (graph, two_ring, area, has_boundary, wound, frames, t_topology, samples, sign_samples) = run_branches(
        [eigen, topology]
    )
    evals, evecs = np.maximum(big_evals[:n_eigen], 0.0), big[:, :n_eigen]  # (k,), (V', k)
    if not evals[1] > 1e-9:
        raise InputValueError("mesh: expected a connected surface, got a second Laplacian eigenvalue of 0")
    timings["eigen"], tic = t_eigen, time.perf_counter()

    t_h = 4.0 * math.log(10.0) / evals[1]
    hks_th = heat_kernel_signature(evals, evecs, np.array([t_h]))[:, 0]  # (V',)
    features = hks_feature_points(hks_th, two_ring)  # (d,)
    features = thin_points(graph, features, feature_radius)[:max_features]  # (d,)
    dense_desc = heat_kernel_signature(evals, evecs, hks_times(evals, n_times))  # (V', h)
    desc = dense_desc[features]  # (d, h)
    timings["features"], tic = t_topology + time.perf_counter() - tic, time.perf_counter()

    tic = time.perf_counter()
    feat_dist = geodesic_distances(graph, features)[:, features]  # (d, d)
    pair_sets, pair_notes = [], []
    for weight in weights:
        pairs, _ = symmetric_pairs(
            features, desc, evecs[features], distances=feat_dist, max_pairs=max_pairs, max_cost=max_pair_cost,
            penalty=penalty, spectral_weight=weight,
        )  # (P, 2)
        pair_sets.append(pairs)
        pair_notes.append(
            ["no pair of feature points passed the affinity test: no symmetry found, the map is the identity"] if pairs.shape[0] == 0 else []
        )
    # the generator's draws, in the order of the serial method: each pairing's sign
    # hypotheses (step 7), then step 9's sample; drawn here, the branches below need no generator
    sign_seeds = [draw_seed(gen) if sign_hypotheses and pairs.shape[0] else None for pairs in pair_sets]
    sign_draws = [
        None if seed is None else sign_samples.get(seed) or _sign_sample(n, np.random.default_rng(seed), v, search_vertices)
        for seed in sign_seeds
    ]
    seed = draw_seed(gen)
    for k_ in ("signs", "correction", "map"):
        timings[k_] = 0.0
    timings["pairs"], tic = time.perf_counter() - tic, time.perf_counter()

    if n_rows > select_samples and n > select_samples:
        notes.append(f"select_samples raised from {select_samples} to {n_rows}, 4 x {'polish_k' if polish else 'refine_k'}")
    if n > search_vertices and n_targets > search_vertices:
        notes.append(f"search_vertices raised from {search_vertices} to {n_targets}, twice the vertex sample")
    sample = next((s for s in samples if s[0] == seed), None) or draw_sample(seed, graph, two_ring, frames)
    _, rng, rows, targets, orient, t_sample = sample
    trees = _Searches(big, targets)
    seen: list[np.ndarray] = []
    width = 3 if refine_k > n_eigen else 2
    timings["select"] = t_sample + time.perf_counter() - tic
    candidates: list[_Candidate] = []

    def first_image(cand: _Candidate) -> np.ndarray:
        # the hypothesis's map on the sample
        return trees.to_vertices(_Nearest(trees.sample_points(cand.target)).query(cand.query[rows]))  # (S,)

    def pairings() -> list[np.ndarray]:
        # steps 5-7 for each pairing, and each map on the vertex sample
        for pairs, cand_notes, sign_draw, weight in zip(pair_sets, pair_notes, sign_draws, weights):
            tic = time.perf_counter()
            signs, confidence = eigenfunction_signs(evecs, v, graph, pairs, cross_pairs=cross_pairs, min_confidence=min_confidence)  # (k,)
            signs[0] = 1.0  # the constant eigenfunction is even
            if not pairs.shape[0]:
                signs[:] = 1.0  # no evidence: C = I, whose map is the identity
            timings["signs"], tic = timings["signs"] + time.perf_counter() - tic, time.perf_counter()

            rotation = np.eye(n_eigen)
            converged = True
            fb_sparse = np.concatenate([evecs[pairs[:, 0]], evecs[pairs[:, 1]]], axis=0).T  # (k, 2P)
            gb_sparse = np.concatenate([evecs[pairs[:, 1]], evecs[pairs[:, 0]]], axis=0).T  # (k, 2P)
            if correct and not pairs.shape[0]:
                cand_notes.append("eigenfunction correction skipped: it needs at least one pair")
            if correct and pairs.shape[0]:
                res = correct_eigenfunctions(evals / evals[-1], fb_sparse, gb_sparse, signs, mu=mu, max_iter=max_iter)
                rotation, converged = res.rotation.numpy(), converged and res.converged
            timings["correction"], tic = timings["correction"] + time.perf_counter() - tic, time.perf_counter()

            emb = evecs @ rotation  # (V', k)
            if sign_draw is not None:
                signs, q_thesis, q_chosen = _sign_hypotheses(emb, signs, confidence, sign_hypotheses, 0.6, sign_draw, points=v, max_points=search_vertices)
                if q_chosen < q_thesis:
                    cand_notes.append(f"signs of C changed from the thesis's rule: map consistency {q_thesis:.3f} -> {q_chosen:.3f}")
            use = signs != 0
            # a map without an odd eigenfunction is the identity, which every test scores as perfect
            usable = bool(pairs.shape[0]) and bool((signs < 0).any())
            name = "pairs" if weight == spectral_weight else "hks_pairs"
            candidates.append(
                _Candidate(name, pairs, np.diag(signs), rotation, converged, emb[:, use] * signs[use], emb[:, use], usable, cand_notes)
            )
            timings["map"] += time.perf_counter() - tic
        tic = time.perf_counter()
        images = [first_image(cand) for cand in candidates]
        timings["select"] += time.perf_counter() - tic
        return images

    def orientation_fmap() -> tuple[np.ndarray, float]:
        tic = time.perf_counter()
        return orientation_reversing_map(v, f, evals, evecs, area, dense_desc), time.perf_counter() - tic  # (k, k)

    def probe_and_searches() -> tuple[GeodesicProbe, float]:
        # step 9's geodesic probe (Dijkstra's searches; the probe draws from the sample's
        # generator, which nothing else draws from until step 14), the searches of the
        # sampled rounds (steps 11, 13) and step 13's tree of every vertex, built before the
        # threads share them
        tic = time.perf_counter()
        probe = GeodesicProbe(graph, rows, rng)
        for kk in (*ks, *schedule):
            trees.sample(kk)
        if polish:
            trees.dense(polish_k)
        return probe, time.perf_counter() - tic

    def orientation_branch() -> tuple[_Candidate, float, GeodesicProbe, float, np.ndarray]:
        fmap, t_fmap = orientation_fmap()
        # its pairs (the thesis's, reported with this map) are set once the pairings are done
        cand = _Candidate("orientation", np.zeros((0, 2), np.int64), fmap, np.eye(n_eigen), True, evecs @ fmap.T, evecs, True, [])
        probe, t_probe = probe_and_searches()
        tic = time.perf_counter()
        image = first_image(cand)
        return cand, t_fmap, probe, t_probe + time.perf_counter() - tic, image

    # on two threads, sharing nothing mutable and drawing nothing from the generator: the
    # pairing hypotheses (steps 5-7, mostly Python and small products), and the orientation
    # hypothesis's map (step 8, numpy products) with step 9's probe and the later searches
    if orientation_hypothesis:
        images, (cand, timings["orientation"], probe, t_probe, image) = run_branches([pairings, orientation_branch])
        cand.pairs = candidates[0].pairs
        candidates.append(cand)
        images.append(image)
    else:
        images, (probe, t_probe) = run_branches([pairings, probe_and_searches])
    timings["select"] += t_probe

    # choose a hypothesis on the vertex sample: each one's map, refined by sampled ZoomOut,
    # scored by three tests of an isometric involution
    tic = time.perf_counter()

    def screen(cand: _Candidate, image: np.ndarray | None = None) -> np.ndarray | None:
        # the hypothesis's map on the sample; None when it is not worth refining
        image = first_image(cand) if image is None else image
        duplicate = any(np.array_equal(image, other) for other in seen)
        seen.append(image)
        cand.start = None if duplicate or not cand.usable else image
        if not cand.usable or probe.near_self(image) >= _NEAR_SELF_LIMIT or duplicate:
            return None
        return image

    def refine_score(cand: _Candidate, image: np.ndarray | None) -> np.ndarray:
        if image is None:
            return np.full(width, np.inf)
        refined, fitted = _sampled_zoomout(big, area, rows, image, ks, trees, refine_involution)
        if probe.near_self(refined) >= _NEAR_SELF_LIMIT:
            # ZoomOut drifted to the identity, which every test scores as perfect
            cand.notes.append("ZoomOut refinement drifted towards the identity map; the unrefined map is kept")
            return np.full(width, np.inf)
        cand.refined = fitted
        phi_k = evecs[rows]
        c_k = _fit_functional(phi_k, evecs[refined], area[rows])
        defects = [_involution_defect(c_k)]
        if refine_k > n_eigen:  # else the same defect twice
            defects.append(_involution_defect(_fit_functional(big[rows, :refine_k], big[refined, :refine_k], area[rows])))
        return np.array([*defects, probe.distortion(refined)])

    def score(cand: _Candidate) -> np.ndarray:
        return refine_score(cand, screen(cand))

    # screened in order (a duplicate of an earlier map is skipped), then refined on threads:
    # each refinement touches only its own hypothesis
    screened = [screen(cand, image) for cand, image in zip(candidates, images)]
    scores = run_branches([partial(refine_score, cand, image) for cand, image in zip(candidates, screened)])
    table = np.stack(scores)  # (H, 3), or (H, 2) without refinement
    limit = max_distortion_open if has_boundary else max_distortion
    best = _rank_choice(table, limit)
    timings["select"] += time.perf_counter() - tic
    extrinsic_note = None
    if extrinsic_hypothesis and (not np.isfinite(table[best]).all() or table[best, 0] > _WEAK_DEFECT):
        # the chosen intrinsic map is weak: try the mirror plane of the vertices
        tic = time.perf_counter()
        seed = (gen.initial_seed() + 1) % 2**64  # a seed of its own (initial_seed may be 2^64 - 1)
        cand, plane_score = _extrinsic_candidate(v, evecs, area, candidates[0].pairs, extrinsic_samples, seed)
        row = score(cand)
        logger.debug("extrinsic plane: score %.3f, defects %s", plane_score, np.round(row, 4))
        weak_row = np.array2string(table[best], precision=3)
        # a vertex whose mirror falls in a covered hole has no partner: the attainable score
        # drops by about the patches' share of the area, and so does the limit
        score_limit = extrinsic_min_score * (1.0 - patch_share)
        # a plane that is no extrinsic symmetry can still seed ZoomOut towards the intrinsic
        # one: its refined map is taken when every test clearly beats the weak map's
        passes = bool(np.isfinite(row).all() and row[-1] < limit)
        clearly = bool(np.isfinite(table[best]).all() and (row <= _EXTRINSIC_CLEARLY * table[best]).all())
        if passes and (plane_score >= score_limit or clearly):
            why = "" if plane_score >= score_limit else (
                f", under {score_limit:.2f}, but each test of its refined map ({np.array2string(row, precision=3)}) is "
                f"at most {_EXTRINSIC_CLEARLY:g} times the intrinsic map's"
            )
            extrinsic_note = (
                f"map from the extrinsic reflection plane of the vertices (symmetry score {plane_score:.2f}{why}): "
                f"the intrinsic map was weak (defects {weak_row})"
            )
            candidates.append(cand)
            table = np.vstack([table, row])
            best = len(candidates) - 1
        else:
            notes.append(
                f"the intrinsic map is weak (defects {weak_row}), and the extrinsic reflection plane of the "
                f"vertices did not replace it (symmetry score {plane_score:.2f}, defects "
                f"{np.array2string(row, precision=3)})"
            )
        timings["extrinsic"] = time.perf_counter() - tic
    chosen = candidates[best]
    for cand, row in zip(candidates, table):
        logger.debug("hypothesis %s: defects %s", cand.name, np.round(row, 4))
    notes.extend(chosen.notes)
    if extrinsic_note is not None:
        notes.append(extrinsic_note)
    elif best != 0:
        notes.append(
            f"map from the {_HYPOTHESIS_TEXT[chosen.name]}: ranked first on the tests of an isometric involution "
            f"(defects {np.array2string(table[best], precision=3)} against {np.array2string(table[0], precision=3)} "
            f"for the thesis's pairs)"
        )

    tic = time.perf_counter()
    # the thesis's dense map; when ZoomOut's map replaces it, it is only reported, and an
    # approximate search (images at most 1 + _COARSE_EPS times too far) is enough
    eps = _COARSE_EPS if refine_iters and chosen.refined is not None else 0.0

    def thesis_map() -> tuple[np.ndarray, float]:
        tic = time.perf_counter()
        dense_tree = _kdtree(chosen.target, balanced=False)
        return dense_tree.query(chosen.query, k=1, eps=eps, workers=-1)[1].astype(np.int64), time.perf_counter() - tic  # (V',)

    refined = bool(refine_iters) and chosen.refined is not None
    full = np.zeros((0, 0))
    if refine_iters:
        timings["refine"] = 0.0
    if refined:
        # steps 12-14 read step 11's map of every vertex only on the sample (ZoomOut's start)
        # and its 2-rings (the orientation test): the map there first, and the rest of it
        # only if no later step replaces the map. The thesis's map (only reported) is
        # searched when the result's map_before_refine is first read.
        full = chosen.refined  # (k_r, k_r), fitted on the sample
        read = np.union1d(rows, two_ring[rows].indices)  # (U,)
        rest = np.setdiff1d(np.arange(n), read)
        vmap = np.full(n, -1, dtype=np.int64)
        vmap[read] = trees.map_every_vertex(full, read)
        step11, step11_fmap = vmap, full
        timings["refine"] = time.perf_counter() - tic

    else:
        coarse_map, t_map = thesis_map()
        vmap = coarse_map
        timings["map"] += t_map
    rescued = False

    def reversed_share(vertex_map: np.ndarray) -> float:
        # share of the sampled vertices around which the map reverses the orientation
        return float(np.mean(orient(vertex_map) < 0))

    vmap_share = None  # reversed_share(vmap) once known
    check_orientation = bool(refine_iters) and refine_orientation > 0 and (chosen.refined is not None or chosen.usable)
    if check_orientation and refine_k > _ORIENTATION_MAX_K:
        check_orientation = False
        notes.append(f"orientation check skipped: its dense penalty grows as refine_k^4, and refine_k > {_ORIENTATION_MAX_K}")
    if check_orientation and not wound:
        check_orientation = False
        notes.append("orientation check skipped: the faces are not consistently wound, so the orientation is undefined")
    if check_orientation:
        # step 12: a reflection reverses the surface's orientation
        tic = time.perf_counter()
        share = vmap_share = reversed_share(vmap)
        if chosen.refined is None:  # no hypothesis passed the tests: start from each one's own map
            starts = [(ks, cand.start) for cand in candidates if cand.start is not None]
        elif share < _KEEPS_ORIENTATION:  # the map keeps the orientation on most of the shape
            starts = [
                (ks, chosen.start),  # the hypothesis's own map, the basis growing as in step 11
                (np.full(refine_iters, ks[-1]), trees.nearest(ks[-1], big[rows, : ks[-1]] @ full)),
            ]
        else:
            starts = []
        if starts:
            ops = orientation_operators(v, f, big[:, : ks[-1]], reduce_descriptors(dense_desc, area))  # (r, K, K)
            best_share, found = _REVERSES_ORIENTATION, None
            try:
                fits = _oriented_fits(big, area, rows, ks, ops, tuple(c * refine_orientation for c in _ORIENTATION_SCALES))
            except np.linalg.LinAlgError:
                fits = []
                notes.append("orientation check: the penalised fit is numerically singular; the map is kept")
            bound = limit * _RESCUE_DISTORTION if chosen.refined is None else limit

            def reoriented(oriented: dict, schedule: np.ndarray, start: np.ndarray) -> tuple | None:
                image, fitted = _sampled_zoomout(big, area, rows, start, schedule, trees, refine_involution, oriented)
                distortion = probe.distortion(image) if probe.near_self(image) < _REORIENTED_NEAR_SELF else math.inf
                if not distortion < bound:
                    return None
                trial = trees.map_every_vertex(fitted)
                return trial, fitted, distortion, reversed_share(trial)

            # independent trials, on threads; chosen in the order of the loops
            trials = run_branches([partial(reoriented, o, sc, st) for o in fits for sc, st in starts])
            for trial in trials:
                if trial is not None and trial[3] >= best_share:
                    best_share, found, found_distortion = trial[3], trial[:2], trial[2]
            if found is not None:
                vmap, full = found
                vmap_share = best_share
                rescued = chosen.refined is None
                notes.append(
                    ("no hypothesis passed the tests of an isometric involution; refined" if rescued else
                     f"the map kept the surface's orientation at {1 - share:.0%} of the sampled vertices; refined again")
                    + f" with the orientation penalty, it reverses it at {best_share:.0%}"
                    + (f", but distorts geodesics by {found_distortion:.3f}, above the limit {limit:g}: the map is "
                       "less reliable" if found_distortion >= limit else "")
                )
            elif chosen.refined is not None:
                notes.append(
                    f"the map keeps the surface's orientation at {1 - share:.0%} of the sampled vertices (a "
                    "reflection reverses it); ZoomOut with the orientation penalty found no map that reverses it "
                    f"at {_REVERSES_ORIENTATION:.0%}, the map is unreliable"
                )
        timings["orientation_check"] = time.perf_counter() - tic
    if polish and (chosen.refined is not None or rescued):
        # step 13: ZoomOut on into a larger basis, kept unless it lowers the orientation reversal
        tic = time.perf_counter()
        image, fitted = _sampled_zoomout(big, area, rows, vmap[rows], schedule, trees, refine_involution)
        trial = trees.map_every_vertex(fitted)
        if wound:
            before = reversed_share(vmap) if vmap_share is None else vmap_share  # step 12's figure when it ran
            after = reversed_share(trial)
            keep, test = after >= before - _POLISH_ORIENTATION_DROP, f"orientation reversed at {before:.0%} -> {after:.0%}"
        else:  # orientation undefined: the geodesic test instead
            before, after = probe.distortion(vmap[rows]), probe.distortion(image)
            keep, test = after <= before, f"geodesic distortion {before:.3f} -> {after:.3f}"
        if keep and probe.near_self(image) < _NEAR_SELF_LIMIT:
            vmap, full = trial, fitted
            vmap_share = after if wound else None  # the kept map's share, for step 14
        else:
            notes.append(f"ZoomOut to polish_k = {polish_k} eigenfunctions not kept ({test}); the map in {refine_k} is returned")
        timings["polish"] = time.perf_counter() - tic
    if realign and not wound and full.shape[0] and (chosen.refined is not None or rescued):
        notes.append("realignment (step 14) skipped: the faces are not consistently wound, so the orientation is undefined")
    if realign and wound and full.shape[0] and (chosen.refined is not None or rescued):
        # step 14: realign by distances to anchors, then ZoomOut; kept only if it reverses
        # the orientation at clearly more of the sampled vertices
        tic = time.perf_counter()
        before = reversed_share(vmap) if vmap_share is None else vmap_share  # steps 12 / 13 measured it
        if before < _REALIGN_BELOW:
            kk = int(full.shape[0])
            psi = big[:, 1:kk] / np.maximum(big_evals[1:kk], np.finfo(float).tiny)  # (V', kk-1) biharmonic embedding
            sq_norms = np.einsum("ij,ij->i", psi, psi)  # (V',)

            def biharmonic(sources: np.ndarray) -> np.ndarray:
                sq = sq_norms[sources][:, None] + sq_norms[None, :] - 2.0 * psi[sources] @ psi.T  # (s, V')
                return np.sqrt(np.maximum(sq, 0.0))

            anchors = rng.choice(rows, size=min(realign_anchors, rows.size), replace=False)  # (A,)

            def realigned(distances) -> tuple[np.ndarray, np.ndarray, float] | None:
                start = _anchor_realignment(distances, rows, vmap, anchors, realign_iters)
                image, fitted = _sampled_zoomout(big, area, rows, start, np.array([kk, kk]), trees, refine_involution, brute=True)
                if probe.near_self(image) >= _NEAR_SELF_LIMIT:
                    return None
                trial = trees.map_every_vertex(fitted)
                return trial, fitted, reversed_share(trial)

            # the two branches share nothing mutable (the tree of every vertex is built
            # first); run together, scipy's Dijkstra, which holds the GIL, overlaps the
            # biharmonic branch's products
            trees.dense(kk)
            labels = ("geodesic", "biharmonic")
            branches = run_branches([partial(realigned, lambda src: geodesic_distances(graph, src)), partial(realigned, biharmonic)])
            best_share, found = before + _REALIGN_GAIN, None
            for label, branch in zip(labels, branches):
                if branch is not None and branch[2] > best_share:
                    best_share, found = branch[2], (label, branch[0], branch[1])
            if found is not None:
                label, vmap, full = found
                notes.append(
                    f"realigned by {label} distances to {anchors.size} anchors: the map reverses the orientation "
                    f"at {best_share:.0%} of the sampled vertices, against {before:.0%}"
                )
        timings["realign"] = time.perf_counter() - tic
    if not np.isfinite(table[best]).all() and chosen.usable and not rescued:
        notes.append(
            "no hypothesis passed the tests of an isometric involution (each left most of the shape "
            "in place, or distorted geodesics by more than the limit): the thesis's map is "
            "returned unrefined and is unreliable"
        )
    if refined:
        if vmap is step11:  # no later step replaced step 11's map: the rest of it
            tic = time.perf_counter()
            vmap[rest] = trees.map_every_vertex(step11_fmap, rest)
            timings["refine"] += time.perf_counter() - tic
    pairs, fmap, rotation, converged = chosen.pairs, chosen.fmap, chosen.rotation, chosen.converged
    hypothesis = chosen.name

    timings["total"] = time.perf_counter() - t_start

    to_input = checked.vertex_index.numpy()
    return IntrinsicSymmetryResult(
        map=checked.map_to_input(torch.from_numpy(vmap)),
        functional_map=torch.from_numpy(np.ascontiguousarray(fmap)),
        rotation=torch.from_numpy(rotation),
        map_before_refine=(
            _Deferred(lambda: checked.map_to_input(torch.from_numpy(thesis_map()[0]))) if refined
            else checked.map_to_input(torch.from_numpy(coarse_map))
        ),
        refined_functional_map=torch.from_numpy(np.ascontiguousarray(full)),
        eigenvalues=torch.from_numpy(evals),
        pairs=torch.from_numpy(to_input[pairs]),
        feature_points=torch.from_numpy(to_input[features]),
        timings=timings,
        num_components=checked.num_components,
        dropped_vertices=checked.dropped_vertices,
        correction_converged=bool(converged),
        hypothesis=hypothesis,
        holes_closed=holes_closed,
        notes=tuple(notes),
    )


@register_solver("intrinsic_symmetry", kind="mesh", default=True)
class IntrinsicSymmetry(nn.Module):
    """Intrinsic reflection symmetry of a triangle mesh by functional maps (thesis Ch. 6).

    Module form of :func:`intrinsic_symmetry`; every setting is documented there. Defaults
    are the thesis's values where it gives one (``k = 13``, ``h = 50``, ``d <= 25``, a large
    ``q``) and otherwise values chosen on a development split of FAUST/TOSCA; ``seed``
    seeds the ``torch.Generator`` of the eigensolver's starting vector.

    Example:
        >>> from torchsym.mesh import IntrinsicSymmetry
        >>> solver = IntrinsicSymmetry(n_eigen=13, seed=0)
        >>> result = solver(mesh)  # doctest: +SKIP
        >>> result.map.shape  # doctest: +SKIP
        torch.Size([V])
    """

    def __init__(
        self,
        *,
        n_eigen: int = 13,
        n_times: int = 50,
        max_features: int = 25,
        feature_radius: float = 0.15,
        max_pairs: int = 5,
        max_pair_cost: float = 0.5,
        penalty: float = 1e6,
        spectral_weight: float = 1.0,
        cross_pairs: bool = True,
        min_confidence: float = 0.0,
        sign_hypotheses: int = 3,
        pairing_hypotheses: bool = True,
        orientation_hypothesis: bool = True,
        extrinsic_hypothesis: bool = True,
        extrinsic_min_score: float = 0.75,
        extrinsic_samples: int = 3000,
        select_samples: int = 1000,
        search_vertices: int = 6000,
        max_distortion: float = 0.12,
        max_distortion_open: float = 0.12,
        correct: bool = True,
        mu: float = 0.01,
        max_iter: int = 50,
        refine_iters: int = 4,
        refine_k: int = 25,
        refine_involution: bool = True,
        refine_orientation: float = 300.0,
        polish_k: int = 40,
        polish_iters: int = 3,
        realign_anchors: int = 64,
        realign_iters: int = 3,
        components: str = "largest",
        fill_holes: bool = True,
        seed: int = 0,
    ) -> None:
        super().__init__()
        self.n_eigen = check_int(n_eigen, "n_eigen", minimum=3)
        self.n_times = check_int(n_times, "n_times", minimum=1)
        self.max_features = check_int(max_features, "max_features", minimum=2)
        self.feature_radius = check_positive(feature_radius, "feature_radius", allow_zero=True)
        self.max_pairs = check_int(max_pairs, "max_pairs", minimum=1)
        self.max_pair_cost = check_positive(max_pair_cost, "max_pair_cost")
        self.penalty = check_positive(penalty, "penalty")
        self.spectral_weight = check_positive(spectral_weight, "spectral_weight", allow_zero=True)
        for name, flag in (
            ("cross_pairs", cross_pairs),
            ("correct", correct),
            ("pairing_hypotheses", pairing_hypotheses),
            ("orientation_hypothesis", orientation_hypothesis),
            ("extrinsic_hypothesis", extrinsic_hypothesis),
            ("refine_involution", refine_involution),
            ("fill_holes", fill_holes),
        ):
            if not isinstance(flag, bool):
                raise InputValueError(f"{name}: expected True or False, got {flag!r}")
        self.cross_pairs, self.correct, self.pairing_hypotheses = cross_pairs, correct, pairing_hypotheses
        self.orientation_hypothesis, self.refine_involution = orientation_hypothesis, refine_involution
        self.fill_holes, self.extrinsic_hypothesis = fill_holes, extrinsic_hypothesis
        self.extrinsic_min_score = check_in_range(extrinsic_min_score, "extrinsic_min_score", 0.0, 1.0)
        self.extrinsic_samples = check_int(extrinsic_samples, "extrinsic_samples", minimum=10)
        self.select_samples = check_int(select_samples, "select_samples", minimum=50)
        self.search_vertices = check_int(search_vertices, "search_vertices", minimum=50)
        self.max_distortion = check_positive(max_distortion, "max_distortion")
        self.max_distortion_open = check_positive(max_distortion_open, "max_distortion_open")
        self.min_confidence = check_positive(min_confidence, "min_confidence", allow_zero=True)
        self.mu = check_positive(mu, "mu", allow_zero=True)
        self.max_iter = check_int(max_iter, "max_iter", minimum=1)
        self.refine_iters = check_int(refine_iters, "refine_iters", minimum=0)
        self.refine_k = check_int(refine_k, "refine_k", minimum=1)
        self.refine_orientation = check_positive(refine_orientation, "refine_orientation", allow_zero=True)
        self.polish_k = check_int(polish_k, "polish_k", minimum=1)
        self.polish_iters = check_int(polish_iters, "polish_iters", minimum=0)
        self.realign_anchors = check_int(realign_anchors, "realign_anchors", minimum=0)
        self.realign_iters = check_int(realign_iters, "realign_iters", minimum=0)
        self.sign_hypotheses = check_int(sign_hypotheses, "sign_hypotheses", minimum=0)
        if components not in ("largest", "refuse"):
            raise InputValueError(f"components: expected 'largest' or 'refuse', got {components!r}")
        self.components = components
        self.seed = check_int(seed, "seed")

    def forward(self, mesh: Mesh, generator: torch.Generator | None = None) -> IntrinsicSymmetryResult:
        gen = generator if generator is not None else make_generator(self.seed)
        return intrinsic_symmetry(
            mesh,
            n_eigen=self.n_eigen,
            n_times=self.n_times,
            max_features=self.max_features,
            feature_radius=self.feature_radius,
            max_pairs=self.max_pairs,
            max_pair_cost=self.max_pair_cost,
            penalty=self.penalty,
            spectral_weight=self.spectral_weight,
            cross_pairs=self.cross_pairs,
            min_confidence=self.min_confidence,
            sign_hypotheses=self.sign_hypotheses,
            pairing_hypotheses=self.pairing_hypotheses,
            orientation_hypothesis=self.orientation_hypothesis,
            extrinsic_hypothesis=self.extrinsic_hypothesis,
            extrinsic_min_score=self.extrinsic_min_score,
            extrinsic_samples=self.extrinsic_samples,
            select_samples=self.select_samples,
            search_vertices=self.search_vertices,
            max_distortion=self.max_distortion,
            max_distortion_open=self.max_distortion_open,
            correct=self.correct,
            mu=self.mu,
            max_iter=self.max_iter,
            refine_iters=self.refine_iters,
            refine_k=self.refine_k,
            refine_involution=self.refine_involution,
            refine_orientation=self.refine_orientation,
            polish_k=self.polish_k,
            polish_iters=self.polish_iters,
            realign_anchors=self.realign_anchors,
            realign_iters=self.realign_iters,
            components=self.components,  # type: ignore[arg-type]
            fill_holes=self.fill_holes,
            generator=gen,
        )

    def extra_repr(self) -> str:
        return (
            f"n_eigen={self.n_eigen}, n_times={self.n_times}, max_pairs={self.max_pairs}, "
            f"correct={self.correct}, mu={self.mu}, sign_hypotheses={self.sign_hypotheses}, "
            f"orientation_hypothesis={self.orientation_hypothesis}, "
            f"refine_iters={self.refine_iters}, refine_k={self.refine_k}, polish_k={self.polish_k}, "
            f"polish_iters={self.polish_iters}, realign_anchors={self.realign_anchors}, fill_holes={self.fill_holes}, "
            f"seed={self.seed}"
        )
