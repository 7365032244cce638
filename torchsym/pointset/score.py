"""A symmetry score calibrated against chance: how much closer than chance each mirror lands.

For a point ``x_i``, its reflection ``x_i'`` and its mirror ``x_m(i)`` the residual is
``r_i = |x_i' - x_m(i)|``. Two distances say what the residual would be without a symmetry:

- ``nn_i``, the distance from ``x_i`` to its nearest other point: a reflection that lands at
  a random place in a set lands about that far from the nearest point, in any dimension
  (which is why an absolute tolerance, or one set by the median spacing, is not enough: in
  high dimension every distance concentrates and a tolerance either passes or fails all);
- ``d_i = |x_i' - x_i|``, how far the reflection moves the point: a plane that nearly
  contains a point "mirrors" it onto itself with residual ``d_i`` whatever the set (the
  trivial planes of flat or high-dimensional sets).

The point's evidence is ``max(0, 1 - r_i / min(nn_i, d_i))``: 1 for an exact mirror, 0 for a
mirror no closer than chance or than the point itself; ``q`` is its mean over all points,
unmatched points counting 0. Sets whose points repel each other (Harris corners after
non-maximum suppression, blue noise) land a reflection closer than ``nn_i`` to some point by
chance, so the same evidence is measured under random planes through the centroid (each
point's mirror the nearest other point to its reflection), ``q_0`` its mean, and the score is
the chance-corrected ``max(0, (q - q_0) / (1 - q_0))`` (as Cohen's kappa). See
``docs/design/pointsymm.md`` for its values on random and symmetric sets.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["chance_evidence", "mirror_evidence", "nearest_other", "symmetry_score"]

#: random planes of the chance level
N_CHANCE_PLANES = 32


def nearest_other(points: np.ndarray, tree: cKDTree | None = None) -> np.ndarray:
    """``(N,)`` distance from each of ``points (N, D)`` to its nearest other point."""
    x = np.asarray(points, dtype=np.float64)
    tree = cKDTree(x) if tree is None else tree
    return tree.query(x, k=2)[0][:, 1]


def mirror_evidence(
    points: np.ndarray, reflected: np.ndarray, mirror: np.ndarray, *, tree: cKDTree | None = None,
    nn: np.ndarray | None = None,
) -> np.ndarray:
    """Per-point evidence ``max(0, 1 - r_i / min(nn_i, d_i))`` in [0, 1].

    Args:
        points: ``(N, D)`` the points ``x_i``.
        reflected: ``(N, D)`` their reflections ``x_i'``.
        mirror: ``(N,)`` int, the index of each point's mirror, -1 where unmatched.
        tree: a :class:`cKDTree` of ``points`` to reuse.
        nn: :func:`nearest_other` of ``points``, to reuse.

    Returns:
        ``(N,)`` float64; an exact mirror (``r_i = 0``) counts 1 even on the plane.
    """
    x = np.asarray(points, dtype=np.float64)
    y = np.asarray(reflected, dtype=np.float64)
    n = x.shape[0]
    out = np.zeros(n)
    if n < 2:
        return out
    nn = nearest_other(x, tree) if nn is None else np.asarray(nn)  # (N,)
    matched = np.asarray(mirror) >= 0
    m = np.asarray(mirror)[matched]
    r = np.linalg.norm(y[matched] - x[m], axis=1)
    scale = np.minimum(nn[matched], np.linalg.norm(y[matched] - x[matched], axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(r > 0.0, r / scale, 0.0)
    out[matched] = np.clip(1.0 - np.nan_to_num(ratio, nan=1.0, posinf=1.0), 0.0, 1.0)
    return out


def chance_evidence(
    points: np.ndarray, rng: np.random.Generator, *, n_planes: int = N_CHANCE_PLANES, tree: cKDTree | None = None,
    nn: np.ndarray | None = None,
) -> float:
    """``q_0``: the mean :func:`mirror_evidence` of ``points (N, D)`` under ``n_planes`` planes
    through the centroid with normals uniform on the sphere (from ``rng``), each point's mirror
    the nearest other point to its reflection."""
    x = np.asarray(points, dtype=np.float64)
    n, d = x.shape
    if n < 2:
        return 0.0
    tree = cKDTree(x) if tree is None else tree
    nn = nearest_other(x, tree) if nn is None else nn
    centre = x.mean(0)
    total = 0.0
    for _ in range(n_planes):
        normal = rng.standard_normal(d)
        normal /= np.linalg.norm(normal)
        y = x - 2.0 * ((x - centre) @ normal)[:, None] * normal  # (N, D)
        _, idx = tree.query(y, k=2)
        mirror = np.where(idx[:, 0] != np.arange(n), idx[:, 0], idx[:, 1])
        total += float(mirror_evidence(x, y, mirror, tree=tree, nn=nn).mean())
    return total / n_planes


def symmetry_score(
    points: np.ndarray, reflected: np.ndarray, mirror: np.ndarray, rng: np.random.Generator, *,
    tree: cKDTree | None = None,
) -> float:
    """The chance-corrected score ``max(0, (q - q_0) / (1 - q_0))`` in [0, 1]: ``q`` the mean
    :func:`mirror_evidence` of the found plane, ``q_0`` that of random planes
    (:func:`chance_evidence`, drawn from ``rng``). 1 for an exact symmetry, about 0 without one."""
    x = np.asarray(points, dtype=np.float64)
    if x.shape[0] < 2:
        return 0.0
    tree = cKDTree(x) if tree is None else tree
    nn = nearest_other(x, tree)
    q = float(mirror_evidence(x, reflected, mirror, tree=tree, nn=nn).mean())
    q0 = min(chance_evidence(x, rng, tree=tree, nn=nn), 1.0 - 1e-12)
    return float(min(1.0, max(0.0, (q - q0) / (1.0 - q0))))
