"""Reflection symmetry axes by k-symmetry clustering of mirror pairs (thesis Sec. 2.2).

Pipeline (thesis Fig. 2.1): SIFT keypoints and mirrored descriptors (Sec. 2.2.1) ->
mirror symmetric pixel pairs (MSPPs) by mutual ``k1`` nearest neighbours (Def. 2.2.1) ->
k-symmetry clustering (Algorithm 1, cost Eq. 2.5) for ``k = 1 .. max_axes`` -> ``k`` at
the elbow of the cost curve (Fig. 2.1e).

For axis ``u = (a, b, c)``, ``|u| = 1``, a pair ``(x^l, x^r)`` costs
``(u . [x^m, y^m, 1])^2 + (u . [y^r - y^l, x^l - x^r, 0])^2``: the midpoint on the axis
(Eq. 2.3) and the chord perpendicular to it (Eq. 2.2). The update of a cluster is the
eigenvector of the smallest eigenvalue of ``B_i = X_i^T X_i + Y_i^T Y_i`` (Eq. 2.7-2.8;
``B_i`` is symmetric, so it is also the smallest eigenvector of ``B_i^T B_i``).

Implementation choices the thesis leaves open, stated here:

- Coordinates are centred on the image and divided by half its longer side before
  clustering, so that ``|u| = 1`` weighs ``a, b`` and ``c`` alike whatever the image size;
  lines are returned in pixels.
- ``outlier_cost`` truncates each pair's cost (a pair farther than that from every axis
  is assigned to none and costs ``outlier_cost``). Photographs give many false MSPPs;
  the thesis's untruncated cost (``outlier_cost=None``) lets them drag the axes.
- Initialisation picks the candidate axis with the most inliers (tolerances
  ``eps_theta``, ``eps_d``), then the next best among candidates that are not inliers of
  an axis already chosen, so the ``k`` starting axes are distinct.

Speed (issue target: at most 1 s per 640-px photograph). SIFT is computed once per image;
the mirrored descriptors are the exact bin permutation of :func:`torchsym.features.sift.mirror_descriptors`,
not a second description pass. The update step of Algorithm 1 forms every pair's
``x x^T + y y^T`` once and builds all ``B_i`` by one scatter-add per round, with one
batched ``eigh``; the former per-cluster loop of masked gathers and ``(3, 3)`` solves ran
``k (k + 1) / 2`` clusters x up to 50 rounds of small torch calls and took up to 4 s on a
loaded machine. The result is the same algorithm (summation order aside).
"""

from __future__ import annotations

import math
import time

import torch
from torch import nn

from torchsym.core.checks import check_image, check_int, check_positive
from torchsym.core.registry import register_solver
from torchsym.errors import InputShapeError
from torchsym.features.mirror_pairs import (
    choose_k1,
    elbow_index,
    mirror_distance_matrix,
    mutual_knn_pairs,
)
from torchsym.features.sift import detect_sift
from torchsym.image.axes import (
    ReflectionAxesResult,
    build_result,
    empty_result,
    run_batched,
)

__all__ = ["KSymmetryDetector", "ksymmetry_axes", "ksymmetry_clustering"]


