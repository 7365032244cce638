"""Functional maps of a mesh onto itself: conversions, fits and ZoomOut (like pyFM's ``convert`` and ``zoomout``).

``Phi (V, k)`` holds area-orthonormal Laplace-Beltrami eigenfunctions and ``A`` the lumped
vertex areas ``(V,)``. A point map ``T (V,)`` has the functional map ``C = Phi^T A Phi[T]``
``(k, k)`` (column ``j`` the coefficients of ``phi_j o T``); ``C`` gives back the point map
sending each vertex to the row of ``Phi`` nearest its row of ``Phi C``. ZoomOut (Melzi et
al. 2019) alternates the two in a growing basis. Thesis Sec. 6.2.5-6.2.7.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from scipy.spatial import cKDTree

from torchsym.core.parallel import thread_budget
from torchsym.mesh.nearest import Nearest, SampledSearch, nearest_profiles

__all__ = [
    "fit_functional",
    "functional_to_pointwise",
    "involution_defect",
    "map_consistency",
    "map_quality",
    "nearest_involution",
    "pointwise_to_functional",
    "zoomout",
    "zoomout_fit",
]


def pointwise_to_functional(phi: np.ndarray, area: np.ndarray, vertex_map: np.ndarray) -> np.ndarray:
    """The functional map ``C = Phi^T A Phi[T]`` ``(k, k)`` of the point map ``vertex_map (V,)``.

    ``phi``: ``(V, k)`` area-orthonormal eigenfunctions; ``area``: ``(V,)`` lumped areas.
    """
    return phi.T @ (area[:, None] * phi[vertex_map])


def functional_to_pointwise(evecs: np.ndarray, fmap: np.ndarray) -> np.ndarray:
    """The point map ``(V,)`` of a self functional map ``fmap (k, k)``: vertex ``i`` goes to the row of ``Phi C^T`` nearest ``Phi[i]``."""
    return cKDTree(evecs @ fmap.T).query(evecs, k=1, workers=thread_budget())[1].astype(np.int64)


def fit_functional(phi_rows: np.ndarray, phi_image: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Area-weighted least-squares ``C (k, k)`` with ``Phi[rows] C ~ Phi[T(rows)]``.

    ``phi_rows``, ``phi_image``: ``(S, k)``; ``weights``: ``(S,)`` areas. On every vertex
    this is :func:`pointwise_to_functional`; on a sample it also corrects for the sampled
    basis not being orthonormal.
    """
    root = np.sqrt(weights)[:, None]
    return np.linalg.lstsq(root * phi_rows, root * phi_image, rcond=None)[0]


def involution_defect(fmap: np.ndarray) -> float:
    """``|C^T C - I|_F + |C C - I|_F``: 0 for the functional map of an isometric involution."""
    eye = np.eye(fmap.shape[0])
    return float(np.linalg.norm(fmap.T @ fmap - eye) + np.linalg.norm(fmap @ fmap - eye))


def map_quality(evecs: np.ndarray, area: np.ndarray, vertex_map: np.ndarray) -> float:
    """:func:`involution_defect` of the functional map of ``vertex_map (V,)`` (0 for an exact
    intrinsic symmetry, and for the identity, which callers must rule out)."""
    return involution_defect(pointwise_to_functional(evecs, area, vertex_map))


def nearest_involution(fmap: np.ndarray) -> np.ndarray:
    """The symmetric orthogonal matrix nearest ``fmap (k, k)`` (Frobenius norm): ``Q sign(L) Q^T``
    with ``(C + C^T) / 2 = Q L Q^T`` (an eigenvalue 0 gets the sign +1)."""
    lam, q = np.linalg.eigh(0.5 * (fmap + fmap.T))
    return (q * np.where(lam >= 0, 1.0, -1.0)) @ q.T


def consistency(emb: np.ndarray, signs: np.ndarray, rows: np.ndarray, target: np.ndarray) -> float:
    """:func:`map_consistency` of the map that sends ``rows (S,)`` to ``target (S,)``."""
    fitted = np.linalg.lstsq(emb[rows], emb[target], rcond=None)[0]  # (k, k)
    return float(np.linalg.norm(fitted - np.diag(signs)))


