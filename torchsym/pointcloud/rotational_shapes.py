"""Meshes with a known rotation group, made in code: a part set about the z axis ``n``
times (chiral: the part alone; achiral: the part and its mirror image), fans with pitched
blades, gears, bolts and spoked wheels (for tests and ``benchmarks/bench_symmetry_group.py``).

Every function returns a :class:`~torchsym.geometry.mesh.Mesh` in float64 whose axis is
the z axis through the origin.
"""

from __future__ import annotations

import math

import torch

from torchsym.core.checks import check_int
from torchsym.geometry.mesh import Mesh
from torchsym.pointcloud.shapes import box_mesh, prism_mesh

__all__ = ["about_axis", "bolt_mesh", "fan_mesh", "gear_mesh", "merge_meshes", "spoked_wheel_mesh", "turned"]


def _rot_z(angle: float) -> torch.Tensor:
    c, s = math.cos(angle), math.sin(angle)
    return torch.tensor([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], dtype=torch.float64)


def _rot_x(angle: float) -> torch.Tensor:
    c, s = math.cos(angle), math.sin(angle)
    return torch.tensor([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]], dtype=torch.float64)


def merge_meshes(meshes: list[Mesh]) -> Mesh:
    """The meshes as one (their surfaces, not a boolean union)."""
    verts, faces, base = [], [], 0
    for m in meshes:
        verts.append(m.vertices.to(torch.float64))
        faces.append(m.faces + base)
        base += m.vertices.shape[0]
    return Mesh(torch.cat(verts), torch.cat(faces))


def turned(mesh: Mesh, rotation: torch.Tensor, shift: torch.Tensor | None = None) -> Mesh:
    """``mesh`` moved by ``x -> R x + shift``; a reflection (det -1) flips the faces."""
    v = mesh.vertices.to(torch.float64) @ rotation.T
    if shift is not None:
        v = v + shift
    faces = mesh.faces if float(torch.linalg.det(rotation)) > 0 else mesh.faces[:, [0, 2, 1]]
    return Mesh(v, faces)


def about_axis(part: Mesh, n: int, *, mirror: bool = False) -> Mesh:
    """``n`` copies of ``part`` rotated by ``2 pi k / n`` about the z axis (group C_n when
    ``part`` has no symmetry of its own); with ``mirror``, the part and its mirror image in
    the plane y = 0 (group C_nv: ``n`` planes through the axis)."""
    n = check_int(n, "n", minimum=1)
    unit = [part]
    if mirror:
        unit.append(turned(part, torch.diag(torch.tensor([1.0, -1.0, 1.0], dtype=torch.float64))))
    return merge_meshes([turned(u, _rot_z(2.0 * math.pi * k / n)) for k in range(n) for u in unit])


def fan_mesh(n: int, pitch: float = 0.5, hub_sides: int = 48) -> Mesh:
    """A fan: a hub (a ``hub_sides``-gon prism, made a multiple of ``n``) and ``n`` flat
    blades pitched by ``pitch`` radians about their radial line. Group C_n (chiral) when
    ``0 < pitch < pi / 2``; with ``pitch = 0`` the blades lie in a plane: D_nh."""
    n = check_int(n, "n", minimum=2)
    sides = n * max(1, round(hub_sides / n))
    hub = prism_mesh(sides, radius=0.25, height=0.3)
    blade = turned(box_mesh((0.7, 0.3, 0.03)), _rot_x(pitch), torch.tensor([0.6, 0.0, 0.0], dtype=torch.float64))
    return merge_meshes([hub, about_axis(blade, n)])


def gear_mesh(n: int, radius: float = 1.0, tooth: float = 0.15, height: float = 0.3) -> Mesh:
    """A spur gear: a ``2 n``-gon prism whose every other vertex is pushed out by ``tooth``
    (``n`` teeth). Group D_nh: ``n + 1`` planes."""
    n = check_int(n, "n", minimum=2)
    m = prism_mesh(2 * n, radius=radius, height=height)
    v = m.vertices.clone()
    ring = torch.arange(2 * n)
    for base in (0, 2 * n):
        idx = base + ring[::2]
        v[idx, :2] *= (radius + tooth) / radius
    return Mesh(v, m.faces)


def bolt_mesh(sides: int = 6, head: float = 0.5, shaft: float = 1.5) -> Mesh:
    """A bolt: a ``sides``-gon head on a round shaft (a ``8 sides``-gon prism). Group
    C_nv (the head on one end): ``sides`` planes through the axis, no plane across."""
    sides = check_int(sides, "sides", minimum=2)
    head_m = turned(prism_mesh(sides, radius=0.6, height=head), torch.eye(3, dtype=torch.float64),
                    torch.tensor([0.0, 0.0, 0.5 * head], dtype=torch.float64))
    shaft_m = turned(prism_mesh(8 * sides, radius=0.25, height=shaft), torch.eye(3, dtype=torch.float64),
                     torch.tensor([0.0, 0.0, -0.5 * shaft], dtype=torch.float64))
    return merge_meshes([head_m, shaft_m])


def spoked_wheel_mesh(n: int, twist: float = 0.0) -> Mesh:
    """A wheel: a rim (a thin ``8 n``-gon prism shell), a hub and ``n`` spokes; the spokes
    turned by ``twist`` radians about their own line (0: group D_nh; otherwise the spokes
    are chiral propellers: D_n, no plane)."""
    n = check_int(n, "n", minimum=2)
    ring = prism_mesh(8 * n, radius=1.0, height=0.15)
    rim = Mesh(ring.vertices, ring.faces[: 2 * 8 * n])  # the sides only: a band
    hub = prism_mesh(8 * n, radius=0.15, height=0.3)
    spoke = turned(box_mesh((0.85, 0.08, 0.02)), _rot_x(twist), torch.tensor([0.575, 0.0, 0.0], dtype=torch.float64))
    return merge_meshes([rim, hub, about_axis(spoke, n)])
