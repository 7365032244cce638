"""Orientation-reversing functional self-maps: a second hypothesis for intrinsic symmetry.

The thesis (Sec. 6.2.5-6.2.7) builds the symmetry's functional map from sparse pairs of
feature points: ``C = diag(s)`` with the signs ``s`` read along geodesics, then a
rotation ``R`` of the eigenbasis. Where the pairs are wrong, or an eigenspace is nearly
repeated, it has no second chance. The classical alternative is to fit the functional map
to dense descriptors (Ovsjanikov et al. 2012). For a *self* map, descriptors alone are
satisfied by the identity; an intrinsic reflection is told apart by reversing the
surface's orientation (Ren, Poulenard, Wonka and Ovsjanikov 2018, "Continuous and
orientation-preserving correspondences via functional maps"): for every descriptor ``f``
the operator ``O_f(g) = <n x grad f, grad g>`` satisfies ``C O_f = -O_f C`` under a
reflection, because the reflection maps ``n x grad f`` to ``-n x grad(f o T)``.

:func:`orientation_reversing_map` minimises, over ``C`` in ``R^{k x k}`` with the
constant function fixed (``C e_0 = e_0``)::

    a_d |C B - B|^2 + a_l sum_ij M_ij C_ij^2
        + a_c sum_p |C D_p - D_p C|^2 + a_o sum_p |C O_p + O_p C|^2

with ``B`` the descriptors in the eigenbasis, ``M`` the resolvent mask of the eigenvalues
(Ren et al. 2019, "Structured regularization of functional map computations"), ``D_p``
the operators of multiplication by descriptor ``p`` and ``O_p`` its orientation
operators. The energy is a quadratic in ``k^2`` unknowns, so it is minimised exactly by
one ``k^2 x k^2`` linear solve (0.2 ms at ``k = 13``) instead of by L-BFGS as pyFM does;
on the benchmark's synthetic meshes both reach the same minimiser (to 1e-2 in Frobenius
norm). Each commutativity weight is divided by the term's expected value under a
uniformly random orthogonal ``C``, the Laplacian weight likewise, and the descriptor
weight by ``|B|^2`` (half that expectation; the same normalisations as pyFM's canonical
weights, so that the default weights mean what they mean there); the descriptor terms
are also divided by the effective number of independent descriptors, so that the weights
compare terms of equal scale.
"""

from __future__ import annotations

import numpy as np

from torchsym.core.checks import check_positive
from torchsym.errors import InputShapeError, InputValueError, SolverError
from torchsym.mesh.operators import ring_neighbourhood

__all__ = [
    "anticommutation_penalty",
    "descriptor_operators",
    "orientation_operators",
    "OrientationTest",
    "orientation_reversal",
    "orientation_reversing_map",
    "reduce_descriptors",
    "resolvent_mask",
    "tangent_frames",
]


