"""The symmetry plane of mirror pairs with outlier rejection (thesis Sec. 5.3.3-5.3.4).

Every pair defines a plane, its perpendicular bisector. For each such plane ``pi_j`` the
loop of Sec. 5.3.4 counts the pairs it explains: the two points on opposite sides, at
distances whose ratio lies within ``1 +- eps_d``, the chord within ``eps_theta`` of the
normal. The plane explaining most pairs wins, and the consensus plane is fitted to its
inliers by Eq. 5.6. All planes are scored at once (a pairs-by-planes table, in chunks).

Departures from the text, each because the text as printed fails on real pairs:
* The distance ratio compares absolute residuals: points on opposite sides have residuals
  of opposite signs, so the printed ratio ``r_l / r_r`` is negative and never within
  ``1 +- eps_d``.
* The chord-normal angle uses ``|cos|``: the chord's direction depends on the pair's
  order, which carries no meaning.
* The consensus plane minimises Eq. 5.6's energy under ``|n| = 1`` rather than Eq. 5.7's
  ``|pi| = 1``, which depends on the placement of the origin
  (:func:`torchsym.geometry.plane_from_pairs`).
* A confidence the thesis does not give: the winner's inlier count over that of the best
  plane at least ``margin_angle`` degrees away. A scene without symmetry has several
  planes explaining about as many chance pairs.
"""

from __future__ import annotations

import dataclasses
import math

import torch
import torch.nn.functional as F

from torchsym.geometry.reflection import canonical_sign, plane_from_pairs

__all__ = ["Consensus", "consensus_plane", "inlier_table", "pair_planes", "plane_votes"]

#: planes scored at once
CHUNK = 1024


def pair_planes(left: torch.Tensor, right: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """The perpendicular bisector of each pair: ``normal (S, 3)`` and ``offset (S,)``."""
    u = right - left  # (S, 3)
    n = u / u.norm(dim=1, keepdim=True)
    b = -(n * (0.5 * (left + right))).sum(1)
    return n, b


def _centred(left, right, normals, offsets):
    """Pairs and planes in float32 coordinates centred at the pairs' mean."""
    centre = 0.5 * (left + right).double().mean(0)
    offsets = (offsets.double() + normals.double() @ centre).float()
    return (left.double() - centre).float(), (right.double() - centre).float(), normals.float(), offsets


def _inlier(left, right, n, b, eps_d):
    """Sec. 5.3.4's side and distance-ratio tests for pairs against planes, elementwise."""
    rl = (left * n).sum(-1) + b
    rr = (right * n).sum(-1) + b
    ratio = rl.abs() / rr.abs().clamp_min(torch.finfo(rr.dtype).tiny)
    return (rl * rr < 0) & (ratio > 1 - eps_d) & (ratio < 1 + eps_d)


def inlier_table(
    left: torch.Tensor, right: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor, eps_d: float, eps_theta: float
) -> torch.Tensor:
    """``(K, S)`` bool: pair ``i`` is an inlier of plane ``k`` (Sec. 5.3.4's test)."""
    left, right, normals, offsets = _centred(left, right, normals, offsets)
    u = F.normalize(right - left, dim=1)  # (S, 3)
    along = (normals @ u.T).abs() > math.cos(math.radians(eps_theta))  # (K, S)
    return along & _inlier(left[None], right[None], normals[:, None], offsets[:, None], eps_d)


def plane_votes(
    left: torch.Tensor, right: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor, eps_d: float, eps_theta: float
) -> torch.Tensor:
    """``(K,)`` inlier pairs of each plane, :func:`inlier_table` summed over pairs: the
    chord-normal angle test first (one matrix product per chunk of planes), the side and
    ratio tests only where it passes."""
    left, right, normals, offsets = _centred(left, right, normals, offsets)
    u = F.normalize(right - left, dim=1)
    cos_min = math.cos(math.radians(eps_theta))
    votes = torch.zeros(normals.shape[0], dtype=torch.int64)
    for start in range(0, normals.shape[0], CHUNK):
        k, i = torch.nonzero((normals[start : start + CHUNK] @ u.T).abs() > cos_min, as_tuple=True)
        ok = _inlier(left[i], right[i], normals[start + k], offsets[start + k], eps_d)
        votes[start : start + CHUNK] = torch.bincount(k[ok], minlength=min(CHUNK, normals.shape[0] - start))
    return votes


@dataclasses.dataclass(frozen=True)
class Consensus:
    """The winning plane of the loop and its consensus refit.

    Attributes:
        normal: ``(3,)`` unit normal of the consensus plane.
        offset: ``()`` its offset.
        inliers: ``(S,)`` bool, the winner's inlier pairs.
        votes: ``(S,)`` int64 inlier count of every pair's plane.
        winner: index of the winning pair.
        runner_up: inliers of the best plane at least ``margin_angle`` from the winner.
    """

    normal: torch.Tensor
    offset: torch.Tensor
    inliers: torch.Tensor
    votes: torch.Tensor
    winner: int
    runner_up: int


def consensus_plane(
    left: torch.Tensor, right: torch.Tensor, *, eps_d: float, eps_theta: float, margin_angle: float, lam: float
) -> Consensus:
    """The plane explaining most pairs and its consensus refit (Sec. 5.3.3-5.3.4).

    Args:
        left, right: ``(S, 3)`` the pairs' points, ``S >= 1``.
        eps_d: tolerance on the ratio of the two distances to the plane.
        eps_theta: tolerance on the chord-normal angle, degrees.
        margin_angle: planes at least this many degrees from the winner compete for the
            runner-up count.
        lam: weight of Eq. 5.4's constraint in the refit (Eq. 5.6).
    """
    normals, offsets = pair_planes(left, right)
    votes = plane_votes(left, right, normals, offsets, eps_d, eps_theta)  # (S,)
    winner = int(votes.argmax())
    inliers = inlier_table(left, right, normals[winner : winner + 1], offsets[winner : winner + 1], eps_d, eps_theta)[0]
    normal, offset = plane_from_pairs(left[inliers], right[inliers], lam=lam)
    normal, offset = canonical_sign(normal, offset)
    far = (normals @ normal).abs() < math.cos(math.radians(margin_angle))
    runner_up = int(votes[far].max()) if bool(far.any()) else 0
    return Consensus(normal, offset, inliers, votes, winner, runner_up)
