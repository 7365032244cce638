"""Axes of revolution: lines about which rotation by any angle is a symmetry.

A surface of revolution has a plane through its axis at every angle; it is reported as
the axis instead of a fan of planes. Candidate axes are the lines where two accepted
planes meet and the principal axis whose two other variances are equal; an axis is
accepted when rotations about it by ``n_angles`` generic angles (none a multiple of
``2 pi / k`` for small ``k``) pass the distance test (:mod:`.distance_test`).
Points are normalised; an axis is a unit ``direction (3,)`` and a ``point (3,)`` on it.
"""

from __future__ import annotations

import math

import torch

from torchsym.pointcloud.reflection_planes.distance_test import DistanceTest

__all__ = ["candidate_axes", "contains_axis", "rotation_transforms", "test_axes"]

#: generic angles (radians): 2 pi times multiples of the golden ratio's fractional part,
#: as far from every 2 pi m / k with small k as angles go
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def rotation_transforms(direction: torch.Tensor, point: torch.Tensor, angles: torch.Tensor) -> torch.Tensor:
    """``(A, 4, 4)`` rotations by ``angles (A,)`` about the line through ``point (3,)``
    along the unit ``direction (3,)`` (Rodrigues)."""
    d = direction / direction.norm()
    kx = torch.zeros(3, 3, dtype=d.dtype, device=d.device)
    kx[0, 1], kx[0, 2], kx[1, 0], kx[1, 2], kx[2, 0], kx[2, 1] = -d[2], d[1], d[2], -d[0], -d[1], d[0]
    s, c = torch.sin(angles)[:, None, None], torch.cos(angles)[:, None, None]
    rot = torch.eye(3, dtype=d.dtype, device=d.device) + s * kx + (1.0 - c) * (kx @ kx)  # (A, 3, 3)
    out = torch.zeros(angles.shape[0], 4, 4, dtype=d.dtype, device=d.device)
    out[:, :3, :3] = rot
    out[:, :3, 3] = point - rot @ point
    out[:, 3, 3] = 1.0
    return out


def _line_point(n1, b1, n2, b2, near: torch.Tensor) -> torch.Tensor:
    """The point of the line where two planes meet nearest to ``near (3,)``."""
    a = torch.stack([n1, n2])  # (2, 3)
    rhs = torch.stack([-b1, -b2]) - a @ near
    return near + a.T @ torch.linalg.solve(a @ a.T, rhs)


def candidate_axes(
    normals: torch.Tensor, offsets: torch.Tensor, centered: torch.Tensor, centre: torch.Tensor, eigen_gap: float,
    max_planes: int = 8,
) -> list[tuple[torch.Tensor, torch.Tensor]]:
    """Candidate axes ``(direction, point)``: the principal axis of ``centered (M, 3)``
    (about ``centre (3,)``) whose other two variances differ by less than ``eigen_gap``
    (relative), and where each pair of the first ``max_planes`` planes meets (when they
    are at least 5 degrees apart)."""
    out = []
    lam, vec = torch.linalg.eigh(centered.T @ centered)  # ascending
    for k, (i, j) in enumerate([(1, 2), (0, 2), (0, 1)]):
        if float(lam[j] - lam[i]) <= eigen_gap * float(lam[j]):
            out.append((vec[:, k], centre))
    k = min(normals.shape[0], max_planes)
    for i in range(k):
        for j in range(i + 1, k):
            d = torch.linalg.cross(normals[i], normals[j])
            if float(d.norm()) > math.sin(math.radians(5.0)):
                out.append((d / d.norm(), _line_point(normals[i], offsets[i], normals[j], offsets[j], centre)))
    return out


def contains_axis(normal: torch.Tensor, offset: torch.Tensor, direction: torch.Tensor, point: torch.Tensor, tol: float) -> bool:
    """Whether the plane contains the axis: the axis lies within ``tol`` of the plane
    over a unit length either side of ``point``."""
    ends = torch.stack([point - direction, point + direction])
    return bool(((ends @ normal + offset).abs() <= tol).all())


def test_axes(
    axes: list[tuple[torch.Tensor, torch.Tensor]], test: DistanceTest, n_angles: int, max_ratio: float, merge_tol: float,
    max_far_share: float = 0.04,
    far_floor: float = 0.0,
) -> list[tuple[torch.Tensor, torch.Tensor, float]]:
    """The distinct axes among ``axes`` whose rotations by ``n_angles`` generic angles all
    pass ``test`` (the worst ratio at most ``max_ratio``, and at most ``max_far_share``
    more of the points moved farther than 3 sampling distances than ``far_floor``, the
    accepted planes' least share (holes move points far under every symmetry),
    :meth:`~.distance_test.DistanceTest.far_shares`; 0.04: a cylinder with three 2 %
    holes reads 0.05 against its planes' 0.017, a filled cube 0.08, a hexagonal bolt
    0.14): ``(direction, point, ratio)``,
    best first. Two axes are one when within ``merge_tol`` of each other (ends of a unit
    segment, either orientation)."""
    angles = torch.tensor([2.0 * math.pi * ((1 + k) * _GOLDEN % 1.0) for k in range(n_angles)], dtype=torch.float64)
    scored = []
    for d, p in axes:
        ts = rotation_transforms(d, p, angles.to(d))
        worst = float(test.ratios(ts, bound=max_ratio).max())
        if worst <= max_ratio and float(test.far_shares(ts).max()) <= far_floor + max_far_share:
            scored.append((d, p, worst))
    found: list[tuple[torch.Tensor, torch.Tensor, float]] = []
    for d, p, worst in sorted(scored, key=lambda f: f[2]):  # the best of each group of near-copies
        if not any(_same_axis(d, p, f[0], f[1], merge_tol) for f in found):
            found.append((d, p, worst))
    return found


def _same_axis(d1, p1, d2, p2, tol: float) -> bool:
    """Whether two axes nearly coincide: within 5 degrees, and each end of ``p1 +- d1``
    within ``tol`` of the other line."""
    if float((d1 @ d2).abs()) < math.cos(math.radians(5.0)):
        return False
    ends = torch.stack([p1 - d1, p1 + d1]) - p2
    off = ends - (ends @ d2)[:, None] * d2
    return bool((off.norm(dim=1) <= tol).all())
