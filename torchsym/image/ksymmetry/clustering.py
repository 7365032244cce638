"""k-symmetry clustering of mirror pairs (thesis Sec. 2.2.2-2.2.3, Algorithm 1).

For axis ``u = (a, b, c)``, ``|u| = 1``, a pair ``(x^l, x^r)`` costs
``(u . [x^m, y^m, 1])^2 + (u . [y^r - y^l, x^l - x^r, 0])^2`` (Eq. 2.5): the midpoint on
the axis (Eq. 2.3) and the chord perpendicular to it (Eq. 2.2). A cluster's update is the
eigenvector of the smallest eigenvalue of ``B_i = X_i^T X_i + Y_i^T Y_i`` (Eq. 2.7-2.8).
Coordinates are centred on the image and scaled by half its longer side.
"""

from __future__ import annotations

import dataclasses
import math

import torch

from torchsym.features.mirror_pairs import elbow_index
from torchsym.image.lines import pair_rows

__all__ = ["ClusteringRun", "cluster_for_each_k", "initial_axes", "inlier_matrix", "ksymmetry_clustering"]


def _pair_costs(u: torch.Tensor, x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    """``(P, K)`` cost of each pair under each axis ``u (K, 3)``."""
    return (x @ u.T) ** 2 + (y @ u.T) ** 2


def inlier_matrix(left: torch.Tensor, right: torch.Tensor, eps_theta: float, eps_d: float) -> torch.Tensor:
    """``(P, P)`` bool: pair i (row) is an inlier of the axis of pair j (column), Sec. 2.2.3.

    ``left, right (P, 2)``; ``eps_theta`` in degrees, ``eps_d`` the distance-ratio tolerance.
    """
    chord = right - left  # (P, 2)
    length = chord.norm(dim=1).clamp_min(1e-12)
    normal = chord / length[:, None]  # unit normal of each candidate axis, (P, 2)
    mid = 0.5 * (left + right)
    off = -(normal * mid).sum(1)  # (P,)
    direction = torch.stack([-normal[:, 1], normal[:, 0]], 1)  # axis directions (P, 2)
    cos_to_axis = (chord @ direction.T).abs() / length[:, None]  # (P_i, P_j): |cos| of chord_i to axis_j
    perpendicular = cos_to_axis < math.sin(math.radians(eps_theta))
    dl = left @ normal.T + off[None]  # (P_i, P_j) signed distances
    dr = right @ normal.T + off[None]
    ratio = dl.abs() / dr.abs().clamp_min(1e-12)
    balanced = (ratio > 1 - eps_d) & (ratio < 1 + eps_d) & (dl * dr < 0)
    return perpendicular & balanced


def ksymmetry_clustering(
    left: torch.Tensor,
    right: torch.Tensor,
    init: torch.Tensor,
    *,
    max_iters: int = 50,
    outlier_cost: float | None = None,
) -> tuple[torch.Tensor, torch.Tensor, float, bool, int]:
    """Algorithm 1 (k-symmetry) from the starting axes ``init (K, 3)``.

    Args:
        left: ``(P, 2)`` first points of the MSPPs.
        right: ``(P, 2)`` their mirror points.
        init: ``(K, 3)`` starting axes ``(a, b, c)``.
        max_iters: the most assignment/update rounds (default 50).
        outlier_cost: truncation of a pair's cost; None is the thesis's cost (Eq. 2.5).

    Returns:
        ``axes (K, 3)`` with ``|u| = 1``, ``labels (P,)`` (-1: outlier), the cost,
        ``converged`` (assignments stopped changing) and the number of rounds.
    """
    x, y = pair_rows(left.double(), right.double())
    # per-pair contributions x x^T + y y^T to B_i (Eq. 2.7), formed once: each round is one
    # scatter-add over the labels and one batched eigh for all K clusters
    outer = (x[:, :, None] * x[:, None, :] + y[:, :, None] * y[:, None, :]).reshape(-1, 9)  # (P, 9)
    u = init.double() / init.double().norm(dim=1, keepdim=True)
    k = u.shape[0]
    labels = torch.full((left.shape[0],), -2, dtype=torch.int64)
    converged, it = False, 0
    for it in range(1, max_iters + 1):
        cost = _pair_costs(u, x, y)  # (P, K)
        best, new = cost.min(1)
        if outlier_cost is not None:
            new = torch.where(best > outlier_cost, torch.full_like(new, -1), new)
        if torch.equal(new, labels):
            converged = True
            break
        labels = new
        assigned = labels >= 0
        lab = labels[assigned]
        b = torch.zeros(k, 9, dtype=torch.float64).index_add_(0, lab, outer[assigned]).reshape(k, 3, 3)  # B_i
        size = torch.bincount(lab, minlength=k)
        _, vecs = torch.linalg.eigh(b)  # (K, 3, 3), ascending eigenvalues
        u = torch.where((size >= 2)[:, None], vecs[:, :, 0], u)  # an empty cluster keeps its axis
    cost = _pair_costs(u, x, y).min(1).values
    if outlier_cost is not None:
        cost = cost.clamp_max(outlier_cost)
    return u, labels, float(cost.sum()), converged, it


def initial_axes(inliers: torch.Tensor, max_axes: int) -> list[int]:
    """Indices of up to ``max_axes`` distinct starting pairs (Sec. 2.2.3).

    The pair whose axis has the most inliers (``inliers (P, P)``, :func:`inlier_matrix`)
    first, then the best among pairs that are no inlier of an axis already chosen.
    """
    counts = inliers.sum(0).double()  # inliers per candidate axis
    available = torch.ones(inliers.shape[0], dtype=torch.bool)
    starts: list[int] = []
    while len(starts) < max_axes and bool(available.any()):
        j = int(torch.where(available, counts, torch.full_like(counts, -1.0)).argmax())
        if counts[j] < 1:
            break
        starts.append(j)
        available &= ~inliers[:, j]
        available[j] = False
    return starts


@dataclasses.dataclass(frozen=True)
class ClusteringRun:
    """The clustering chosen at the elbow of the cost curve.

    Attributes:
        axes: ``(k, 3)`` float64 axes in normalised coordinates, ``|u| = 1``.
        labels: ``(P,)`` int64 cluster of each pair, -1 for outliers.
        k: the number of axes chosen.
        cost_curve: the cost for ``k = 1, 2, ...``.
        converged: the chosen run's assignments stopped changing.
        iterations: the chosen run's rounds.
    """

    axes: torch.Tensor
    labels: torch.Tensor
    k: int
    cost_curve: list[float]
    converged: bool
    iterations: int


def cluster_for_each_k(
    left: torch.Tensor, right: torch.Tensor, starts: list[int], *, max_iters: int, outlier_cost: float | None
) -> ClusteringRun:
    """Algorithm 1 for ``k = 1 .. len(starts)`` from the axes of the pairs ``starts``;
    ``k`` at the elbow of the cost curve (Fig. 2.1e; all when fewer than 3 runs)."""
    cand = torch.cat([torch.nn.functional.normalize(right - left, dim=1), torch.zeros(left.shape[0], 1, dtype=torch.float64)], 1)
    cand[:, 2] = -(cand[:, :2] * 0.5 * (left + right)).sum(1)
    runs, curve = [], []
    for k in range(1, len(starts) + 1):
        run = ksymmetry_clustering(left, right, cand[starts[:k]], max_iters=max_iters, outlier_cost=outlier_cost)
        runs.append(run)
        curve.append(run[2])
    k_best = elbow_index(torch.tensor(curve)) + 1 if len(curve) >= 3 else len(runs)
    u, labels, _, converged, n_iter = runs[k_best - 1]
    return ClusteringRun(u, labels, k_best, curve, converged, n_iter)
