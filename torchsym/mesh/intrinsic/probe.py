"""Sampled geodesic tests of a self map: distortion and how much of the shape it leaves in place."""

from __future__ import annotations

import math

import numpy as np

from torchsym.mesh.geodesic import geodesic_distances

__all__ = ["GeodesicProbe", "map_score", "reflection_score"]


class GeodesicProbe:
    """Sampled geodesic tests of a self map on the unit-area mesh (Dijkstra on the edge graph).

    :meth:`distortion`: ``mean |d(x, y) - d(T x, T y)| / mean d(x, y)`` over ``n_sources``
    x ``n_targets`` vertices drawn from ``rows (S,)``; 0 for an isometry.
    :meth:`near_self`: the share of ``n_balls`` vertices of ``rows`` that the map leaves
    within ``radius`` of themselves (the correspondence tolerance of Sec. 6.3.2,
    ``sqrt(1 / (20 pi))`` on a unit-area mesh).
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


def reflection_score(distortion: float, reversed_share: float, scale: float) -> float:
    """How well a map passes as an intrinsic reflection, in [0, 1]: ``(1 - distortion / scale)_+``
    times the share of sampled vertices around which it reverses the orientation."""
    return float(min(1.0, max(0.0, 1.0 - distortion / scale) * reversed_share))


def map_score(ws, vertex_map: np.ndarray) -> float:
    """The score in [0, 1] of a map ``(V,)`` (-1 allowed off the sample's 2-rings) on the workspace ``ws``
    of :func:`~torchsym.mesh.intrinsic.intrinsic_symmetry`: ``(1 - d / select.score_distortion)_+``
    times the share of sampled vertices around which it reverses the orientation (an intrinsic
    reflection reverses it everywhere), or, faces not consistently wound, one less the share it
    leaves within the correspondence tolerance of themselves; ``d`` its sampled geodesic distortion."""
    image = vertex_map[ws.rows]
    if (image < 0).any():
        return 0.0
    agree = ws.reversed_share(vertex_map) if ws.orient is not None else 1.0 - ws.probe.near_self(image)
    return reflection_score(ws.probe.distortion(image), agree, ws.settings.select.score_distortion)
