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

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from torchsym.mesh.operators import edge_face_counts, face_areas

__all__ = ["boundary_loops", "close_holes"]


def boundary_loops(faces: np.ndarray, n_vertices: int) -> int:
    """Number of boundary loops: connected components of the edges held by one triangle."""
    edges, counts = edge_face_counts(faces)
    border = edges[counts == 1]  # (B, 2)
    if border.shape[0] == 0:
        return 0
    graph = sp.coo_matrix((np.ones(border.shape[0]), (border[:, 0], border[:, 1])), shape=(n_vertices, n_vertices))
    _, labels = connected_components(graph, directed=False)
    return int(np.unique(labels[np.unique(border)]).size)


def close_holes(vertices: np.ndarray, faces: np.ndarray, *, max_area: float = 0.1) -> tuple[np.ndarray, int]:
    """Faces of ``(vertices, faces)`` with its boundary loops covered by new triangles.

    Uses MeshLab's ``meshing_close_holes`` with its check that the new triangles do not
    intersect the mesh; new triangles of zero area (collinear boundary vertices) are left
    out, so a hole may stay partly open. Vertices are neither added nor moved. A patch
    larger than ``max_area`` times the mesh's area is left out: such a boundary is the
    outline of an open surface (a panel, a mask), not a hole, and covering it would glue
    a second face onto the surface.

    Args:
        vertices: ``(V, 3)`` positions.
        faces: ``(F, 3)`` a manifold triangulation (as :func:`validate_mesh` ensures).
        max_area: the largest patch, as a share of the mesh's area.

    Returns:
        ``faces (F', 3)`` int64 with the input's triangles first, and the number of
        boundary loops closed (0 leaves ``faces`` as they were).
    """
    import pymeshlab

    before = boundary_loops(faces, vertices.shape[0])
    if before == 0:
        return faces, 0
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.ascontiguousarray(vertices, dtype=np.float64),
                               face_matrix=np.ascontiguousarray(faces, dtype=np.int32)))
    try:
        ms.meshing_close_holes(maxholesize=max(3, 2 * faces.shape[0]), selfintersection=True, newfaceselected=True)
    except pymeshlab.PyMeshLabException:
        return faces, 0
    out = ms.current_mesh()
    if out.vertex_number() != vertices.shape[0] or not np.array_equal(out.vertex_matrix(), vertices):
        return faces, 0  # MeshLab moved or added vertices: the map would no longer be the input's
    new = out.face_matrix()[out.face_selection_array()].astype(np.int64)  # (N, 3) the patches
    area = face_areas(vertices, new)
    old_area = face_areas(vertices, faces)
    keep = area > 1e-12 * max(float(old_area.max()), np.finfo(float).tiny)
    # one patch per hole: the new triangles joined through shared vertices
    n = vertices.shape[0]
    ring = np.concatenate([new[:, [0, 1]], new[:, [1, 2]]])
    graph = sp.coo_matrix((np.ones(ring.shape[0]), (ring[:, 0], ring[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    patch = labels[new[:, 0]]  # (N,)
    patch_area = np.bincount(patch, weights=area, minlength=labels.max() + 1)  # per label
    keep &= patch_area[patch] <= max_area * float(old_area.sum())
    new = new[keep]
    if new.shape[0] == 0:
        return faces, 0
    closed = np.concatenate([faces, new])
    if (edge_face_counts(closed)[1] > 2).any():
        return faces, 0  # a patch would make an edge non-manifold
    return closed, before - boundary_loops(closed, vertices.shape[0])
