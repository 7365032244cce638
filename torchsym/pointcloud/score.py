"""The detector's score: the plane's mirror share above what a random plane gets on the same cloud.

A dense cloud meets any absolute inlier tolerance under many planes (a volume reflected
into itself lands near some point), so the raw inlier share does not separate symmetric
from asymmetric clouds. The score corrects it for chance (see ``docs/design/reflection_plane.md``).
Points are normalised to a unit bounding-box diagonal.
"""

from __future__ import annotations

import torch

from torchsym.core.random import random_subset
from torchsym.geometry.reflection import reflect_points
from torchsym.geometry.sampling import sphere_normals
from torchsym.matching.knn import KNNIndex

__all__ = ["chance_corrected_score", "chance_share", "corrected_share", "mirror_share"]


def mirror_share(points: torch.Tensor, dist: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor, tol: float) -> float:
    """Share of the points farther than ``tol`` from the plane whose mirror residual
    ``dist (N,)`` is at most ``tol``: points on the plane are their own mirrors and say
    nothing about it (0 when every point is on the plane)."""
    off_plane = (points @ normal + offset).abs() > tol  # (N,)
    count = int(off_plane.sum())
    return float((dist[off_plane] <= tol).double().sum()) / count if count else 0.0


def chance_corrected_score(
    points: torch.Tensor,
    index: KNNIndex,
    dist: torch.Tensor,
    normal: torch.Tensor,
    offset: torch.Tensor,
    tol: float,
    generator: torch.Generator,
    *,
    n_planes: int = 64,
    n_probe: int = 300,
) -> float:
    """``(s - s0) / (1 - s0)`` clamped to [0, 1]: ``s`` the :func:`mirror_share` of the
    plane, ``s0`` the highest share among ``n_planes`` random planes (normals on a randomly
    rotated Fibonacci half sphere, each through the median of the points' projections),
    measured on ``n_probe`` random points of ``points (N, 3)`` (``index`` over them): the
    detected plane is the best of many, so it is compared with the best of many by chance.

    A plane that mirrors the cloud no better than a random one scores 0; a cloud
    symmetric about every plane through its centre (a ball) scores low, since no plane
    stands out.
    """
    s = mirror_share(points, dist, normal, offset, tol)
    if n_planes == 0:
        return s
    return corrected_share(s, chance_share(points, index, tol, generator, n_planes=n_planes, n_probe=n_probe))


def chance_share(
    points: torch.Tensor, index: KNNIndex, tol: float, generator: torch.Generator, *, n_planes: int = 64, n_probe: int = 300
) -> float:
    """The highest :func:`mirror_share` among ``n_planes`` random planes (normals on a
    randomly rotated Fibonacci half sphere, each through the median of the points'
    projections), measured on ``n_probe`` random points of ``points (N, 3)`` (``index``
    over them): the chance level of :func:`chance_corrected_score`."""
    probe = points[random_subset(points.shape[0], n_probe, generator)]  # (P, 3)
    q, _ = torch.linalg.qr(torch.randn(3, 3, generator=generator, dtype=torch.float64))
    normals = sphere_normals(n_planes, dtype=torch.float64).to(points) @ q.to(points).T  # (K, 3)
    offsets = -(probe @ normals.T).median(0).values  # (K,)
    moved = reflect_points(probe.expand(n_planes, -1, -1), normals, offsets)  # (K, P, 3)
    # only "within tol" matters: a bounded search skips the far queries, the slow ones
    d, _ = index.query(moved.reshape(-1, 3), max_distance=2.0 * tol)
    d = d.reshape(n_planes, -1)  # (K, P)
    off_plane = (probe @ normals.T + offsets).abs().T > tol  # (K, P)
    counts = off_plane.sum(1).clamp_min(1)
    return float(((d <= tol) & off_plane).sum(1).div(counts).max())


def corrected_share(s: float, s0: float) -> float:
    """``(s - s0) / (1 - s0)`` clamped to [0, 1] (0 when ``s0 >= 1``): a mirror share
    ``s`` above the chance level ``s0``."""
    if s0 >= 1.0:
        return 0.0
    return float(min(max((s - s0) / (1.0 - s0), 0.0), 1.0))
