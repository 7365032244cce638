"""Intrinsic-symmetry evaluation of Sec. 6.3.2 (after Kim et al. 2010).

A predicted correspondence ``x -> y`` is correct when the geodesic distance from ``y`` to
the ground-truth symmetric vertex of ``x`` is below ``sqrt(area / (20 pi))``. The
correspondence rate of a mesh is the share of correct correspondences among the
evaluated ones; the mesh rate of a data set is the share of meshes whose rate exceeds
75 %. Geodesic distances are measured on the surface (``geodesics="surface"``, default):
the shortest edge path (Dijkstra), straightened into a geodesic across the faces by
potpourri3d's FlipOut wherever the edge path alone is not short enough to count as
correct. ``geodesics="edges"`` keeps the edge-path lengths, which over-estimate the
surface distance (by a median 7.4 % near the tolerance, up to 77 %) and so give lower,
conservative rates.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch

from torchsym.core.random import make_generator
from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError
from torchsym.mesh.geodesic import geodesic_distances, surface_geodesic_lengths
from torchsym.geometry.mesh import Mesh
from torchsym.mesh.operators import edge_graph, face_areas, mass_matrix

__all__ = ["CorrespondenceScore", "correspondence_rate", "extremity_vertices", "mesh_rate", "symmetry_threshold"]


def _np(x: Any, dtype: Any) -> np.ndarray:
    if isinstance(x, torch.Tensor):
        x = x.detach().cpu().numpy()
    return np.asarray(x, dtype=dtype)


def symmetry_threshold(mesh: Mesh) -> float:
    """``sqrt(area / (20 pi))``, the geodesic tolerance of a correct correspondence."""
    v = _np(mesh.vertices, np.float64)
    f = _np(mesh.faces, np.int64)
    return math.sqrt(float(face_areas(v, f).sum()) / (20.0 * math.pi))


@dataclasses.dataclass(frozen=True)
class CorrespondenceScore(Result):
    """Correspondence rate of one mesh (Sec. 6.3.2).

    Attributes:
        rate: share of evaluated correspondences that are correct, in [0, 1].
        num_evaluated: correspondences evaluated (those with a ground truth and a prediction).
        threshold: the geodesic tolerance used.
        errors: ``(num_evaluated,)`` geodesic distance from each prediction to its ground
            truth, ``inf`` beyond ``2 * threshold`` (not searched further). With
            ``geodesics="surface"`` the errors from ``threshold`` up are surface geodesic
            lengths and those below it edge-path lengths (an upper bound, already small
            enough to count as correct).
        geodesics: how distances were measured, ``"surface"`` or ``"edges"``.
    """

    rate: float
    num_evaluated: int
    threshold: float
    errors: torch.Tensor
    geodesics: str = "surface"


_GEODESICS = ("surface", "edges")


def correspondence_rate(
    mesh: Mesh,
    predicted: Any,
    *,
    ground_truth: Any | None = None,
    landmarks: Any | None = None,
    threshold: float | None = None,
    geodesics: str = "surface",
) -> CorrespondenceScore:
    """Correspondence rate of a predicted symmetric map on one mesh (Sec. 6.3.2).

    Give the ground truth either densely or as landmark pairs:

    - ``ground_truth (V,)``: symmetric vertex of every vertex, ``-1`` where unknown;
    - ``landmarks (L, 2)``: rows ``(x, y)`` meaning ``y`` is the symmetric vertex of ``x``.

    Args:
        mesh: the mesh the map lives on.
        predicted: ``(V,)`` int predicted symmetric vertex of every vertex (``-1``: none,
            counted as wrong when a ground truth exists).
        ground_truth: dense ground-truth map.
        landmarks: ground-truth landmark pairs.
        threshold: geodesic tolerance; ``sqrt(area / (20 pi))`` when None.
        geodesics: ``"surface"`` (default): geodesic distance on the surface, as Sec. 6.3.2
            and Kim et al. 2010 define the error; each edge-graph distance at or above the
            tolerance (and below twice it) is replaced by the length of the FlipOut geodesic
            between the same vertices (:func:`~torchsym.mesh.geodesic.surface_geodesic_lengths`),
            which is never longer, so the rate equals that of straightening every path.
            ``"edges"``: edge-graph distances only (Dijkstra), faster and stricter.

    Returns:
        A :class:`CorrespondenceScore`.
    """
    if geodesics not in _GEODESICS:
        raise InputValueError(f"geodesics: expected one of {', '.join(map(repr, _GEODESICS))}, got {geodesics!r}")
    n = mesh.num_vertices
    pred = _np(predicted, np.int64).ravel()
    if pred.shape[0] != n:
        raise InputShapeError(f"predicted: expected ({n},) to match the mesh's vertices, got {pred.shape}")
    if (ground_truth is None) == (landmarks is None):
        raise InputShapeError("ground_truth, landmarks: expected exactly one of them, got "
                              f"{'both' if ground_truth is not None else 'neither'}")
    if ground_truth is not None:
        gt = _np(ground_truth, np.int64).ravel()
        if gt.shape[0] != n:
            raise InputShapeError(f"ground_truth: expected ({n},) to match the mesh's vertices, got {gt.shape}")
        src = np.flatnonzero(gt >= 0)
        dst = gt[src]
    else:
        lm = _np(landmarks, np.int64)
        if lm.ndim != 2 or lm.shape[1] != 2:
            raise InputShapeError(f"landmarks: expected (L, 2) vertex pairs, got {lm.shape}")
        src, dst = lm[:, 0], lm[:, 1]
    if src.size and (src.max() >= n or dst.max() >= n or src.min() < 0 or dst.min() < 0):
        raise InputShapeError(f"ground truth: expected vertex indices in [0, {n - 1}]")
    thr = symmetry_threshold(mesh) if threshold is None else float(threshold)
    v = _np(mesh.vertices, np.float64)
    f = _np(mesh.faces, np.int64)
    graph = edge_graph(v, f)
    guess = pred[src]  # (L,)
    errors = np.full(src.shape[0], np.inf)  # (L,)
    have = np.flatnonzero(guess >= 0)
    if have.size:
        starts, inv = np.unique(guess[have], return_inverse=True)
        dist = geodesic_distances(graph, starts, limit=2.0 * thr)  # (S, V)
        errors[have] = dist[inv, dst[have]]
    if geodesics == "surface":
        near = np.flatnonzero((errors >= thr) & np.isfinite(errors))  # only these can change the rate
        if near.size:
            pairs = np.stack([guess[near], dst[near]], axis=1)  # (P, 2)
            errors[near] = np.minimum(errors[near], surface_geodesic_lengths(v, f, pairs))
    rate = float((errors < thr).mean()) if errors.size else float("nan")
    return CorrespondenceScore(
        rate=rate, num_evaluated=int(errors.size), threshold=thr, errors=torch.from_numpy(errors), geodesics=geodesics
    )


def mesh_rate(rates: Sequence[float], *, minimum: float = 0.75) -> float:
    """Share of meshes whose correspondence rate exceeds ``minimum`` (75 % in Sec. 6.3.2)."""
    r = np.asarray(list(rates), dtype=np.float64)
    if r.size == 0:
        return float("nan")
    return float((r > minimum).mean())


def extremity_vertices(
    mesh: Mesh,
    *,
    share: float = 0.05,
    candidates: Any | None = None,
    n_sources: int = 128,
    generator: torch.Generator | None = None,
) -> torch.Tensor:
    """The vertices farthest, on average, from the rest of the surface: limb, head and tail ends.

    Each vertex's mean geodesic distance (edge paths) to the surface is estimated from
    ``n_sources`` farthest-point source vertices, each weighted by the area of its geodesic
    Voronoi cell; the top ``share`` of ``candidates`` by that distance is returned. Scoring a
    symmetric map on these vertices (``correspondence_rate(..., landmarks=...)``) judges
    it where intrinsic symmetry maps go wrong (hands, feet, ears, tails) rather than on
    the torso, which any orientation-reversing map gets right.

    Args:
        mesh: the mesh (one connected component is expected; unreachable vertices count as far).
        share: fraction of the candidates returned, in (0, 1]; default 5 %.
        candidates: ``(C,)`` vertex indices to choose among (e.g. those with a ground
            truth), or a ``(V,)`` bool mask; None: every vertex.
        n_sources: geodesic sources of the estimate.
        generator: draws the first source; None seeds one with 0.

    Returns:
        ``(M,)`` int64 vertex indices, ``M = max(1, round(share * C))``, farthest first.

    Raises:
        InputValueError: ``share`` outside (0, 1] or ``n_sources < 1``.
        InputShapeError: ``candidates`` out of range.
    """
    if not 0.0 < share <= 1.0:
        raise InputValueError(f"share: expected a fraction in (0, 1], got {share}")
    if n_sources < 1:
        raise InputValueError(f"n_sources: expected at least 1, got {n_sources}")
    v = _np(mesh.vertices, np.float64)
    f = _np(mesh.faces, np.int64)
    n = v.shape[0]
    if candidates is None:
        cand = np.arange(n)
    else:
        cand = candidates.detach().cpu().numpy() if isinstance(candidates, torch.Tensor) else np.asarray(candidates)
        cand = cand.ravel() if cand.dtype == bool else cand.ravel().astype(np.int64)
        if cand.dtype == bool:
            if cand.shape[0] != n:
                raise InputShapeError(f"candidates: expected a ({n},) mask, got {cand.shape}")
            cand = np.flatnonzero(cand)
        elif cand.size and (cand.min() < 0 or cand.max() >= n):
            raise InputShapeError(f"candidates: expected vertex indices in [0, {n - 1}]")
    gen = generator if generator is not None else make_generator(0)
    area = mass_matrix(v, f).diagonal()  # (V,)
    graph = edge_graph(v, f)
    source = int(torch.randint(n, (1,), generator=gen))
    rows = []
    nearest = np.full(n, np.inf)
    for _ in range(min(n_sources, n)):  # farthest-point sources, spread evenly over the surface
        row = geodesic_distances(graph, np.array([source]))[0]  # (V,)
        rows.append(row)
        nearest = np.minimum(nearest, row)
        finite = np.where(np.isfinite(nearest), nearest, -1.0)
        source = int(np.argmax(finite))
        if finite[source] <= 0.0:
            break
    dist = np.stack(rows)  # (S, V)
    dist[~np.isfinite(dist)] = 2.0 * dist[np.isfinite(dist)].max()
    cell = np.bincount(np.argmin(dist, axis=0), weights=area, minlength=dist.shape[0])  # (S,) Voronoi cell areas
    mean = (cell @ dist / cell.sum())[cand]  # (C,) area-weighted mean distance
    m = max(1, int(round(share * cand.size)))
    order = np.argsort(-mean, kind="stable")[:m]
    return torch.from_numpy(cand[order].astype(np.int64))