def _rows(left: torch.Tensor, right: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    mid = 0.5 * (left + right)  # (P, 2)
    x = torch.cat([mid, torch.ones_like(mid[:, :1])], 1)  # (P, 3) rows of X (Eq. 2.6)
    y = torch.stack([right[:, 1] - left[:, 1], left[:, 0] - right[:, 0], torch.zeros_like(mid[:, 0])], 1)  # (P, 3) rows of Y
    return x, y


def _pair_costs(u: torch.Tensor, x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    """``(P, K)`` cost of each pair under each axis ``u (K, 3)``."""
    return (x @ u.T) ** 2 + (y @ u.T) ** 2


def _inlier_matrix(left: torch.Tensor, right: torch.Tensor, eps_theta: float, eps_d: float) -> torch.Tensor:
    """``(P, P)`` bool: pair i (row) is an inlier of the axis of pair j (column), Sec. 2.2.3."""
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
    max_iter: int = 50,
    outlier_cost: float | None = None,
) -> tuple[torch.Tensor, torch.Tensor, float, bool, int]:
    """Algorithm 1 (k-symmetry) from the starting axes ``init (K, 3)``.

    Args:
        left: ``(P, 2)`` first points of the MSPPs.
        right: ``(P, 2)`` their mirror points.
        init: ``(K, 3)`` starting axes ``(a, b, c)``.
        max_iter: the most assignment/update rounds.
        outlier_cost: truncation of a pair's cost; None is the thesis's cost (Eq. 2.5).

    Returns:
        ``axes (K, 3)`` with ``|u| = 1``, ``labels (P,)`` (-1: outlier), the cost,
        ``converged`` (assignments stopped changing) and the number of rounds.
    """
    x, y = _rows(left.double(), right.double())
    # per-pair contributions x x^T + y y^T to B_i (Eq. 2.7), formed once: each update
    # round is then one scatter-add over the labels and one batched eigh for all K
    # clusters, not a Python loop of masked gathers per cluster
    outer = (x[:, :, None] * x[:, None, :] + y[:, :, None] * y[:, None, :]).reshape(-1, 9)  # (P, 9)
    u = init.double() / init.double().norm(dim=1, keepdim=True)
    k = u.shape[0]
    labels = torch.full((left.shape[0],), -2, dtype=torch.int64)
    converged, it = False, 0
    for it in range(1, max_iter + 1):
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


def ksymmetry_axes(
    image: torch.Tensor,
    *,
    num_features: int = 1000,
    k1: int | None = None,
    max_axes: int = 5,
    eps_theta: float = 2.0,
    eps_d: float = 0.05,
    max_iter: int = 50,
    outlier_cost: float | None = 0.0025,
    min_pair_distance: float = 5.0,
    min_support: int = 3,
) -> ReflectionAxesResult:
    """Reflection symmetry axes of one image by k-symmetry clustering (thesis Sec. 2.2).

    Args:
        image: ``(C, H, W)`` or ``(1, C, H, W)`` float image in [0, 1], ``C`` in {1, 3}.
        num_features: the most SIFT keypoints (Sec. 2.2.1).
        k1: neighbours in the mutual nearest-neighbour rule (Def. 2.2.1); None chooses it
            at the elbow of the pair count (see :func:`torchsym.features.choose_k1`).
        max_axes: the largest ``k`` tried; ``k`` is the elbow of the cost curve.
        eps_theta: angle tolerance in degrees of the inlier test (Sec. 2.2.3, 2 deg).
        eps_d: distance-ratio tolerance of the inlier test (Sec. 2.2.3, 0.05).
        max_iter: the most assignment/update rounds of Algorithm 1.
        outlier_cost: truncation of a pair's cost in normalised coordinates (module
            docstring); None gives the thesis's untruncated Eq. 2.5.
        min_pair_distance: pairs of keypoints closer than this (pixels) are not paired.
        min_support: axes supported by fewer pairs are dropped.

    Returns:
        :class:`~torchsym.image.axes.ReflectionAxesResult`, scores = pairs per axis;
        ``info`` holds ``k1``, ``cost_curve`` and ``k``.

    Example:
        >>> img = torch.zeros(1, 64, 64); img[:, 20:44, 16:48] = torch.rand(1, 24, 16).repeat(1, 1, 2)
        >>> ksymmetry_axes(img).axes.shape[1]
        4
    """
    img = check_image(image, "image", min_size=16)
    if img.shape[0] != 1:
        raise InputShapeError(f"image: expected one image (C, H, W) or (1, C, H, W), got {tuple(img.shape)}")
    num_features = check_int(num_features, "num_features", minimum=1)
    max_axes = check_int(max_axes, "max_axes", minimum=1)
    max_iter = check_int(max_iter, "max_iter", minimum=1)
    min_support = check_int(min_support, "min_support", minimum=1)
    eps_theta = check_positive(eps_theta, "eps_theta")
    eps_d = check_positive(eps_d, "eps_d")
    min_pair_distance = check_positive(min_pair_distance, "min_pair_distance", allow_zero=True)
    if k1 is not None:
        k1 = check_int(k1, "k1", minimum=1)
    if outlier_cost is not None:
        outlier_cost = check_positive(outlier_cost, "outlier_cost")
    h, w = int(img.shape[-2]), int(img.shape[-1])
    t0 = time.perf_counter()
    feats = detect_sift(img, num_features=num_features)
    if len(feats) < 2:
        return empty_result(h, w, "ksymmetry", k1=k1, reason="fewer than 2 keypoints")
    dist = mirror_distance_matrix(feats.descriptors, feats.points, min_distance=min_pair_distance)
    if k1 is None:
        k1 = choose_k1(dist)
    idx = mutual_knn_pairs(dist, k1)  # (P, 2)
    pts = feats.points.double()
    pairs = torch.cat([pts[idx[:, 0]], pts[idx[:, 1]]], 1)  # (P, 4) pixels
    if idx.shape[0] < min_support:
        return empty_result(h, w, "ksymmetry", pairs=pairs, k1=k1, reason="too few mirror pairs")
    centre = torch.tensor([(w - 1) / 2, (h - 1) / 2], dtype=torch.float64)
    scale = max(h, w) / 2.0
    left = (pairs[:, :2] - centre) / scale  # (P, 2) normalised
    right = (pairs[:, 2:] - centre) / scale
    inl = _inlier_matrix(left, right, eps_theta, eps_d)  # (P, P)
    counts = inl.sum(0).double()  # inliers per candidate axis
    available = torch.ones(idx.shape[0], dtype=torch.bool)
    starts = []
    while len(starts) < max_axes and bool(available.any()):
        j = int(torch.where(available, counts, torch.full_like(counts, -1.0)).argmax())
        if counts[j] < 1:
            break
        starts.append(j)
        available &= ~inl[:, j]
        available[j] = False
    if not starts:
        return empty_result(h, w, "ksymmetry", pairs=pairs, k1=k1, reason="no candidate axis")
    cand = torch.cat([torch.nn.functional.normalize(right - left, dim=1), torch.zeros(left.shape[0], 1, dtype=torch.float64)], 1)
    cand[:, 2] = -(cand[:, :2] * 0.5 * (left + right)).sum(1)
    runs, curve = [], []
    for k in range(1, len(starts) + 1):
        run = ksymmetry_clustering(left, right, cand[starts[:k]], max_iter=max_iter, outlier_cost=outlier_cost)
        runs.append(run)
        curve.append(run[2])
    k_best = elbow_index(torch.tensor(curve)) + 1 if len(curve) >= 3 else len(runs)
    u, labels, _, converged, n_iter = runs[k_best - 1]
    lines, supports, scores = [], [], []
    for i in range(u.shape[0]):
        sup = (labels == i).nonzero().flatten()
        if sup.numel() < min_support:
            continue
        a, b, c = u[i]
        line = torch.stack([a, b, c * scale - a * centre[0] - b * centre[1]])  # back to pixels
        line = line / line[:2].norm().clamp_min(1e-12)
        lines.append(line)
        supports.append(sup)
        scores.append(float(sup.numel()))
    return build_result(
        lines, supports, scores, pairs, h, w, "ksymmetry", converged=converged,
        k1=k1, k=k_best, cost_curve=curve, n_iter=n_iter, seconds=time.perf_counter() - t0,
    )


@register_solver("ksymmetry", kind="image")
class KSymmetryDetector(nn.Module):
    """Reflection axes by SIFT mirror pairs and k-symmetry clustering (thesis Sec. 2.2).

    Module form of :func:`ksymmetry_axes`; see it for every setting. ``forward(image)``
    takes ``(C, H, W)`` or ``(B, C, H, W)`` float in [0, 1] and returns a
    :class:`~torchsym.image.axes.ReflectionAxesResult` (``B = 1``) or a
    :class:`~torchsym.image.axes.ReflectionAxesBatch`.
    """

    def __init__(
        self,
        *,
        num_features: int = 1000,
        k1: int | None = None,
        max_axes: int = 5,
        eps_theta: float = 2.0,
        eps_d: float = 0.05,
        max_iter: int = 50,
        outlier_cost: float | None = 0.0025,
        min_pair_distance: float = 5.0,
        min_support: int = 3,
    ) -> None:
        super().__init__()
        self.settings = dict(
            num_features=check_int(num_features, "num_features", minimum=1),
            k1=None if k1 is None else check_int(k1, "k1", minimum=1),
            max_axes=check_int(max_axes, "max_axes", minimum=1),
            eps_theta=check_positive(eps_theta, "eps_theta"),
            eps_d=check_positive(eps_d, "eps_d"),
            max_iter=check_int(max_iter, "max_iter", minimum=1),
            outlier_cost=None if outlier_cost is None else check_positive(outlier_cost, "outlier_cost"),
            min_pair_distance=check_positive(min_pair_distance, "min_pair_distance", allow_zero=True),
            min_support=check_int(min_support, "min_support", minimum=1),
        )

    def extra_repr(self) -> str:
        return ", ".join(f"{k}={v}" for k, v in self.settings.items())

    def forward(self, image: torch.Tensor):
        return run_batched(ksymmetry_axes, image, self.settings)
