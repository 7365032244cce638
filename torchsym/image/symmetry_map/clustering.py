"""RansaCov clustering of mirror pairs into symmetry axes (thesis Sec. 3.2.2, Eqs. 3.1-3.2).

Every pair ``M_i = (p_i, p_i^m)`` defines an axis ``l_i``: the perpendicular bisector of its
chord. A pair ``M_j`` agrees with ``l_i`` (Eq. 3.1) when its chord is within ``eps_theta``
of the axis normal and its points' distances ``d1, d2`` to the line satisfy
``min(d1, d2) / max(d1, d2) > 1 - eps_d``. Two additions, both measured in
``docs/design/symmetry_map.md``: the points must lie on opposite sides of the line (the
ratio alone also accepts a short chord beside the axis), and ``|d1 - d2| <= tol_px`` is
accepted too (for short chords, keypoint noise of a pixel already breaks the ratio test).
The inlier sets ``I_i`` are then covered by ``k`` of them (maximum coverage, Eq. 3.2):
greedily (the default) or exactly, by the integer program through
``scipy.optimize.milp`` (HiGHS).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import torch

__all__ = ["PairClusters", "agreement_matrix", "cover_exact", "cover_greedy", "pair_lines", "ransacov"]


@dataclasses.dataclass(frozen=True)
class PairClusters:
    """The ``k`` clusters of mirror pairs chosen by RansaCov.

    Attributes:
        members: one ``(M_h,)`` int64 tensor per cluster, indices into the pairs.
        lines: ``(k, 3)`` float axis lines ``(a, b, c)`` (``a x + b y + c = 0``, unit
            ``(a, b)``) of the pair that defines each chosen set.
        covered: pairs covered by the chosen sets.
    """

    members: list[torch.Tensor]
    lines: torch.Tensor
    covered: int


def pair_lines(pairs: torch.Tensor) -> torch.Tensor:
    """Axes ``(P, 3)`` of mirror pairs ``(P, 4)``: the perpendicular bisectors, unit normal along the chord."""
    p, q = pairs[:, :2], pairs[:, 2:]
    chord = p - q
    n = chord / chord.norm(dim=1, keepdim=True).clamp_min(1e-12)  # (P, 2)
    mid = 0.5 * (p + q)
    c = -(n * mid).sum(1)
    return torch.cat([n, c[:, None]], 1)


def agreement_matrix(pairs: torch.Tensor, *, eps_d: float, eps_theta: float, tol_px: float) -> torch.Tensor:
    """``(P, P)`` bool: entry ``(i, j)`` when pair ``j`` agrees with the axis of pair ``i`` (Eq. 3.1)."""
    lines = pair_lines(pairs.double())  # (P, 3)
    p, q = pairs[:, :2].double(), pairs[:, 2:].double()
    chord = p - q
    chord = chord / chord.norm(dim=1, keepdim=True).clamp_min(1e-12)  # (P, 2)
    cos = (lines[:, None, :2] * chord[None]).sum(-1).abs()  # (P, P)
    s1 = lines[:, :2] @ p.T + lines[:, 2:3]  # (P, P) signed distance of p_j to line i
    s2 = lines[:, :2] @ q.T + lines[:, 2:3]
    d1, d2 = s1.abs(), s2.abs()
    ratio = torch.minimum(d1, d2) / torch.maximum(d1, d2).clamp_min(1e-12)
    opposite = s1 * s2 < 0
    agree = (cos > math.cos(math.radians(eps_theta))) & opposite & ((ratio > 1 - eps_d) | ((d1 - d2).abs() <= tol_px))
    return agree | torch.eye(pairs.shape[0], dtype=torch.bool, device=pairs.device)


def cover_greedy(agree: torch.Tensor, k: int, min_support: int = 1) -> list[int]:
    """Greedy maximum coverage: ``k`` rows of ``agree (P, P)`` covering the most columns.

    Each round takes the set adding the most uncovered pairs (ties: the lowest index);
    stops early when no set adds ``min_support`` pairs. The set of a pair that a chosen set
    already covers is not offered again: it is the same axis found twice (without this
    rule a near-copy of the first set, adding the few pairs at the edge of its
    tolerance, would be the second axis).
    """
    chosen: list[int] = []
    uncovered = torch.ones(agree.shape[1], dtype=torch.bool, device=agree.device)
    counts_all = agree.float()
    for _ in range(k):
        gain = (counts_all @ uncovered.float()).masked_fill(~uncovered, -1.0)  # (P,)
        best = int(gain.argmax())
        if gain[best] < min_support:
            break
        chosen.append(best)
        uncovered &= ~agree[best]
    return chosen


def cover_exact(agree: torch.Tensor, k: int, min_support: int = 1) -> list[int]:
    """Maximum coverage by the integer program of Eq. 3.2 (``scipy.optimize.milp``, HiGHS).

    Variables ``y (P,)`` in [0, 1] (pair covered) and ``z (P,)`` binary (set chosen);
    maximise ``sum y`` subject to ``sum z <= k`` and ``y_i <= sum_{j: I_j contains i} z_j``.
    Sets that cover fewer than ``min_support`` pairs are not offered.
    """
    from scipy.optimize import Bounds, LinearConstraint, milp
    from scipy.sparse import csr_matrix, hstack, identity

    a = agree.cpu().numpy()
    sizes = a.sum(1)
    offer = np.nonzero(sizes >= min_support)[0]
    if offer.size == 0:
        return []
    p = a.shape[1]
    cover = csr_matrix(a[offer].T.astype(np.float64))  # (P pairs, S sets): pair i in set j
    n_sets = offer.size
    c = np.concatenate([-np.ones(p), np.zeros(n_sets)])
    rows = hstack([identity(p, format="csr"), -cover]).tocsr()  # y_i - sum z_j <= 0
    budget = csr_matrix(np.concatenate([np.zeros(p), np.ones(n_sets)])[None])
    constraints = [LinearConstraint(rows, -np.inf, 0.0), LinearConstraint(budget, -np.inf, float(k))]
    integrality = np.concatenate([np.zeros(p), np.ones(n_sets)])
    res = milp(c, constraints=constraints, integrality=integrality, bounds=Bounds(0, 1))
    if res.x is None:
        return cover_greedy(agree, k, min_support)
    z = res.x[p:] > 0.5
    chosen = offer[z]
    return [int(i) for i in chosen[np.argsort(-sizes[chosen], kind="stable")]]


def ransacov(
    pairs: torch.Tensor,
    k: int,
    *,
    eps_d: float = 0.03,
    eps_theta: float = 2.0,
    tol_px: float = 1.5,
    cover: str = "greedy",
    min_support: int = 3,
) -> PairClusters:
    """RansaCov: the ``k`` inlier sets of Eq. 3.1 covering the most pairs (Eq. 3.2).

    Args:
        pairs: ``(P, 4)`` mirror pairs ``x1, y1, x2, y2`` in pixels.
        k: clusters wanted; fewer come back when fewer sets reach ``min_support``.
        eps_d, eps_theta, tol_px: the agreement tolerances of Eq. 3.1 (degrees for the angle).
        cover: ``"greedy"`` or ``"milp"``.
        min_support: the fewest pairs in a returned cluster.

    Returns:
        :class:`PairClusters`; a pair covered by two chosen sets belongs to both (a pixel
        may be symmetric about two axes).
    """
    device = pairs.device
    if pairs.shape[0] == 0 or k < 1:
        return PairClusters([], torch.zeros(0, 3, device=device), 0)
    agree = agreement_matrix(pairs, eps_d=eps_d, eps_theta=eps_theta, tol_px=tol_px)  # (P, P)
    chosen = cover_exact(agree, k, min_support) if cover == "milp" else cover_greedy(agree, k, min_support)
    members = [agree[i].nonzero()[:, 0] for i in chosen]
    covered = int(agree[chosen].any(0).sum()) if chosen else 0
    lines = pair_lines(pairs[chosen].double()).to(pairs.dtype) if chosen else torch.zeros(0, 3, device=device)
    return PairClusters(members, lines, covered)
