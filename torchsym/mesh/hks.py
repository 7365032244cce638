"""Heat kernel signature and its feature points (thesis Sec. 6.2.4, after Sun et al. 2009).

``HKS(x, t) = sum_i exp(-lambda_i t) phi_i(x)^2`` over the first ``k`` eigenpairs.
Feature points are the vertices where the HKS at the time ``t_h = 4 ln 10 / lambda_2``
is larger than everywhere in their 2-ring.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from torchsym.errors import InputShapeError

__all__ = ["heat_kernel_signature", "hks_feature_points", "hks_times"]


def hks_times(evals: np.ndarray, n_times: int = 50) -> np.ndarray:
    """``n_times`` times sampled logarithmically in ``[4 ln 10 / lambda_k, 4 ln 10 / lambda_2]``.

    Args:
        evals: ``(k,)`` ascending eigenvalues with ``k >= 2`` and ``lambda_2 > 0``.
        n_times: the number of time scales ``h``.

    Returns:
        ``(n_times,)`` ascending times.
    """
    evals = np.asarray(evals, dtype=np.float64)
    if evals.ndim != 1 or evals.shape[0] < 2 or not evals[1] > 0:
        raise InputShapeError(f"evals: expected (k,) ascending with k >= 2 and evals[1] > 0, got {evals[:3]}")
    t_min = 4.0 * math.log(10.0) / evals[-1]
    t_max = 4.0 * math.log(10.0) / evals[1]
    return np.geomspace(t_min, t_max, n_times)


def heat_kernel_signature(
    evals: np.ndarray, evecs: np.ndarray, times: np.ndarray, *, scaled: bool = True
) -> np.ndarray:
    """HKS of every vertex at every time, ``(V, T)``.

    Args:
        evals: ``(k,)`` eigenvalues.
        evecs: ``(V, k)`` mass-orthonormal eigenvectors.
        times: ``(T,)`` diffusion times.
        scaled: divide each time's column by the heat trace ``sum_i exp(-lambda_i t)``,
            which makes signatures comparable across scales (Sun et al.).
    """
    decay = np.exp(-np.outer(evals, times))  # (k, T)
    hks = (evecs**2) @ decay  # (V, T)
    if scaled:
        hks = hks / decay.sum(axis=0, keepdims=True)  # (V, T)
    return hks


def hks_feature_points(values: np.ndarray, neighbourhood: sp.csr_matrix) -> np.ndarray:
    """Vertices whose value is strictly larger than at every vertex of their neighbourhood.

    Args:
        values: ``(V,)`` function on the vertices (e.g. the HKS at one time).
        neighbourhood: ``(V, V)`` 0/1 matrix of each vertex's neighbours, e.g. its 2-ring
            (:func:`~torchsym.mesh.operators.ring_neighbourhood`).

    Returns:
        ``(d,)`` int64 vertex indices, sorted by decreasing value.
    """
    nb = neighbourhood.tocsr()
    counts = np.diff(nb.indptr)  # (V,)
    rows = np.repeat(np.arange(nb.shape[0]), counts)  # (nnz,)
    larger_neighbour = np.zeros(nb.shape[0], dtype=bool)  # (V,)
    np.logical_or.at(larger_neighbour, rows, values[nb.indices] >= values[rows])
    maxima = np.flatnonzero(~larger_neighbour & (counts > 0))  # (d,)
    return maxima[np.argsort(-values[maxima], kind="stable")].astype(np.int64)
