"""Discrete operators on triangle meshes (thesis Sec. 6.2.3), as pure NumPy/SciPy functions.

Every function takes ``vertices (V, 3)`` float and ``faces (F, 3)`` int arrays and
returns NumPy arrays or SciPy sparse matrices, in the style of pyFM. The cotangent
Laplacian is returned as the positive semi-definite stiffness matrix ``W`` (the thesis's
``-M``) with the lumped mass matrix ``A``; the eigenfunctions solve ``W phi = lambda A phi``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
import torch
from threadpoolctl import threadpool_limits

from torchsym.core.random import numpy_rng
from torchsym.errors import InputShapeError, SolverError

__all__ = [
    "adjacency_matrix",
    "cotangent_laplacian",
    "edge_face_counts",
    "edge_graph",
    "face_areas",
    "laplacian_eigen",
    "mass_matrix",
    "ring_neighbourhood",
]

#: Triangles whose doubled area is below this fraction of the mean get zero cotangent weights.
_DEGENERATE_REL = 1e-12


def face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area of every triangle, ``(F,)``."""
    v0, v1, v2 = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]  # (F, 3) each
    return 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)  # (F,)


def cotangent_laplacian(vertices: np.ndarray, faces: np.ndarray) -> sp.csr_matrix:
    """The cotangent stiffness matrix ``W`` (positive semi-definite), ``(V, V)`` CSR.

    ``W[j, j'] = -(cot alpha + cot beta) / 2`` for every edge ``(j, j')`` and
    ``W[j, j] = -sum_{j' != j} W[j, j']`` (thesis Sec. 6.2.3, with the sign flipped so
    that ``W`` is positive semi-definite). Triangles of (near) zero area contribute
    nothing instead of infinite cotangents.
    """
    n = vertices.shape[0]
    v = [vertices[faces[:, i]] for i in range(3)]  # 3 x (F, 3)
    dbl_area = np.linalg.norm(np.cross(v[1] - v[0], v[2] - v[0]), axis=1)  # (F,)
    ok = dbl_area > _DEGENERATE_REL * max(float(dbl_area.mean()), np.finfo(float).tiny)  # (F,)
    safe = np.where(ok, dbl_area, 1.0)  # (F,)
    rows, cols, vals = [], [], []
    for k in range(3):  # angle at corner k, opposite edge (i, j)
        i, j = (k + 1) % 3, (k + 2) % 3
        e1, e2 = v[i] - v[k], v[j] - v[k]  # (F, 3)
        cot = np.where(ok, np.einsum("fd,fd->f", e1, e2) / safe, 0.0)  # (F,)
        rows += [faces[:, i], faces[:, j]]
        cols += [faces[:, j], faces[:, i]]
        vals += [-0.5 * cot, -0.5 * cot]
    off = sp.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    ).tocsr()  # (V, V)
    diag = -np.asarray(off.sum(axis=1)).ravel()  # (V,)
    return (off + sp.diags(diag)).tocsr()  # (V, V)


def mass_matrix(vertices: np.ndarray, faces: np.ndarray) -> sp.dia_matrix:
    """Lumped (barycentric) mass: a third of the incident triangles' area, ``(V, V)`` diagonal."""
    areas = face_areas(vertices, faces)  # (F,)
    lumped = np.bincount(faces.ravel(), weights=np.repeat(areas / 3.0, 3), minlength=vertices.shape[0])  # (V,)
    return sp.diags(lumped)  # (V, V)


