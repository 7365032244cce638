"""Meshes with known symmetry groups, made in code: boxes, regular prisms, cylinders,
cones, and furniture built from boxes (for tests and ``benchmarks/bench_planes.py``).

Each function returns a :class:`~torchsym.geometry.mesh.Mesh` in float64, centred so that
its symmetry planes pass through the origin when it has any.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch

from torchsym.core.checks import check_int, check_positive
from torchsym.geometry.mesh import Mesh

__all__ = ["box_mesh", "boxes_mesh", "chair_mesh", "cone_mesh", "prism_mesh", "table_mesh"]

# the 12 triangles of a unit cube's faces, counter-clockwise seen from outside
_CUBE_FACES = [
    [0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
    [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7],
]


def box_mesh(size: Sequence[float], center: Sequence[float] = (0.0, 0.0, 0.0)) -> Mesh:
    """The box with edge lengths ``size (3,)`` centred at ``center (3,)`` (12 triangles).
    Three distinct lengths: 3 symmetry planes and three 2-fold axes."""
    s = torch.tensor([check_positive(float(v), "size") for v in size], dtype=torch.float64)
    c = torch.tensor([float(v) for v in center], dtype=torch.float64)
    corners = torch.tensor(
        [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]],
        dtype=torch.float64,
    )
    return Mesh(0.5 * corners * s + c, torch.tensor(_CUBE_FACES, dtype=torch.int64))


def boxes_mesh(boxes: Sequence[tuple[Sequence[float], Sequence[float]]]) -> Mesh:
    """The boxes ``(size, center)`` as one mesh (their surfaces, not a boolean union)."""
    parts = [box_mesh(size, center) for size, center in boxes]
    verts = torch.cat([p.vertices for p in parts])
    faces = torch.cat([p.faces + 8 * i for i, p in enumerate(parts)])
    return Mesh(verts, faces)


def prism_mesh(n: int, radius: float = 1.0, height: float = 1.0) -> Mesh:
    """The regular ``n``-gon prism about the z axis, circumradius ``radius``, capped.
    ``n + 1`` symmetry planes (``n`` through the axis, one across it) when its height is
    not that of a cube (``n = 4``); large ``n`` approximates a cylinder."""
    n = check_int(n, "n", minimum=3)
    r, h = check_positive(radius, "radius"), check_positive(height, "height")
    t = torch.arange(n, dtype=torch.float64) * (2 * math.pi / n)
    ring = torch.stack([r * torch.cos(t), r * torch.sin(t)], 1)  # (n, 2)
    low = torch.cat([ring, torch.full((n, 1), -h / 2, dtype=torch.float64)], 1)
    high = torch.cat([ring, torch.full((n, 1), h / 2, dtype=torch.float64)], 1)
    centres = torch.tensor([[0.0, 0.0, -h / 2], [0.0, 0.0, h / 2]], dtype=torch.float64)
    verts = torch.cat([low, high, centres])  # (2n + 2, 3)
    i = torch.arange(n)
    j = (i + 1) % n
    sides = torch.cat([torch.stack([i, j, n + j], 1), torch.stack([i, n + j, n + i], 1)])
    bottom = torch.stack([torch.full_like(i, 2 * n), j, i], 1)
    top = torch.stack([torch.full_like(i, 2 * n + 1), n + i, n + j], 1)
    return Mesh(verts, torch.cat([sides, bottom, top]))


def cone_mesh(n: int = 256, radius: float = 1.0, height: float = 1.5) -> Mesh:
    """A capped cone (an ``n``-sided pyramid) about the z axis, its apex at ``height / 2``:
    a surface of revolution with no plane across its axis."""
    n = check_int(n, "n", minimum=3)
    r, h = check_positive(radius, "radius"), check_positive(height, "height")
    t = torch.arange(n, dtype=torch.float64) * (2 * math.pi / n)
    base = torch.stack([r * torch.cos(t), r * torch.sin(t), torch.full_like(t, -h / 2)], 1)
    verts = torch.cat([base, torch.tensor([[0.0, 0.0, h / 2], [0.0, 0.0, -h / 2]], dtype=torch.float64)])
    i = torch.arange(n)
    j = (i + 1) % n
    sides = torch.stack([i, j, torch.full_like(i, n)], 1)
    bottom = torch.stack([torch.full_like(i, n + 1), j, i], 1)
    return Mesh(verts, torch.cat([sides, bottom]))


def table_mesh(width: float = 1.2, depth: float = 0.8, height: float = 0.75, leg: float = 0.06) -> Mesh:
    """A table: a top and four legs at its corners. Two symmetry planes (four when
    ``width == depth``), one 2-fold axis (4-fold)."""
    top = 0.04
    boxes = [((width, depth, top), (0.0, 0.0, height - top / 2))]
    for sx in (-1, 1):
        for sy in (-1, 1):
            boxes.append(((leg, leg, height - top), (sx * (width - leg) / 2, sy * (depth - leg) / 2, (height - top) / 2)))
    return boxes_mesh(boxes)


def chair_mesh(width: float = 0.5, depth: float = 0.5, seat: float = 0.45, back: float = 0.5, leg: float = 0.04) -> Mesh:
    """A chair: a seat, four legs and a back. One symmetry plane (``x = 0``)."""
    t = 0.04
    boxes = [((width, depth, t), (0.0, 0.0, seat - t / 2)), ((width, t, back), (0.0, depth / 2 - t / 2, seat + back / 2))]
    for sx in (-1, 1):
        for sy in (-1, 1):
            boxes.append(((leg, leg, seat - t), (sx * (width - leg) / 2, sy * (depth - leg) / 2, (seat - t) / 2)))
    return boxes_mesh(boxes)