def _hat_gradients(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-face gradients of the three hat functions, unit normals and areas.

    Returns ``(G, N, a)`` with ``G (F, 3, 3)``: ``G[f, c]`` the gradient on face ``f`` of
    the hat function of its ``c``-th corner, ``N (F, 3)`` and ``a (F,)``.
    """
    p = vertices[faces]  # (F, 3, 3)
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])  # (F, 3)
    dbl = np.linalg.norm(cross, axis=1)  # (F,) twice the area
    safe = np.where(dbl > 0, dbl, 1.0)
    normal = cross / safe[:, None]  # (F, 3)
    # gradient of corner c's hat function: n x (edge opposite c, counter-clockwise) / (2a)
    opposite = np.stack([p[:, 2] - p[:, 1], p[:, 0] - p[:, 2], p[:, 1] - p[:, 0]], axis=1)  # (F, 3, 3)
    grads = np.cross(normal[:, None, :], opposite) / safe[:, None, None]  # (F, 3, 3)
    grads[dbl == 0] = 0.0  # a degenerate face carries no gradient
    return grads, normal, 0.5 * dbl


def descriptor_operators(evecs: np.ndarray, area: np.ndarray, functions: np.ndarray) -> np.ndarray:
    """Operators of multiplication by each function in the eigenbasis, ``(p, k, k)``.

    ``D_p = Phi^T A diag(f_p) Phi``; a functional map of a map that preserves ``f_p``
    commutes with ``D_p``.

    Args:
        evecs: ``(V, k)`` area-orthonormal eigenfunctions ``Phi``.
        area: ``(V,)`` lumped vertex areas ``A``.
        functions: ``(V, p)`` the functions ``f_p``.
    """
    v, k = evecs.shape
    products = (evecs * area[:, None])[:, :, None] * evecs[:, None, :]  # (V, k, k)
    return (functions.T @ products.reshape(v, k * k)).reshape(-1, k, k)  # (p, k, k)


def orientation_operators(
    vertices: np.ndarray, faces: np.ndarray, evecs: np.ndarray, functions: np.ndarray
) -> np.ndarray:
    """Orientation operators ``O_p(g) = <n x grad f_p, grad g>`` in the eigenbasis, ``(p, k, k)``.

    The pointwise operator is evaluated per face (gradients of piecewise-linear functions
    are constant on a face) and integrated against each eigenfunction with the face's
    area shared equally by its corners: ``(O_p)_ij = sum_f (a_f / 3) (sum_{v in f}
    phi_i(v)) <n_f x grad f_p, grad phi_j>_f``. It flips sign under an
    orientation-reversing isometry (see the module docstring).

    Args:
        vertices: ``(V, 3)`` positions.
        faces: ``(F, 3)`` vertex indices.
        evecs: ``(V, k)`` eigenfunctions ``Phi``.
        functions: ``(V, p)`` the functions ``f_p``.
    """
    grads, normal, face_area = _hat_gradients(vertices, faces)  # (F, 3, 3), (F, 3), (F,)
    corner_phi = evecs[faces]  # (F, 3, k)
    grad_phi = np.matmul(grads.transpose(0, 2, 1), corner_phi)  # (F, 3, k)
    # <n x grad f, grad phi_j> = <grad f, grad phi_j x n>, and grad f = sum_c f(corner c) grads[:, c]
    rot_phi = np.cross(grad_phi, normal[:, :, None], axis=1)  # (F, 3, k)
    per_corner = np.matmul(grads, rot_phi)  # (F, 3, k): <grads[:, c], grad phi_j x n>
    inner = np.matmul(functions[faces].transpose(0, 2, 1), per_corner)  # (F, p, k)
    corner = corner_phi.sum(axis=1) * (face_area / 3.0)[:, None]  # (F, k)
    n_faces, p, k = inner.shape
    return (corner.T @ inner.reshape(n_faces, p * k)).reshape(k, p, k).transpose(1, 0, 2)  # (p, k, k)


def resolvent_mask(evals: np.ndarray, gamma: float = 0.5) -> np.ndarray:
    """Penalty ``M_ij`` on ``C_ij`` for maps between eigenfunctions of different eigenvalues.

    The resolvent form of Ren et al. 2019: with ``l = (lambda / max lambda)^gamma`` and
    ``r(l) = 1 / (l - i)``, ``M_ij = |r(l_i) - r(l_j)|^2``. It vanishes on equal
    eigenvalues, like the usual ``(lambda_i - lambda_j)^2``, but stays bounded as ``k``
    grows. ``(k, k)``.
    """
    lam = np.abs(np.asarray(evals, dtype=np.float64))
    lam = (lam / max(float(lam.max()), np.finfo(float).tiny)) ** gamma  # (k,)
    re, im = lam / (lam**2 + 1.0), 1.0 / (lam**2 + 1.0)  # (k,), (k,)
    return (re[:, None] - re[None, :]) ** 2 + (im[:, None] - im[None, :]) ** 2


def _commutator_gram(ops: np.ndarray, sign: float) -> tuple[np.ndarray, float]:
    """Gram matrix of ``sum_p |C X_p - sign X_p C|^2`` in ``vec(C)`` (row major), and its scale.

    With ``vec(A C B) = (A kron B^T) vec(C)`` the residual is ``(I kron X^T - sign X kron I)
    vec(C)``, whose Gram matrix is ``I kron X X^T + X^T X kron I - sign (X^T kron X^T + X
    kron X)``. The scale is the term's mean under a uniformly random orthogonal ``C``:
    ``2 |X|^2 - 2 sign tr(X)^2 / k`` (Haar moments of ``C``).
    """
    k = ops.shape[1]
    eye = np.eye(k)
    xxt = np.einsum("pij,pkj->ik", ops, ops)  # (k, k) sum X X^T
    xtx = np.einsum("pji,pjk->ik", ops, ops)  # (k, k) sum X^T X
    # (A kron B)[(i, j), (l, m)] = A_il B_jm
    cross = np.einsum("pli,pmj->ijlm", ops, ops).reshape(k * k, k * k)  # sum X^T kron X^T
    cross += np.einsum("pil,pjm->ijlm", ops, ops).reshape(k * k, k * k)  # sum X kron X
    gram = np.kron(eye, xxt) + np.kron(xtx, eye) - sign * cross
    scale = float(2.0 * np.sum(ops**2) - 2.0 * sign * np.sum(np.trace(ops, axis1=1, axis2=2) ** 2) / k)
    return gram, max(scale, np.finfo(float).tiny)


def reduce_descriptors(descriptors: np.ndarray, area: np.ndarray) -> np.ndarray:
    """Descriptors scaled to unit area-weighted L2 norm, in an area-orthogonal basis of their span, ``(V, r)``.

    The descriptor, commutativity and orientation terms depend on the descriptors only
    through ``sum_p f_p f_p^T``, so this basis gives the same energies with fewer columns
    (the HKS lives in the span of the ``k`` functions ``phi_i^2``: 50 scales, at most ``k``
    columns). Scaling each column first makes the result independent of the order and
    scale of the columns.

    Raises:
        InputShapeError: ``descriptors`` without one row per entry of ``area``.
        InputValueError: NaN or inf, or no non-zero descriptor.
    """
    area = np.asarray(area, dtype=np.float64)
    if area.ndim != 1:
        raise InputShapeError(f"area: expected (V,), got {tuple(area.shape)}")
    desc = np.asarray(descriptors, dtype=np.float64)
    if desc.ndim != 2 or desc.shape[0] != area.shape[0]:
        raise InputShapeError(f"descriptors: expected ({area.shape[0]}, p), one row per vertex, got {tuple(desc.shape)}")
    if not np.isfinite(desc).all():
        raise InputValueError("descriptors: expected finite values, got NaN or inf")
    norms = np.sqrt((area[:, None] * desc**2).sum(axis=0))  # (p,)
    if not (norms > 0).any():
        raise InputValueError("descriptors: expected at least one non-zero descriptor, got none")
    desc = desc[:, norms > 0] / norms[norms > 0]
    gram_f, basis = np.linalg.eigh(desc.T @ (area[:, None] * desc))  # (p,), (p, p)
    keep = gram_f > 1e-12 * max(float(gram_f.max()), np.finfo(float).tiny)
    return desc @ basis[:, keep]  # (V, r), sum of outer products unchanged


def anticommutation_penalty(ops: np.ndarray) -> np.ndarray:
    """Gram matrix of ``sum_p |C O_p + O_p C|^2`` in ``vec(C)`` (row major), divided by its mean.

    The mean is the term's value under a uniformly random orthogonal ``C`` (see
    :func:`_commutator_gram`), so that the penalty is about 1 for a map that ignores
    orientation and 0 for the functional map of an orientation-reversing isometry that
    preserves the descriptors. ``ops``: ``(p, k, k)`` orientation operators
    (:func:`orientation_operators`); the result is ``(k^2, k^2)``.
    """
    ops = np.asarray(ops, dtype=np.float64)
    if ops.ndim != 3 or ops.shape[1] != ops.shape[2]:
        raise InputShapeError(f"ops: expected (p, k, k), got {tuple(ops.shape)}")
    gram, scale = _commutator_gram(ops, -1.0)
    return gram / scale


def orientation_reversing_map(
    vertices: np.ndarray,
    faces: np.ndarray,
    evals: np.ndarray,
    evecs: np.ndarray,
    area: np.ndarray,
    descriptors: np.ndarray,
    *,
    w_descriptor: float = 0.1,
    w_laplacian: float = 1e-3,
    w_commutation: float = 1.0,
    w_orientation: float = 1.0,
    gamma: float = 0.5,
) -> np.ndarray:
    """The functional map of an intrinsic reflection fitted to dense descriptors, ``(k, k)``.

    Minimises the energy of the module docstring exactly (one linear solve) with
    ``C e_0 = e_0``. The default weights are those pyFM's documentation gives for
    orientation-reversing self-maps, used for the peer in ``benchmarks/bench_mesh.py``.

    Args:
        vertices: ``(V, 3)`` positions.
        faces: ``(F, 3)`` vertex indices.
        evals: ``(k,)`` Laplace-Beltrami eigenvalues (any common scale).
        evecs: ``(V, k)`` area-orthonormal eigenfunctions, the first one constant.
        area: ``(V,)`` lumped vertex areas.
        descriptors: ``(V, p)`` functions preserved by the symmetry (e.g. the HKS); each
            is scaled to unit area-weighted L2 norm first, so the result does not depend
            on the order or the scale of the columns.
        w_descriptor, w_laplacian, w_commutation, w_orientation: relative weights of the
            four terms (only their ratios matter).
        gamma: exponent of the resolvent mask (:func:`resolvent_mask`).

    Raises:
        InputValueError: negative or all-zero weights, a non-positive ``gamma``, or no
            usable (finite, non-zero) descriptor.
        InputShapeError: ``descriptors`` without one row per vertex.
        SolverError: a singular system (possible only with ``w_laplacian = 0``).

    Returns:
        ``C`` such that ``Phi C^T`` at a vertex's mirror is close to ``Phi`` at the vertex;
        :func:`~torchsym.mesh.fmaps.functional_to_pointwise` turns it into a point map.
    """
    k = evecs.shape[1]
    weights = np.array(
        [check_positive(w, name, allow_zero=True) for w, name in (
            (w_descriptor, "w_descriptor"), (w_laplacian, "w_laplacian"),
            (w_commutation, "w_commutation"), (w_orientation, "w_orientation"),
        )],
        dtype=np.float64,
    )
    if not weights.sum() > 0:
        raise InputValueError("w_descriptor, w_laplacian, w_commutation, w_orientation: expected a positive sum, got 0")
    gamma = check_positive(gamma, "gamma")
    desc = reduce_descriptors(descriptors, area)  # (V, r)
    weights = weights / weights.sum()
    b = evecs.T @ (area[:, None] * desc)  # (k, p) descriptors in the eigenbasis
    # effective number of independent descriptors, (tr G)^2 / |G|^2 with G = B^T B (no constant)
    g = b[1:].T @ b[1:]
    p_eff = float(np.trace(g) ** 2 / max(np.sum(g**2), np.finfo(float).tiny))
    eye = np.eye(k)

    # |C B - B|^2 = x^T (I kron B B^T) x - 2 vec(B B^T)^T x + const
    bbt = b @ b.T
    scale_d = max(float(np.sum(b[1:] ** 2)) / p_eff, np.finfo(float).tiny)
    quad = (weights[0] / scale_d) * np.kron(eye, bbt)
    lin = (weights[0] / scale_d) * bbt.reshape(-1)
    mask = resolvent_mask(evals, gamma)
    quad += (weights[1] / max(float(mask.sum()) / k, np.finfo(float).tiny)) * np.diag(mask.reshape(-1))
    if weights[2] > 0:
        gram, scale = _commutator_gram(descriptor_operators(evecs, area, desc), 1.0)
        quad += (weights[2] * p_eff / scale) * gram
    if weights[3] > 0:
        gram, scale = _commutator_gram(orientation_operators(vertices, faces, evecs, desc), -1.0)
        quad += (weights[3] * p_eff / scale) * gram

    # fix the first column to e_0 (constants map to constants) and solve for the rest
    fixed = np.zeros((k, k), dtype=bool)
    fixed[:, 0] = True
    fixed = fixed.reshape(-1)
    x = np.zeros(k * k)
    x[0] = 1.0
    rhs = lin[~fixed] - quad[np.ix_(~fixed, fixed)] @ x[fixed]
    try:
        x[~fixed] = np.linalg.solve(quad[np.ix_(~fixed, ~fixed)], rhs)
    except np.linalg.LinAlgError as exc:
        raise SolverError(f"orientation_reversing_map: the quadratic system is singular ({exc}); raise w_laplacian") from exc
    return x.reshape(k, k)


def orientation_reversal(
    vertices: np.ndarray,
    faces: np.ndarray,
    vertex_map: np.ndarray,
    rows: np.ndarray | None = None,
    rings: int = 2,
    neighbourhood=None,
) -> np.ndarray:
    """Whether a self map reverses the surface's orientation around each vertex of ``rows``, ``(R,)`` in {-1, 0, 1}.

    At vertex ``x`` with neighbours ``y`` (within ``rings`` edges), the offsets ``y - x``
    in a tangent frame at ``x`` and ``T y - T x`` in the frame at ``T x`` (both frames
    right-handed about the vertex normals of the face winding) give the 2 x 2 matrix
    ``M = sum_y (y - x) (T y - T x)^T``; ``sign det M`` is -1 where the map reverses the
    orientation, +1 where it keeps it, 0 where it collapses the neighbourhood. An
    intrinsic reflection reverses it everywhere but along its symmetry curve; the share
    of -1 is a pointwise check of a symmetric map that needs no ground truth (the maps
    of FAUST that fail by turning the torso half a turn about its axis keep the
    orientation on 65-80 % of the vertices, the true symmetries of FAUST and TOSCA
    reverse it on 65-85 %). Entries of ``vertex_map`` that are -1 (no image) give 0 at
    every row whose vertex or a neighbour has no image.

    Args:
        vertices: ``(V, 3)`` positions.
        faces: ``(F, 3)`` consistently wound triangles.
        vertex_map: ``(V,)`` the image of every vertex (-1: none).
        rows: the vertices to test (default: all).
        rings: the neighbourhood's size in edges, at least 1.
        neighbourhood: the ``(V, V)`` CSR of :func:`~torchsym.mesh.operators.ring_neighbourhood`
            for ``rings``, when the caller already has it (``rings`` is then ignored).

    Returns:
        ``(R,)`` int64.

    Raises:
        InputShapeError: ``vertices`` not ``(V, 3)``, ``faces`` not ``(F, 3)``, or
            ``vertex_map`` not ``(V,)``.
        InputValueError: indices out of range, or ``rings < 1``.
    """
    v = np.asarray(vertices, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] != 3:
        raise InputShapeError(f"vertices: expected (V, 3), got {tuple(v.shape)}")
    n = v.shape[0]
    faces = np.asarray(faces, dtype=np.int64)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise InputShapeError(f"faces: expected (F, 3), got {tuple(faces.shape)}")
    if faces.size and (faces.min() < 0 or faces.max() >= n):
        raise InputValueError(f"faces: expected vertex indices in [0, {n}), got {faces.min()}..{faces.max()}")
    vmap = np.asarray(vertex_map, dtype=np.int64)
    if vmap.shape != (n,):
        raise InputShapeError(f"vertex_map: expected ({n},), one image per vertex, got {tuple(vmap.shape)}")
    if vmap.size and (vmap.min() < -1 or vmap.max() >= n):
        raise InputValueError(f"vertex_map: expected indices in [-1, {n}), got {vmap.min()}..{vmap.max()}")
    rows = np.arange(n) if rows is None else np.asarray(rows, dtype=np.int64).reshape(-1)
    if rows.size and (rows.min() < 0 or rows.max() >= n):
        raise InputValueError(f"rows: expected vertex indices in [0, {n}), got {rows.min()}..{rows.max()}")
    if isinstance(rings, bool) or not isinstance(rings, (int, np.integer)) or rings < 1:
        raise InputValueError(f"rings: expected an integer >= 1, got {rings!r}")
    if neighbourhood is None:
        neighbourhood = ring_neighbourhood(faces, n, rings=rings)
    elif getattr(neighbourhood, "shape", None) != (n, n):
        raise InputShapeError(f"neighbourhood: expected a ({n}, {n}) sparse matrix, got {getattr(neighbourhood, 'shape', None)}")
    return OrientationTest(v, faces, rows, neighbourhood)(vmap)


def tangent_frames(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Right-handed tangent frames ``(e1, e2)``, each ``(V, 3)``, about the area-weighted vertex normals of the winding."""
    v = vertices
    face_normal = np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])  # (F, 3) area-weighted
    normal = np.zeros_like(v)
    for c in range(3):
        np.add.at(normal, faces[:, c], face_normal)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), np.finfo(float).tiny)
    # a right-handed tangent frame (e1, e2, n) at every vertex
    helper = np.where(np.abs(normal[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    e1 = np.cross(normal, helper)
    e1 /= np.maximum(np.linalg.norm(e1, axis=1, keepdims=True), np.finfo(float).tiny)
    return e1, np.cross(normal, e1)


class OrientationTest:
    """:func:`orientation_reversal` for many maps of one mesh: the frames and neighbourhoods computed once.

    Args (taken as given, unchecked; :func:`orientation_reversal` checks them):
        vertices: ``(V, 3)`` float64 positions.
        faces: ``(F, 3)`` int64 consistently wound triangles.
        rows: ``(R,)`` int64 vertices to test.
        neighbourhood: the ``(V, V)`` CSR of :func:`~torchsym.mesh.operators.ring_neighbourhood`.
        frames: :func:`tangent_frames` of the mesh, when the caller already has them.

    Calling it with a map ``(V,)`` int64 (-1: no image) gives what
    :func:`orientation_reversal` gives for that map, the same bits.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, rows: np.ndarray, neighbourhood, frames=None):
        v = vertices
        e1, e2 = tangent_frames(v, faces) if frames is None else frames
        reach = neighbourhood.tocsr()[rows].tocoo()  # (R, V)
        self.centre, self.nbr = rows[reach.row], reach.col  # one entry per (row, neighbour)
        off = v[self.nbr] - v[self.centre]  # (E, 3)
        self.p = np.stack([(off * e1[self.centre]).sum(1), (off * e2[self.centre]).sum(1)], axis=1)  # (E, 2)
        self.v, self.e1, self.e2, self.rows, self.entry_row = v, e1, e2, rows, reach.row

    def __call__(self, vertex_map: np.ndarray) -> np.ndarray:
        """``(R,)`` int64 in {-1, 0, 1} for the map ``vertex_map (V,)``."""
        v, centre, nbr, rows = self.v, self.centre, self.nbr, self.rows
        missing = vertex_map < 0
        vmap = np.where(missing, 0, vertex_map)  # placeholders; their rows are zeroed below
        img = v[vmap[nbr]] - v[vmap[centre]]  # (E, 3)
        at = vmap[centre]
        q = np.stack([(img * self.e1[at]).sum(1), (img * self.e2[at]).sum(1)], axis=1)  # (E, 2)
        outer = (self.p[:, :, None] * q[:, None, :]).reshape(-1, 4)  # (E, 4)
        m = np.zeros((rows.size, 4))
        np.add.at(m, self.entry_row, outer)
        out = np.sign(m[:, 0] * m[:, 3] - m[:, 1] * m[:, 2]).astype(np.int64)
        if missing.any():
            bad = missing[rows].copy()
            np.logical_or.at(bad, self.entry_row, missing[nbr])
            out[bad] = 0
        return out
