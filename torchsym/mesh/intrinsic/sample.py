"""Vertex samples of the method: the selection's sample (step 9) and the sign hypotheses' (step 7)."""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from torchsym.mesh.orientation import OrientationTest

__all__ = ["Sample", "draw_sample", "even_subset", "sign_sample"]


@dataclasses.dataclass
class Sample:
    """Step 9's vertex sample, drawn from ``seed``.

    Attributes:
        seed: the seed of ``rng``.
        rng: the sample's generator (the geodesic probe and step 14 draw from it later).
        rows: ``(S,)`` sorted sampled vertices.
        targets: ``(T,)`` sorted vertices the sampled searches look among (None: all).
        orient: the orientation test on ``rows`` (None when the faces are not wound consistently).
        seconds: the time taken.
    """

    seed: int
    rng: np.random.Generator
    rows: np.ndarray
    targets: np.ndarray | None
    orient: OrientationTest | None
    seconds: float


def even_subset(points: np.ndarray, rows: np.ndarray, m: int, rng: np.random.Generator) -> np.ndarray:
    """Sorted vertex indices, at most ``m``: every one of ``rows`` and one random vertex per
    occupied cell of a cubic grid over ``points (V, 3)`` (unit area), the cell side found by
    bisection (more than ``m`` only when ``rows`` alone are)."""
    rows = np.unique(rows)
    if rows.size >= m:
        return rows
    order = rng.permutation(points.shape[0])
    q = points[order] - points.min(axis=0)
    span = float(q.max())
    # a surface of area a holds about a / h^2 cells of side h; the mesh has unit area, and
    # rows fill part of the m
    free = m - rows.size
    lo, hi = max(0.25 / math.sqrt(m), span / 2.0**19), max(4.0 / math.sqrt(free), span / 2.0**19)
    for _ in range(8):
        mid = math.sqrt(lo * hi)
        if _grid_subset(q, order, rows, mid).size > m:
            lo = mid
        else:
            hi = mid
    out = _grid_subset(q, order, rows, hi)
    return out if out.size <= m else rows


def _grid_subset(q: np.ndarray, order: np.ndarray, rows: np.ndarray, h: float) -> np.ndarray:
    """``rows`` and the first vertex of ``order`` in each occupied cell of side ``h`` (``q``: ``(V, 3)`` shifted points in that order)."""
    cells = np.floor(q / h).astype(np.int64)  # (V, 3), each below 2^20
    keys = (cells[:, 0] << 40) | (cells[:, 1] << 20) | cells[:, 2]
    return np.union1d(rows, order[np.unique(keys, return_index=True)[1]])


def sign_sample(
    n: int, rng: np.random.Generator, points: np.ndarray | None, max_points: int
) -> tuple[np.ndarray, np.ndarray | None]:
    """The sign hypotheses' 800 sorted vertices ``(S,)``, and the even subset holding them
    that their images are sought among (None: every vertex)."""
    rows = np.sort(rng.choice(n, size=min(n, 800), replace=False))
    keep = even_subset(points, rows, max_points, rng) if points is not None and n > max_points else None
    return rows, keep


def draw_sample(
    seed: int, v: np.ndarray, f: np.ndarray, n_rows: int, max_search_vertices: int, n_targets: int, two_ring, frames
) -> Sample:
    """Step 9's sample of ``n_rows`` vertices of ``v (V, 3)`` from ``seed``, its search
    targets (``n_targets`` on a mesh over ``max_search_vertices``) and orientation test."""
    tic = time.perf_counter()
    n = v.shape[0]
    rng = np.random.default_rng(seed)
    rows = np.sort(rng.choice(n, size=n_rows, replace=False))  # (S,)
    targets = None
    if n > max_search_vertices:
        # a generator of its own, so that the draws below do not depend on max_search_vertices
        targets = even_subset(v, rows, n_targets, np.random.default_rng(rng.bit_generator.seed_seq.spawn(1)[0]))
    orient = OrientationTest(v, f, rows, two_ring, frames) if frames is not None else None
    return Sample(seed, rng, rows, targets, orient, time.perf_counter() - tic)
