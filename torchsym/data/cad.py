"""CAD-style meshes made in code: models of several parts with non-manifold edges and
uneven tessellation, the meshes people most often have (ShapeNet, web models), with their
true reflection plane. Used by the front-door tests and ``benchmarks/bench_cad.py``.

A model is boxes: parts across the plane and mirrored pairs of parts; parts that touch
share their vertices (welded, as exporters write them), so an edge where two parts meet
lies in four triangles; the two parts of a mirrored pair may be tessellated differently,
so the vertices are not symmetric where the surface is.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import torch

from torchsym.core.random import numpy_rng
from torchsym.geometry.mesh import Mesh

__all__ = ["CadModel", "box_arrays", "cad_chair", "cad_model"]


@dataclasses.dataclass(frozen=True)
class CadModel:
    """A model and its plane ``normal . x + offset = 0``.

    Attributes:
        mesh: the triangle mesh (float32 vertices).
        normal: ``(3,)`` float64 unit normal of the true plane.
        offset: ``()`` float64.
    """

    mesh: Mesh
    normal: torch.Tensor
    offset: torch.Tensor


def box_arrays(lo: np.ndarray, hi: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed box from ``lo (3,)`` to ``hi (3,)``, each face an ``n x n`` grid of quads of
    two triangles: ``(vertices (6 (n + 1)^2, 3), faces (12 n^2, 3))``, outward winding."""
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


def _assemble(parts: list[tuple[np.ndarray, np.ndarray, int]], rot: np.ndarray, shift: np.ndarray) -> CadModel:
    """Boxes welded where they touch, turned by ``rot`` and moved by ``shift``; the plane
    ``x = 0`` goes with them."""
    verts, faces, count = [], [], 0
    for lo, hi, n in parts:
        v, f = box_arrays(np.minimum(lo, hi), np.maximum(lo, hi), n)
        faces.append(f + count)
        verts.append(v)
        count += len(v)
    v, f = np.concatenate(verts), np.concatenate(faces)
    uniq, inverse = np.unique(np.round(v, 9), axis=0, return_inverse=True)
    f = inverse.reshape(-1)[f]
    normal = rot @ np.array([1.0, 0.0, 0.0])
    mesh = Mesh(torch.from_numpy(uniq @ rot.T + shift).float(), torch.from_numpy(f).long())
    return CadModel(mesh, torch.from_numpy(normal), torch.tensor(-float(normal @ shift), dtype=torch.float64))


def cad_chair(fine_side: int = 6) -> CadModel:
    """A chair: seat, a back welded to it along an edge, four legs and two armrests, the
    left side's parts tessellated ``fine_side x fine_side`` per face, the right side's with
    two triangles a face (687 vertices, 1,356 triangles, one non-manifold edge at the
    default), turned and moved by a fixed motion."""
    parts = [
        (np.array([-0.5, 0.4, -0.5]), np.array([0.5, 0.5, 0.5]), 1),  # seat
        (np.array([-0.5, 0.5, 0.4]), np.array([0.5, 1.5, 0.5]), 1),  # back, welded to the seat along an edge
    ]
    for x in (-1, 1):
        n = fine_side if x < 0 else 1
        for z in (-1, 1):
            parts.append((np.array([x * 0.45 - 0.05, 0.0, z * 0.45 - 0.05]), np.array([x * 0.45 + 0.05, 0.4, z * 0.45 + 0.05]), n))
        parts.append((np.array([x * 0.5 - 0.05, 0.5, -0.4]), np.array([x * 0.5 + 0.05, 0.8, 0.4]), n))
    a, b = math.radians(25), math.radians(-40)
    rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    return _assemble(parts, ry @ rz, np.array([0.3, -0.2, 0.1]))


def cad_model(generator: torch.Generator | int | None = None) -> CadModel:
    """A random model: one to three parts across the plane (the first with a back welded
    along its top rear edge), two to four mirrored pairs of parts whose two sides are
    tessellated with 1 to 8 quads a side independently, a random rigid motion.

    Args:
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.
    """
    rng = numpy_rng(generator if not isinstance(generator, int) else torch.Generator().manual_seed(generator))
    parts = []
    for i in range(rng.integers(1, 4)):  # across x = 0
        half = rng.uniform(0.2, 0.6, 3)
        centre = np.array([0.0, *rng.uniform(-0.6, 0.6, 2)])
        n = int(rng.integers(1, 4))
        parts.append((centre - half, centre + half, n))
        if i == 0:  # the back: its bottom rear edge is the part's top rear edge, in four triangles
            top, rear = centre[1] + half[1], centre[2] + half[2]
            depth, height = rng.uniform(0.05, 0.2), rng.uniform(0.3, 0.8)
            parts.append((np.array([-half[0], top, rear - depth]), np.array([half[0], top + height, rear]), n))
    for _ in range(rng.integers(2, 5)):  # mirrored pairs
        half = rng.uniform(0.03, 0.25, 3)
        centre = np.array([rng.uniform(0.3, 0.9), *rng.uniform(-0.9, 0.9, 2)])
        n_right, n_left = (int(k) for k in rng.integers(1, 9, 2))
        mirror = centre * np.array([-1.0, 1.0, 1.0])
        parts += [(centre - half, centre + half, n_right), (mirror - half, mirror + half, n_left)]
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return _assemble(parts, q * np.sign(np.linalg.det(q)), rng.uniform(-1, 1, 3))
