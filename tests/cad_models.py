"""ShapeNet-style CAD meshes built in code, for the front-door tests: several parts, welded
where they touch (so some edges lie in four triangles), flat faces of two triangles next to
finely tessellated ones."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import torch

from torchsym.geometry.mesh import Mesh


def _box(lo, hi, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed box from ``lo`` to ``hi``, each face an ``n x n`` grid of quads (2 triangles each)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    verts, faces = [], []
    for axis, side in itertools.product(range(3), (0, 1)):
        u, v = [a for a in range(3) if a != axis]
        base = len(verts)
        for i, j in itertools.product(range(n + 1), repeat=2):
            p = np.empty(3)
            p[axis] = (lo, hi)[side][axis]
            p[u] = lo[u] + (hi[u] - lo[u]) * i / n
            p[v] = lo[v] + (hi[v] - lo[v]) * j / n
            verts.append(p)
        for i, j in itertools.product(range(n), repeat=2):
            a, b, c, d = (base + (i + di) * (n + 1) + j + dj for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)))
            tri = [[a, b, c], [a, c, d]]
            faces += tri if side else [t[::-1] for t in tri]
    return np.array(verts), np.array(faces)


def cad_chair(fine_side: int = 6) -> tuple[Mesh, torch.Tensor, torch.Tensor]:
    """A chair of seven boxes (seat, back, four legs, a left armrest and its mirror),
    symmetric about a tilted plane; the parts of the left side are tessellated
    ``fine_side x fine_side`` per face, those of the right side with two triangles a face,
    so its vertices crowd one side while its surface does not.

    Returns ``(mesh, normal (3,), offset ())`` of the plane ``normal . x + offset = 0``.
    """
    parts = [
        ((-0.5, 0.4, -0.5), (0.5, 0.5, 0.5), 1),  # seat
        ((-0.5, 0.5, 0.4), (0.5, 1.5, 0.5), 1),  # back, welded to the seat along an edge
    ]
    for x in (-1, 1):  # legs and armrests, the left side finely tessellated
        n = fine_side if x < 0 else 1
        for z in (-1, 1):
            parts.append(((x * 0.45 - 0.05, 0.0, z * 0.45 - 0.05), (x * 0.45 + 0.05, 0.4, z * 0.45 + 0.05), n))
        parts.append(((x * 0.5 - 0.05, 0.5, -0.4), (x * 0.5 + 0.05, 0.8, 0.4), n))
    verts, faces = [], []
    for lo, hi, n in parts:
        lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
        v, f = _box(lo, hi, n)
        faces.append(f + sum(len(q) for q in verts))
        verts.append(v)
    v, f = np.concatenate(verts), np.concatenate(faces)
    # weld coincident vertices, as CAD exporters do where parts touch
    key = np.round(v, 9)
    uniq, inverse = np.unique(key, axis=0, return_inverse=True)
    f = inverse.reshape(-1)[f]
    # a fixed tilt and shift, so the plane is no coordinate plane
    a, b = math.radians(25), math.radians(-40)
    rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    rot, shift = ry @ rz, np.array([0.3, -0.2, 0.1])
    v = uniq @ rot.T + shift
    normal = rot @ np.array([1.0, 0.0, 0.0])
    offset = -float(normal @ shift)
    mesh = Mesh(torch.from_numpy(v).float(), torch.from_numpy(f).long())
    return mesh, torch.from_numpy(normal), torch.tensor(offset, dtype=torch.float64)


def write_obj(path: Path, mesh: Mesh) -> Path:
    """``mesh`` as a Wavefront ``.obj`` (``v`` and 1-based ``f`` lines), as CAD exporters write it."""
    lines = [f"v {x:.7f} {y:.7f} {z:.7f}" for x, y, z in mesh.vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces.tolist()]
    path.write_text("\n".join(lines) + "\n")
    return path
