"""Closing the holes of a triangle mesh before its spectrum is computed.

The thesis shows its intrinsic symmetry surviving holes that remove a tenth of the area
(Sec. 6.3, Fig. 6.11). The Laplace-Beltrami eigenfunctions and the heat kernel signature
of a mesh with holes change near every boundary (the cotangent Laplacian puts a Neumann
condition there), and holes at asymmetric places make them asymmetric; on the
benchmark's meshes with 10 % of the area punched out, too few feature points keep a
mirror partner for the pairing of Sec. 6.2.4. Covering each hole with a patch of new
triangles that joins its boundary vertices (no vertex is added or moved) brings the
spectrum back close to that of the whole shape, and the symmetric map of the patched
mesh is a map of the input's vertices. MeshLab's hole filling (through pymeshlab, a
dependency already) does the triangulation.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from torchsym.mesh.operators import edge_face_counts, face_areas

__all__ = ["HoleFilling", "boundary_loops", "close_holes"]


@dataclasses.dataclass(frozen=True)
class HoleFilling:
    """What :func:`close_holes` did.

    Attributes:
        faces: ``(F', 3)`` int64, the input's triangles first, then the patches kept.
        holes_closed: patches kept (one per covered hole; 0: ``faces`` are the input's).
        notes: why patches were left out, if any were.
    """

    faces: np.ndarray
    holes_closed: int
    notes: tuple[str, ...] = ()


def boundary_loops(faces: np.ndarray, n_vertices: int) -> int:
    """Number of boundary loops: the cycle rank ``E - V + C`` of the graph of edges held by
    one triangle (on a manifold mesh every boundary vertex has even degree there, so the
    boundary is a union of loops; two loops that touch at a vertex count as two)."""
    edges, counts = edge_face_counts(np.asarray(faces, dtype=np.int64))
    border = edges[counts == 1]  # (B, 2)
    if border.shape[0] == 0:
        return 0
    graph = sp.coo_matrix((np.ones(border.shape[0]), (border[:, 0], border[:, 1])), shape=(n_vertices, n_vertices))
    _, labels = connected_components(graph, directed=False)
    used = np.unique(border)
    return int(border.shape[0] - used.size + np.unique(labels[used]).size)


def _loop_spans(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The least area that covering each boundary component needs, and whether it is one loop.

    For a closed curve, any surface it bounds has area at least the length of the curve's
    vector area ``1/2 sum p_a x p_b`` over its directed edges (the integral of the unit
    normal over the surface, whose length is at most the surface's area). Each boundary
    edge is taken in the direction of its one triangle, so the loop is consistently
    oriented and its edges need no ordering.

    Returns:
        ``span (C,)`` the length of each component's vector area, and ``simple (C,)``
        whether the component is a single, consistently oriented loop (every vertex
        starts one boundary edge and ends one); ``span`` bounds a patch only there.
    """
    n = vertices.shape[0]
    faces = np.asarray(faces, dtype=np.int64)
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])  # (3F, 2)
    key = directed.min(axis=1) * n + directed.max(axis=1)  # one int64 per undirected edge
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    border = directed[counts[inverse] == 1]  # (B, 2) each in its triangle's direction
    graph = sp.coo_matrix((np.ones(border.shape[0]), (border[:, 0], border[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    used, comp = np.unique(labels[border[:, 0]], return_inverse=True)
    # cross products about a point of each component: the same sum for a closed chain, without
    # the cancellation of large coordinates far from the origin
    ref = np.zeros((used.size, 3))
    ref[comp] = vertices[border[:, 0]]  # any one vertex of each component
    a, b = vertices[border[:, 0]] - ref[comp], vertices[border[:, 1]] - ref[comp]
    cross = 0.5 * np.cross(a, b)  # (B, 3)
    span = np.stack([np.bincount(comp, weights=cross[:, i], minlength=used.size) for i in range(3)], 1)
    # a single, consistently oriented loop: every vertex starts one border edge and ends one
    # (a flipped triangle on the rim reverses an edge, and the sum is then no vector area)
    out_deg = np.bincount(border[:, 0], minlength=n)
    in_deg = np.bincount(border[:, 1], minlength=n)
    bad = (out_deg[border[:, 0]] != 1) | (in_deg[border[:, 0]] != 1) | (out_deg[border[:, 1]] != 1) | (in_deg[border[:, 1]] != 1)
    simple = np.bincount(comp, weights=bad.astype(float), minlength=used.size) == 0
    return np.linalg.norm(span, axis=1), simple


def _patches(new: np.ndarray) -> np.ndarray:
    """Label ``(N,)`` of the patch of each new triangle: triangles joined through shared edges."""
    edges = np.sort(np.concatenate([new[:, [0, 1]], new[:, [1, 2]], new[:, [2, 0]]]), axis=1)  # (3N, 2)
    owner = np.tile(np.arange(new.shape[0]), 3)  # (3N,)
    _, key = np.unique(edges, axis=0, return_inverse=True)
    order = np.argsort(key.ravel(), kind="stable")
    same = key.ravel()[order][1:] == key.ravel()[order][:-1]  # consecutive copies of one edge
    a, b = owner[order][:-1][same], owner[order][1:][same]
    graph = sp.coo_matrix((np.ones(a.size), (a, b)), shape=(new.shape[0], new.shape[0]))
    return connected_components(graph, directed=False)[1]


def _large_note(count: int, max_area: float) -> str:
    return (
        f"{count} boundary loops left open: covering them would add more than {max_area:g} of the "
        "area (the outline of an open surface, not a hole)"
    )


def close_holes(vertices: np.ndarray, faces: np.ndarray, *, max_area: float = 0.1) -> HoleFilling:
    """Cover the holes of ``(vertices, faces)`` with new triangles between boundary vertices.

    Uses MeshLab's ``meshing_close_holes`` with its check that the new triangles do not
    intersect the mesh. Vertices are neither added nor moved. Left out, and said in
    ``notes``: new triangles of zero area (collinear boundary vertices; the hole stays
    partly open), a patch larger than ``max_area`` times the mesh's area (the outline of
    an open surface, a panel or a mask, not a hole: covering it would glue a second face
    onto the surface), and a patch that would make an edge non-manifold. When every
    boundary is a single loop whose vector area alone exceeds ``max_area`` (a lower bound
    of any patch's area), MeshLab is not called: no patch could be kept.

    Args:
        vertices: ``(V, 3)`` positions.
        faces: ``(F, 3)`` a manifold triangulation (as :func:`validate_mesh` ensures).
        max_area: the largest patch, as a share of the mesh's area.

    Returns:
        A :class:`HoleFilling`.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    if boundary_loops(faces, vertices.shape[0]) == 0:
        return HoleFilling(faces, 0)
    span, simple = _loop_spans(vertices, faces)
    old_area = face_areas(vertices, faces)  # (F,)
    limit = max_area * float(old_area.sum())
    if simple.all() and (span > limit).all():  # no patch could be kept: MeshLab need not run
        return HoleFilling(faces, 0, (_large_note(span.size, max_area),))
    import pymeshlab  # only open meshes need it

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.ascontiguousarray(vertices), face_matrix=np.ascontiguousarray(faces, dtype=np.int32)))
    try:
        ms.meshing_close_holes(maxholesize=max(3, 2 * faces.shape[0]), selfintersection=True, newfaceselected=True)
    except pymeshlab.PyMeshLabException as exc:
        return HoleFilling(faces, 0, (f"holes left open: MeshLab's hole filling failed ({exc})",))
    out = ms.current_mesh()
    if out.vertex_number() != vertices.shape[0] or not np.array_equal(out.vertex_matrix(), vertices):
        return HoleFilling(faces, 0, ("holes left open: MeshLab's hole filling moved or added vertices",))
    new = out.face_matrix()[out.face_selection_array()].astype(np.int64)  # (N, 3) the patches
    notes: list[str] = []
    area = face_areas(vertices, new)
    flat = area <= 1e-12 * max(float(old_area.max()), np.finfo(float).tiny)
    if flat.any():
        notes.append(f"{int(flat.sum())} new triangles of zero area left out")
        new, area = new[~flat], area[~flat]
    if new.shape[0] == 0:
        return HoleFilling(faces, 0, tuple(notes))
    patch = _patches(new)  # (N,)
    patch_area = np.bincount(patch, weights=area)  # (P,)
    large = patch_area > limit
    if large.any():
        notes.append(_large_note(int(large.sum()), max_area))
    keep = ~large[patch]
    edges, counts = edge_face_counts(np.concatenate([faces, new[keep]]))
    if (counts > 2).any():  # patches that would make an edge non-manifold are left out
        bad = {tuple(e) for e in edges[counts > 2].tolist()}
        tri_edges = np.sort(np.stack([new[:, [0, 1]], new[:, [1, 2]], new[:, [2, 0]]], axis=1), axis=2)  # (N, 3, 2)
        touches = np.array([any(tuple(e) in bad for e in tri.tolist()) for tri in tri_edges])
        drop = np.unique(patch[touches & keep])
        keep &= ~np.isin(patch, drop)
        notes.append(f"{drop.size} patches left out: they would make an edge non-manifold")
    if not keep.any():
        return HoleFilling(faces, 0, tuple(notes))
    return HoleFilling(np.concatenate([faces, new[keep]]), int(np.unique(patch[keep]).size), tuple(notes))
