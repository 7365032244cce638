"""Meshes with known intrinsic symmetry, for tests and benchmarks (thesis Sec. 6.3).

- :func:`icosphere`: a subdivided icosahedron, whose triangulation is mirror symmetric
  across the three coordinate planes.
- :func:`mirror_complete`: cut a mesh by a plane, keep one side and glue its mirror
  image to it, giving an exactly symmetric mesh and its ground-truth map.
- :func:`twist`: a smooth, nearly isometric twist that breaks the extrinsic symmetry
  and keeps the intrinsic one.
- :func:`punch_holes`: remove geodesic discs of about a given share of the area.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
import torch
from scipy.sparse.csgraph import connected_components

from torchsym.core.random import numpy_rng
from torchsym.errors import InputValueError
from torchsym.mesh.geodesic import geodesic_distances
from torchsym.geometry.mesh import Mesh
from torchsym.mesh.operators import edge_graph, face_areas

__all__ = ["icosphere", "mirror_complete", "punch_holes", "twist"]


def icosphere(subdivisions: int = 3, *, dtype: torch.dtype = torch.float64) -> Mesh:
    """The unit sphere as a subdivided icosahedron: ``10 * 4^s + 2`` vertices."""
    p = (1.0 + math.sqrt(5.0)) / 2.0
    v = np.array(
        [[-1, p, 0], [1, p, 0], [-1, -p, 0], [1, -p, 0], [0, -1, p], [0, 1, p],
         [0, -1, -p], [0, 1, -p], [p, 0, -1], [p, 0, 1], [-p, 0, -1], [-p, 0, 1]], dtype=np.float64
    )
    f = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
         [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5],
         [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], dtype=np.int64
    )
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)  # (3F, 2)
        uniq, inv = np.unique(edges, axis=0, return_inverse=True)
        mid = v[uniq[:, 0]] + v[uniq[:, 1]]  # (E, 3)
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m = inv.reshape(3, -1).T + v.shape[0]  # (F, 3): midpoints of edges 01, 12, 20
        v = np.concatenate([v, mid])
        f = np.concatenate([
            np.stack([f[:, 0], m[:, 0], m[:, 2]], 1), np.stack([f[:, 1], m[:, 1], m[:, 0]], 1),
            np.stack([f[:, 2], m[:, 2], m[:, 1]], 1), m,
        ])
    return Mesh(torch.from_numpy(v).to(dtype), torch.from_numpy(f))


def mirror_complete(mesh: Mesh, normal: np.ndarray | None = None, offset: float | None = None) -> tuple[Mesh, torch.Tensor]:
    """A mesh that is exactly mirror symmetric, made from the part of ``mesh`` on one side of a plane.

    Faces whose centroid lies on the positive side of ``x . normal = offset`` are kept; the
    cut's boundary vertices are moved onto the plane, faces that would then fold onto the
    plane are dropped, and the mirror image is glued along the cut. The result's largest
    connected component is returned.

    Args:
        mesh: any mesh.
        normal: ``(3,)`` plane normal; the x axis by default.
        offset: plane offset; the median ``x . normal`` of the vertices by default.

    Returns:
        The symmetric mesh and ``(V,)`` int64 the mirror vertex of every vertex (vertices on
        the plane map to themselves).
    """
    v = mesh.vertices.detach().cpu().double().numpy()
    f = mesh.faces.detach().cpu().numpy()
    n = np.array([1.0, 0.0, 0.0]) if normal is None else np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    s = v @ n  # (V,)
    o = float(np.median(s)) if offset is None else float(offset)
    s = s - o
    keep = s[f].mean(axis=1) > 0  # (F,)
    nv = v.shape[0]
    orig_boundary = _boundary_keys(f, nv)
    for _ in range(50):
        kf = f[keep]
        cut = np.setdiff1d(_boundary_keys(kf, nv), orig_boundary)  # (C,) edge keys a * V + b
        on_plane = np.zeros(nv, dtype=bool)
        on_plane[cut // nv] = True
        on_plane[cut % nv] = True
        e = np.sort(np.stack([kf[:, [0, 1]], kf[:, [1, 2]], kf[:, [2, 0]]], axis=1), axis=2)  # (F', 3, 2)
        both = on_plane[e[..., 0]] & on_plane[e[..., 1]]  # (F', 3)
        is_cut = np.isin(e[..., 0] * nv + e[..., 1], cut)  # (F', 3)
        # an interior edge between two plane vertices would be shared by four faces once glued
        bad = (both & ~is_cut).any(axis=1) | on_plane[kf].all(axis=1)  # (F',)
        if not bad.any():
            break
        keep[np.flatnonzero(keep)[bad]] = False
    else:
        raise InputValueError("mesh: mirror completion did not find a clean cut; try another plane")
    vv = v.copy()
    vv[on_plane] -= s[on_plane, None] * n  # snap the cut onto the plane
    used = np.unique(f[keep])
    half = np.full(v.shape[0], -1, dtype=np.int64)
    half[used] = np.arange(used.size)
    hv = vv[used]  # (H, 3)
    hf = half[f[keep]]  # (Fh, 3)
    plane = on_plane[used]  # (H,)
    mirror_id = np.arange(used.size) + used.size  # new ids of mirrored copies
    mirror_id[plane] = np.flatnonzero(plane)  # plane vertices are shared
    mv = hv - 2.0 * ((hv - o * n) @ n)[:, None] * n  # (H, 3)
    verts = np.concatenate([hv, mv])
    faces = np.concatenate([hf, mirror_id[hf][:, ::-1]])
    gt = np.concatenate([mirror_id, np.arange(used.size)])  # copy of i maps back to i
    gt[:used.size][plane] = np.flatnonzero(plane)
    # drop triangles flattened by the snapping, then keep the largest component
    dbl = np.linalg.norm(np.cross(verts[faces[:, 1]] - verts[faces[:, 0]], verts[faces[:, 2]] - verts[faces[:, 0]]), axis=1)
    faces = faces[dbl > 1e-10 * dbl.max()]
    return _compact(verts, faces, gt)


def _boundary_keys(f: np.ndarray, nv: int) -> np.ndarray:
    """Edges in exactly one face, as sorted int64 keys ``a * nv + b`` with ``a < b``."""
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    keys, counts = np.unique(e[:, 0] * nv + e[:, 1], return_counts=True)
    return keys[counts == 1]


def _compact(verts: np.ndarray, faces: np.ndarray, gt: np.ndarray) -> tuple[Mesh, torch.Tensor]:
    """Keep the largest face-connected component; re-index vertices and the map (-1 where lost)."""
    nv = verts.shape[0]
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]]])
    g = sp.coo_matrix((np.ones(e.shape[0]), (e[:, 0], e[:, 1])), shape=(nv, nv))
    _, labels = connected_components(g, directed=False)
    in_faces = np.zeros(nv, dtype=bool)
    in_faces[faces.ravel()] = True
    sizes = np.bincount(labels[in_faces], minlength=labels.max() + 1)
    keep_v = in_faces & (labels == int(np.argmax(sizes)))
    new = np.full(nv, -1, dtype=np.int64)
    new[keep_v] = np.arange(int(keep_v.sum()))
    faces = new[faces]
    faces = faces[(faces >= 0).all(axis=1)]
    mapped = gt[keep_v]
    mapped = np.where(mapped >= 0, new[np.maximum(mapped, 0)], -1)
    return Mesh(torch.from_numpy(verts[keep_v]), torch.from_numpy(faces)), torch.from_numpy(mapped)


def twist(mesh: Mesh, angle: float = math.pi / 4, axis: int = 1) -> Mesh:
    """Rotate every vertex about coordinate ``axis`` by an angle growing linearly along it.

    The total twist over the mesh's extent is ``angle``. Horizontal slices move rigidly, so
    the deformation is nearly isometric for moderate angles; it breaks mirror symmetry
    across planes that contain ``axis`` while keeping the intrinsic symmetry.
    """
    v = mesh.vertices.detach().cpu().double().numpy().copy()
    c = v.mean(axis=0)
    h = v[:, axis] - c[axis]
    span = max(float(h.max() - h.min()), np.finfo(float).tiny)
    theta = angle * (h - h.min()) / span - angle / 2  # (V,)
    i, j = [a for a in range(3) if a != axis]
    x, z = v[:, i] - c[i], v[:, j] - c[j]
    v[:, i] = c[i] + np.cos(theta) * x - np.sin(theta) * z
    v[:, j] = c[j] + np.sin(theta) * x + np.cos(theta) * z
    return Mesh(torch.from_numpy(v).to(mesh.vertices.dtype), mesh.faces.clone())


def punch_holes(
    mesh: Mesh,
    symmetric_map: torch.Tensor,
    *,
    area_fraction: float = 0.1,
    n_holes: int = 3,
    generator: torch.Generator | None = None,
) -> tuple[Mesh, torch.Tensor]:
    """Remove ``n_holes`` geodesic discs holding about ``area_fraction`` of the area.

    Args:
        mesh: the mesh.
        symmetric_map: ``(V,)`` its ground-truth symmetric map.
        area_fraction: share of the area to remove, in (0, 0.5).
        n_holes: number of discs (random centres).
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        The largest remaining component and its map (``-1`` where the mirror vertex was
        removed).
    """
    if not 0 < area_fraction < 0.5:
        raise InputValueError(f"area_fraction: expected a number in (0, 0.5), got {area_fraction!r}")
    v = mesh.vertices.detach().cpu().double().numpy()
    f = mesh.faces.detach().cpu().numpy()
    rng = numpy_rng(generator)
    centres = rng.choice(v.shape[0], size=n_holes, replace=False)
    dist = geodesic_distances(edge_graph(v, f), centres).min(axis=0)  # (V,)
    fdist = dist[f].mean(axis=1)  # (F,)
    areas = face_areas(v, f)
    order = np.argsort(fdist)
    cum = np.cumsum(areas[order])
    cut = int(np.searchsorted(cum, area_fraction * cum[-1]))
    keep = np.ones(f.shape[0], dtype=bool)
    keep[order[: cut + 1]] = False
    gt = symmetric_map.detach().cpu().numpy().astype(np.int64)
    return _compact(v, f[keep], gt)