def laplacian_eigen(
    vertices: np.ndarray,
    faces: np.ndarray,
    k: int,
    *,
    generator: torch.Generator | None = None,
    tol: float = 1e-8,
) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` smallest eigenpairs of ``W phi = lambda A phi`` (Sec. 6.2.3).

    Solved by ARPACK (``scipy.sparse.linalg.eigsh``) in shift-invert mode around a small
    negative shift, from a seeded starting vector. Eigenvectors are ``A``-orthonormal.
    There is no fallback: a failure raises :class:`SolverError`.

    Args:
        vertices: ``(V, 3)`` positions.
        faces: ``(F, 3)`` triangles.
        k: number of eigenpairs, ``1 <= k < V``.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.
        tol: ARPACK relative accuracy.

    Returns:
        ``evals (k,)`` ascending and ``evecs (V, k)``.
    """
    n = vertices.shape[0]
    if not 1 <= k < n:
        raise InputShapeError(f"k: expected 1 <= k < V = {n} (number of vertices), got {k}")
    stiff = cotangent_laplacian(vertices, faces)  # (V, V)
    mass = mass_matrix(vertices, faces).tocsc()  # (V, V)
    scale = float(stiff.diagonal().mean() / max(mass.diagonal().mean(), np.finfo(float).tiny))
    sigma = -1e-6 * scale
    v0 = numpy_rng(generator).standard_normal(n)  # (V,)
    # a roomy Krylov space lets single-vector Lanczos find every copy of a repeated eigenvalue
    ncv = min(n, max(2 * k + 1, 40))
    try:
        # ARPACK's vector updates are small: several BLAS threads only contend (about 5x
        # slower on a loaded 2-core machine), so they run on one
        with threadpool_limits(limits=1, user_api="blas"):
            evals, evecs = spla.eigsh(stiff.tocsc(), k=k, M=mass, sigma=sigma, which="LM", v0=v0, tol=tol, ncv=ncv)
    except (spla.ArpackNoConvergence, spla.ArpackError, RuntimeError) as exc:
        raise SolverError(f"laplacian_eigen: ARPACK failed for k={k} on a mesh with {n} vertices ({exc})") from None
    order = np.argsort(evals)
    return evals[order], evecs[:, order]  # (k,), (V, k)


def edge_face_counts(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct edges ``(E, 2)`` (sorted vertex pairs) and how many triangles hold each ``(E,)``.

    Count 1: a boundary edge; 2: an interior edge of a manifold; more: non-manifold.
    """
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)  # (3F, 2)
    if edges.size == 0:
        return edges.reshape(0, 2), np.zeros(0, dtype=np.int64)
    key = _pair_keys(edges)
    if key is None:
        return np.unique(edges, axis=0, return_counts=True)
    _, first, counts = np.unique(key, return_index=True, return_counts=True)
    return edges[first], counts


def _pair_keys(pairs: np.ndarray) -> np.ndarray | None:
    """One int64 key per row of ``pairs`` ``(M, 2)``, in the rows' lexicographic order.

    ``np.unique`` on these is ~10x faster than ``np.unique(pairs, axis=0)``. None when a
    key would collide or overflow (negative or huge indices).
    """
    top = int(pairs.max())
    if int(pairs.min()) < 0 or top >= 3_000_000_000:
        return None
    return pairs[:, 0].astype(np.int64) * (top + 1) + pairs[:, 1].astype(np.int64)


def consistently_wound(faces: np.ndarray) -> bool:
    """Whether every edge shared by two triangles is traversed in opposite directions by them.

    Then the winding defines one orientation of each connected surface; where it does
    not (half a mesh mirrored without flipping its triangles), an orientation test such
    as :func:`~torchsym.mesh.orientation.orientation_reversal` is meaningless.
    """
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])  # (3F, 2)
    if directed.size == 0:
        return True
    key = _pair_keys(directed)
    unique = np.unique(directed, axis=0).shape[0] if key is None else np.unique(key).size
    return unique == directed.shape[0]


def adjacency_matrix(faces: np.ndarray, n_vertices: int) -> sp.csr_matrix:
    """Vertex adjacency through edges, symmetric 0/1 without the diagonal, ``(V, V)`` CSR."""
    i = faces[:, [0, 1, 2, 1, 2, 0]].ravel()  # (6F,)
    j = faces[:, [1, 2, 0, 0, 1, 2]].ravel()  # (6F,)
    adj = sp.coo_matrix((np.ones(i.shape[0]), (i, j)), shape=(n_vertices, n_vertices)).tocsr()  # (V, V)
    adj.data[:] = 1.0
    adj.setdiag(0)
    adj.eliminate_zeros()
    return adj


def ring_neighbourhood(faces: np.ndarray, n_vertices: int, rings: int = 2) -> sp.csr_matrix:
    """Vertices within ``rings`` edges of each vertex (itself excluded), 0/1 ``(V, V)`` CSR."""
    adj = adjacency_matrix(faces, n_vertices)  # (V, V)
    reach = adj.copy()
    for _ in range(rings - 1):
        reach = reach + reach @ adj  # (V, V)
    reach = reach.tocsr()
    reach.data[:] = 1.0
    reach.setdiag(0)
    reach.eliminate_zeros()
    return reach


def edge_graph(vertices: np.ndarray, faces: np.ndarray) -> sp.csr_matrix:
    """The edge graph weighted by Euclidean edge lengths, symmetric ``(V, V)`` CSR."""
    adj = adjacency_matrix(faces, vertices.shape[0]).tocoo()  # (V, V)
    length = np.linalg.norm(vertices[adj.row] - vertices[adj.col], axis=1)  # (E2,)
    # zero-length edges would vanish from a sparse graph; keep them as tiny positive weights
    length = np.maximum(length, np.finfo(float).tiny)
    return sp.csr_matrix((length, (adj.row, adj.col)), shape=adj.shape)  # (V, V)