def map_consistency(tree: cKDTree, emb: np.ndarray, signs: np.ndarray, rows: np.ndarray, approx: float = 0.0) -> float:
    """How far the point map of ``C = diag(signs)`` is from realising ``C`` itself (Frobenius norm).

    The map sends vertex ``i`` to the row of ``emb (V, k)`` (the tree's points) nearest
    ``signs * emb[i]`` (Sec. 6.2.7); its functional map is fitted by least squares on
    ``rows (S,)``. ``approx``: the search's ``eps`` (images up to ``1 + approx`` times too far).
    """
    _, target = tree.query(emb[rows] * signs, k=1, eps=approx, workers=thread_budget())
    return consistency(emb, signs, rows, target)


def zoomout_fit(phi: np.ndarray, area: np.ndarray, rows: np.ndarray, image: np.ndarray, factor=None) -> np.ndarray:
    """One fit of ZoomOut: ``C (kk, kk)`` with ``Phi[rows] C ~ Phi[image]``.

    ``phi``: ``(V, kk)``; ``rows``, ``image``: ``(S,)`` vertices. ``factor``: None for the
    plain area-weighted fit, or ``scipy.linalg.cho_factor`` of penalised normal equations
    in ``vec(C)`` (row major) whose data term is ``G kron I``, ``G = Phi[rows]^T A Phi[rows] / a``.
    """
    if factor is None:
        return fit_functional(phi[rows], phi[image], area[rows])  # (kk, kk)
    kk = phi.shape[1]
    weights = area[rows] / area[rows].sum()
    rhs = phi[rows].T @ (weights[:, None] * phi[image])  # (kk, kk)
    return scipy.linalg.cho_solve(factor, rhs.reshape(-1)).reshape(kk, kk)


def zoomout(
    big: np.ndarray, area: np.ndarray, rows: np.ndarray, image: np.ndarray, ks: np.ndarray, search: SampledSearch,
    involution: bool = True, oriented: dict | None = None, brute: bool = False,
) -> tuple[np.ndarray, np.ndarray | None]:
    """ZoomOut on the vertex sample ``rows (S,)`` from the point map ``image (S,)``.

    Each round fits ``C`` in the first ``kk`` of ``ks`` columns of ``big (V, K)`` and maps
    each sampled vertex to the nearest row of ``Phi`` (among ``search``'s targets) to its
    row of ``Phi C``. With ``involution``, ``C`` is first averaged with the fit of the
    inverse map (each sample's preimage) and replaced by :func:`nearest_involution`.
    ``oriented``: ``{kk: factor}`` of a penalised fit (:func:`zoomout_fit`). ``brute``:
    float32 brute-force searches (:func:`~torchsym.mesh.nearest.nearest_profiles`), each
    preimage among the sample only.

    Returns:
        The sample's last image ``(S,)`` and the last ``C (kk, kk)`` (None when ``ks`` is empty).
    """
    fitted = None
    for kk in ks:
        phi = big[:, :kk]  # (V, kk)
        factor = None if oriented is None else oriented[int(kk)]
        fitted = zoomout_fit(phi, area, rows, image, factor)
        if involution:
            # the inverse map: for an involution T^-1 = T, so both fit the same C
            if brute:
                pre = rows[nearest_profiles(phi[rows], phi[rows] @ fitted)]
            else:
                # (C is near an orthogonal matrix, which keeps the spacing of the points)
                pre = search.to_vertices(Nearest(search.sample_points(phi) @ fitted, search.sample(kk).spacing).query(phi[rows]))
            fitted = nearest_involution(0.5 * (fitted + zoomout_fit(phi, area, rows, pre, factor)))
        if brute:
            image = search.to_vertices(nearest_profiles(phi[rows] @ fitted, search.sample_points(phi)))
        else:
            image = search.nearest(kk, phi[rows] @ fitted)
    return image, fitted
