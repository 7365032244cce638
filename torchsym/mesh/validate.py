"""Checks a triangle mesh before any operator runs on it.

:class:`~torchsym.geometry.mesh.Mesh` already checks shapes, dtypes, finiteness and index
range. :func:`validate_mesh` adds what the spectral methods of Chapter 6 need: at least
one triangle, no degenerate triangles, manifold edges, and one connected component (the
largest is kept by default, and the result says which vertices were dropped).
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np
import scipy.sparse as sp
import torch
from scipy.sparse.csgraph import connected_components

from torchsym.core.checks import check_finite
from torchsym.errors import InputShapeError, InputValueError
from torchsym.geometry.mesh import Mesh
from torchsym.mesh.operators import edge_face_counts, face_areas

__all__ = ["ValidatedMesh", "validate_mesh"]


@dataclasses.dataclass(frozen=True)
class ValidatedMesh:
    """A mesh that passed :func:`validate_mesh`, and how it relates to the input.

    Attributes:
        mesh: the mesh the solver works on (the largest component when others were dropped).
        vertex_index: ``(V',)`` int64, for each vertex of ``mesh`` its index in the input.
        num_input_vertices: ``V`` of the input mesh.
        num_components: connected components of the input (isolated vertices count).
        dropped_vertices: input vertices not in ``mesh``.
    """

    mesh: Mesh
    vertex_index: torch.Tensor
    num_input_vertices: int
    num_components: int
    dropped_vertices: int

    def to_input(self, values: torch.Tensor, fill: int = -1) -> torch.Tensor:
        """Scatter per-vertex int64 ``values (V',)`` back to input order ``(V,)``, ``fill`` elsewhere."""
        out = torch.full((self.num_input_vertices,), fill, dtype=values.dtype)
        out[self.vertex_index] = values
        return out

    def map_to_input(self, vertex_map: torch.Tensor) -> torch.Tensor:
        """A self-map of ``mesh``'s vertices ``(V',)`` as a map of input vertices ``(V,)`` (-1 where dropped)."""
        return self.to_input(self.vertex_index[vertex_map])


def validate_mesh(
    mesh: Mesh,
    *,
    components: Literal["largest", "refuse"] = "largest",
    min_vertices: int = 4,
) -> ValidatedMesh:
    """Check ``mesh`` for the problems that break Laplacian eigenmaps, and keep one component.

    Args:
        mesh: the input :class:`Mesh`.
        components: ``"largest"`` keeps the component with the most vertices (vertices in
            no triangle count as components of their own) and reports what was dropped;
            ``"refuse"`` raises when there is more than one.
        min_vertices: the fewest vertices the kept mesh may have.

    Raises:
        InputShapeError: ``mesh`` is not a :class:`Mesh`.
        InputValueError: no triangles (a point cloud passed as a mesh), NaN coordinates,
            a triangle with a repeated vertex or zero area, an edge shared by more than
            two triangles, several components with ``components="refuse"``, or fewer than
            ``min_vertices`` vertices.
    """
    if not isinstance(mesh, Mesh):
        raise InputShapeError(f"mesh: expected a torchsym.mesh.Mesh, got {type(mesh).__name__}")
    if components not in ("largest", "refuse"):
        raise InputValueError(f"components: expected 'largest' or 'refuse', got {components!r}")
    check_finite(mesh.vertices, "mesh.vertices")
    if mesh.num_faces == 0:
        raise InputValueError(
            f"mesh.faces: expected at least one triangle, got (0, 3) with {mesh.num_vertices} vertices "
            "(a point cloud passed as a mesh?)"
        )
    v = mesh.vertices.detach().cpu().double().numpy()  # (V, 3)
    f = mesh.faces.detach().cpu().numpy()  # (F, 3)
    n = v.shape[0]

    repeated = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])  # (F,)
    if repeated.any():
        idx = np.flatnonzero(repeated)
        raise InputValueError(
            f"mesh.faces: expected three distinct vertices per triangle, got {idx.size} degenerate "
            f"triangles with a repeated vertex (first: face {idx[0]} = {f[idx[0]].tolist()})"
        )
    dbl_area = 2.0 * face_areas(v, f)  # (F,)
    flat = dbl_area <= 1e-12 * max(float(dbl_area.max()), np.finfo(float).tiny)
    if flat.any():
        idx = np.flatnonzero(flat)
        raise InputValueError(
            f"mesh.faces: expected triangles of positive area, got {idx.size} degenerate "
            f"zero-area triangles (first: face {idx[0]} = {f[idx[0]].tolist()})"
        )

    uniq, counts = edge_face_counts(f)
    if (counts > 2).any():
        bad = uniq[counts > 2]
        raise InputValueError(
            f"mesh.faces: expected a manifold mesh (each edge in at most 2 triangles), got {bad.shape[0]} "
            f"non-manifold edges (first: vertices {bad[0].tolist()} in {int(counts[counts > 2][0])} triangles)"
        )

    graph = sp.coo_matrix((np.ones(uniq.shape[0]), (uniq[:, 0], uniq[:, 1])), shape=(n, n))
    n_comp, labels = connected_components(graph, directed=False)
    keep = np.arange(n)
    if n_comp > 1:
        sizes = np.bincount(labels, minlength=n_comp)
        if components == "refuse":
            raise InputValueError(
                f"mesh: expected one connected component, got {n_comp} "
                f"(sizes {sorted(sizes.tolist(), reverse=True)[:5]}...); pass components='largest' to keep the largest"
            )
        keep = np.flatnonzero(labels == int(np.argmax(sizes)))
    if keep.size < min_vertices:
        raise InputValueError(
            f"mesh: expected at least {min_vertices} vertices in the largest connected component, got {keep.size}"
        )
    if keep.size < n:
        new_id = np.full(n, -1, dtype=np.int64)
        new_id[keep] = np.arange(keep.size)
        f_keep = new_id[f]
        f_keep = f_keep[(f_keep >= 0).all(axis=1)]
        out = Mesh(mesh.vertices[torch.from_numpy(keep)], torch.from_numpy(f_keep))
    else:
        out = mesh
    return ValidatedMesh(
        mesh=out,
        vertex_index=torch.from_numpy(keep.astype(np.int64)),
        num_input_vertices=n,
        num_components=int(n_comp),
        dropped_vertices=int(n - keep.size),
    )
