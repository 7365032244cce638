"""n-fold rotation axes found directly, whether or not any mirror plane exists (a fan with
pitched blades, a pinwheel: chiral shapes), and rotoreflections about them.

Candidate axes (a unit ``direction (3,)`` and a ``point (3,)`` on it, normalised
coordinates) come from the principal axes about the centroid, the normals of accepted
planes and the lines where two planes meet. Each candidate's rotations by ``2 pi / n``,
``n = 2 .. max_order``, are measured by the distance test (:mod:`~torchsym.pointcloud.
reflection_planes.distance_test`: the mean distance from the rotated half of the cloud to
the other half over the sampling distance); the best order's rotation is refined by a
trimmed point-to-point ICP whose result is projected back onto a rotation by exactly
``2 pi / n`` about a line, and the orders are measured again. An axis has order ``n`` when
``n`` is the largest order whose rotation and whose divisors' rotations pass the test;
its score is the share of points moved onto the surface, corrected for chance as a
plane's is.
"""

from __future__ import annotations

import dataclasses
import math

import torch

from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.reflection_planes.distance_test import DistanceTest
from torchsym.pointcloud.reflection_planes.revolution import rotation_transforms

__all__ = ["RotationAxis", "candidate_axes", "find_axes", "half_turns_across", "polish_axis", "refine_axis", "rotoreflection_transform", "same_line"]


@dataclasses.dataclass(frozen=True)
class RotationAxis:
    """One verified axis: unit ``direction (3,)``, ``point (3,)`` on it, its ``order``,
    the distance ``ratio`` of its rotation by ``2 pi / order`` and its chance-corrected
    ``score``."""

    direction: torch.Tensor
    point: torch.Tensor
    order: int
    ratio: float
    score: float


def candidate_axes(
    xs: torch.Tensor, normals: torch.Tensor, offsets: torch.Tensor, max_planes: int = 3
) -> list[tuple[torch.Tensor, torch.Tensor]]:
    """Candidate lines ``(direction, point)`` for ``xs (N, 3)``: the three principal axes
    through the centroid, the normal of each of the first ``max_planes`` planes
    ``normals (P, 3)``, ``offsets (P,)`` through the centroid's foot on it, and where each
    two of them meet (5 degrees apart or more)."""
    centre = xs.mean(0)
    cen = xs - centre
    _, vec = torch.linalg.eigh(cen.T @ cen)
    out = [(vec[:, k].clone(), centre) for k in range(3)]
    k = min(normals.shape[0], max_planes)
    for i in range(k):
        out.append((normals[i], centre - (centre @ normals[i] + offsets[i]) * normals[i]))
        for j in range(i + 1, k):
            d = torch.linalg.cross(normals[i], normals[j])
            if float(d.norm()) > math.sin(math.radians(5.0)):
                a = torch.stack([normals[i], normals[j]])
                rhs = -torch.stack([offsets[i], offsets[j]]) - a @ centre
                out.append((d / d.norm(), centre + a.T @ torch.linalg.solve(a @ a.T, rhs)))
    return out


def same_line(d1, p1, d2, p2, tol: float, angle_deg: float = 5.0) -> bool:
    """Whether two lines nearly coincide: within ``angle_deg`` and the ends of the unit
    segment ``p1 +- d1`` within ``tol`` of the other line."""
    if float((d1 @ d2).abs()) < math.cos(math.radians(angle_deg)):
        return False
    ends = torch.stack([p1 - d1, p1 + d1]) - p2
    off = ends - (ends @ d2)[:, None] * d2
    return bool((off.norm(dim=1) <= tol).all())


def rotoreflection_transform(direction: torch.Tensor, point: torch.Tensor, angle: float) -> torch.Tensor:
    """``(4, 4)``: rotation by ``angle`` about the line, then reflection in the plane
    across it through ``point``."""
    rot = rotation_transforms(direction, point, torch.tensor([angle], dtype=direction.dtype))[0]
    d = direction / direction.norm()
    refl = torch.eye(4, dtype=d.dtype)
    refl[:3, :3] -= 2.0 * torch.outer(d, d)
    refl[:3, 3] = 2.0 * (point @ d) * d
    return refl @ rot


def _screw_line(transform: torch.Tensor, near: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, float]:  # noqa: D401
    """The axis ``(direction, point nearest near, angle)`` of a rigid ``transform (4, 4)``
    (the point fixed up to a slide along the axis, least squares)."""
    r, t = transform[:3, :3], transform[:3, 3]
    from scipy.spatial.transform import Rotation

    rv = torch.from_numpy(Rotation.from_matrix(r.numpy()).as_rotvec()).to(r)
    angle = float(rv.norm())
    d = rv / max(angle, 1e-12)
    a = torch.eye(3, dtype=r.dtype) - r
    p = near + torch.linalg.pinv(a, rtol=1e-3) @ (t - a @ near)
    return d, p, angle


def refine_axis(
    direction: torch.Tensor, point: torch.Tensor, order: int, queries: torch.Tensor, index: KNNIndex, iters: int = 12
) -> tuple[torch.Tensor, torch.Tensor]:
    """The line of a ``2 pi / order`` rotation refined by trimmed ICP of ``queries (Q, 3)``
    onto the cloud ``index`` is built on: each step matches the rotated queries to their
    nearest points (the nearer half kept), takes the direction of the rigid fit (Kabsch)
    and, for the rotation by exactly ``2 pi / order`` about it, the point of the line in
    closed form (least squares of ``(I - R) p = mean(m - R q)``). The axis must be placed
    well within a sampling distance: a centroid 0.002 off (of a unit diagonal, 20,000
    samples) raised a true 4-fold turn's ratio to 1.8."""
    d, p = direction / direction.norm(), point
    angle = 2.0 * math.pi / order
    ref = index.points.to(queries)
    eye = torch.eye(3, dtype=queries.dtype)
    for _ in range(iters):
        t = rotation_transforms(d, p, torch.tensor([angle], dtype=d.dtype))[0]
        dist, nn = index.query(queries @ t[:3, :3].T + t[:3, 3])
        keep = dist <= dist.median()
        src, dst = queries[keep], ref[nn[keep]]
        sc, dc = src.mean(0), dst.mean(0)
        u, _, vh = torch.linalg.svd((src - sc).T @ (dst - dc))
        s = torch.eye(3, dtype=src.dtype)
        s[2, 2] = float(torch.sign(torch.linalg.det(vh.T @ u.T)))
        nd, _, a = _screw_line(torch.cat([torch.cat([vh.T @ s @ u.T, torch.zeros(3, 1, dtype=src.dtype)], 1),
                                          torch.tensor([[0.0, 0.0, 0.0, 1.0]], dtype=src.dtype)]), p)
        if a < 0.25 * angle:  # the fit fell towards the identity: keep the line
            break
        nd = nd if float(nd @ d) >= 0 else -nd
        r = rotation_transforms(nd, torch.zeros(3, dtype=d.dtype), torch.tensor([angle], dtype=d.dtype))[0, :3, :3]
        np_ = torch.linalg.pinv(eye - r, rtol=1e-3) @ (dc - r @ sc)
        np_ = np_ + ((p - np_) @ nd) * nd  # the same height along the axis
        moved = float((nd - d).norm()) + float((np_ - p).norm())
        d, p = nd, np_
        if moved < 1e-6:
            break
    return d / d.norm(), p


def polish_axis(
    direction: torch.Tensor, point: torch.Tensor, order: int, test: DistanceTest, *, tilt: float = 0.02,
    shift: float = 0.004, rounds: int = 10,
) -> tuple[torch.Tensor, torch.Tensor, float]:
    """A pattern search of the line that lowers the distance ratio of its rotation by
    ``2 pi / order``: the direction tilted by ``+- tilt`` radians and the point shifted by
    ``+- shift`` (normalised units) along two directions across the line, all eight in one
    query; the best move taken, the steps halved when none helps. Returns ``(direction,
    point, ratio)``."""
    angle = torch.tensor([2.0 * math.pi / order], dtype=direction.dtype)
    d, p = direction / direction.norm(), point
    best = float(test.ratios(rotation_transforms(d, p, angle))[0])
    for _ in range(rounds):
        e = torch.linalg.cross(d, torch.eye(3, dtype=d.dtype)[int(d.abs().argmin())])
        e = e / e.norm()
        f = torch.linalg.cross(d, e)
        moves = [(d + s * tilt * v, p) for v in (e, f) for s in (1.0, -1.0)]
        moves += [(d, p + s * shift * v) for v in (e, f) for s in (1.0, -1.0)]
        moves = [(m / m.norm(), q) for m, q in moves]
        r = test.ratios(torch.cat([rotation_transforms(m, q, angle) for m, q in moves]))
        k = int(r.argmin())
        if float(r[k]) < best:
            (d, p), best = moves[k], float(r[k])
        else:
            tilt, shift = 0.5 * tilt, 0.5 * shift
    return d, p, best


def _orders_ratios(lines, test: DistanceTest, max_order: int, bound: float) -> torch.Tensor:
    """``(L, max_order - 1)`` ratio of the rotation by ``2 pi / n`` about each line, n = 2.."""
    angles = torch.tensor([2.0 * math.pi / n for n in range(2, max_order + 1)], dtype=torch.float64)
    ts = torch.cat([rotation_transforms(d, p, angles.to(d)) for d, p in lines])
    return test.ratios(ts, bound=bound).reshape(len(lines), -1)


def _best_order(ratios: torch.Tensor, max_ratio: float, turns_pass) -> int:
    """The largest ``n`` whose ratio (``ratios[n - 2]``) and every divisor's pass, and
    whose turns by ``2 pi k / n`` all pass (``turns_pass(n)``), or 1."""
    ok = [False, False] + [float(r) <= max_ratio for r in ratios]
    for n in range(len(ok) - 1, 1, -1):
        if ok[n] and all(ok[m] for m in range(2, n) if n % m == 0) and turns_pass(n):
            return n
    return 1


def _turns_pass(d, p, n: int, test: DistanceTest, max_ratio: float, max_far_share: float, far_floor: float) -> bool:
    """Whether the turns by ``2 pi k / n`` about the line, ``k = 1 .. n // 2``, pass the
    test: ratio within ``max_ratio`` for ``k`` coprime to ``n`` (a near-cylinder passes
    2 pi / 9 by a whisker, not 4 pi / 9), and at most ``max_far_share`` more points
    moved far than ``far_floor`` (the best order's own far share: holes move points far
    under every symmetry) for every ``k`` (:meth:`DistanceTest.far_shares`: the mean
    forgives a small part moved far, a hexagonal bolt head turned by 2 pi / 7)."""
    ks = list(range(1, n // 2 + 1))
    ts = rotation_transforms(d, p, torch.tensor([2.0 * math.pi * k / n for k in ks], dtype=d.dtype))
    if float(test.far_shares(ts).max()) > far_floor + max_far_share:
        return False
    coprime = [i for i, k in enumerate(ks) if k > 1 and math.gcd(k, n) == 1]
    return not coprime or bool((test.ratios(ts[coprime], bound=max_ratio) <= max_ratio).all())


def rotation_share(xs: torch.Tensor, index: KNNIndex, transform: torch.Tensor, axis_d, axis_p, tol: float) -> float:
    """The share of the points of ``xs (N, 3)`` farther than ``tol`` from the axis that
    ``transform (4, 4)`` moves within ``tol`` of the cloud."""
    rel = xs - axis_p
    off = (rel - (rel @ axis_d)[:, None] * axis_d).norm(dim=1) > tol
    d, _ = index.query(xs[off] @ transform[:3, :3].T + transform[:3, 3], max_distance=2.0 * tol)
    return float((d <= tol).double().mean()) if d.numel() else 0.0


def find_axes(
    xs: torch.Tensor,
    index: KNNIndex,
    test: DistanceTest,
    candidates: list[tuple[torch.Tensor, torch.Tensor]],
    queries: torch.Tensor,
    *,
    max_order: int,
    max_ratio: float,
    refine_ratio: float,
    merge_tol: float,
    relative: float = 1.15,
    max_far_share: float = 0.02,
    max_refined: int = 4,
) -> list[tuple[torch.Tensor, torch.Tensor, int, float]]:
    """The distinct axes among ``candidates`` with an order of 2 or more:
    ``(direction, point, order, ratio)``, the highest order first. Candidates whose best
    ratio is at most ``refine_ratio`` (the ``max_refined`` lowest) are refined
    (:func:`refine_axis`, :func:`polish_axis` on 1,000 queries) and measured again;
    an order passes within ``max_ratio`` and ``relative`` times the axis's best ratio,
    with no more than ``max_far_share`` of the points moved far (:func:`_turns_pass`);
    two axes within ``merge_tol`` (:func:`same_line`) are one."""
    unique: list[tuple[torch.Tensor, torch.Tensor]] = []
    for d, p in candidates:
        if not any(same_line(d, p, u[0], u[1], merge_tol) for u in unique):
            unique.append((d, p))
    candidates = unique
    if not candidates:
        return []
    ratios = _orders_ratios(candidates, test, max_order, refine_ratio)
    quick = dataclasses.replace(test, queries=test.queries[:1000])  # the pattern search's queries
    found = []
    order = ratios.min(1).values.argsort()[:max_refined].tolist()  # the most promising first
    for (d, p), r in ((candidates[i], ratios[i]) for i in order):
        best = int(r.argmin()) + 2
        if float(r.min()) > refine_ratio:
            continue
        if any(same_line(d, p, f[0], f[1], merge_tol) for f in found):
            continue
        d, p = refine_axis(d, p, best, queries, index)
        d, p, _ = polish_axis(d, p, best, quick)
        r2 = _orders_ratios([(d, p)], test, max_order, max_ratio)[0]
        if int(r2.argmin()) + 2 != best:  # polished for an order that is not the best one now
            d, p, _ = polish_axis(d, p, int(r2.argmin()) + 2, quick)
            r2 = _orders_ratios([(d, p)], test, max_order, max_ratio)[0]
        best = int(r2.argmin()) + 2
        floor = float(test.far_shares(rotation_transforms(d, p, torch.tensor([2.0 * math.pi / best], dtype=d.dtype)))[0])
        n = _best_order(
            r2, min(max_ratio, relative * float(r2.min())), lambda m: _turns_pass(d, p, m, test, max_ratio, max_far_share, floor)
        )
        if n >= 2 and not any(same_line(d, p, f[0], f[1], merge_tol) for f in found):
            found.append((d, p, n, float(r2[n - 2])))
    return sorted(found, key=lambda f: (-f[2], f[3]))


def half_turns_across(
    direction: torch.Tensor,
    point: torch.Tensor,
    order: int,
    centre: torch.Tensor,
    test: DistanceTest,
    queries: torch.Tensor,
    index: KNNIndex,
    *,
    max_ratio: float,
    max_far_share: float,
    step_deg: float = 2.0,
) -> list[tuple[torch.Tensor, torch.Tensor, int, float]]:
    """A 2-fold axis across an ``order``-fold axis (the dihedral groups D_n: a fan whose
    pitched blades each have a half-turn about their own line, with no plane at all):
    half-turns about lines through the foot of ``centre`` on the axis, perpendicular to
    it, every ``step_deg`` over ``[0, pi / order)`` (the ``order``-fold turns give the
    rest); the best is refined and kept when it passes (its far share within
    ``max_far_share`` of the main axis's turn's). ``[(direction, point, 2, ratio)]``
    or ``[]``."""
    d = direction / direction.norm()
    foot = point + ((centre - point) @ d) * d
    e = torch.linalg.cross(d, torch.eye(3, dtype=d.dtype)[int(d.abs().argmin())])
    e = e / e.norm()
    f = torch.linalg.cross(d, e)
    count = max(2, int(math.ceil(180.0 / order / step_deg)))
    thetas = torch.arange(count, dtype=d.dtype) * (math.pi / order / count)
    lines = [(math.cos(t) * e + math.sin(t) * f, foot) for t in thetas.tolist()]
    ts = torch.cat([rotation_transforms(u, q, torch.tensor([math.pi], dtype=d.dtype)) for u, q in lines])
    r = test.ratios(ts, bound=max_ratio)
    best = int(r.argmin())
    if float(r[best]) > 2.0 * max_ratio:
        return []
    u, q = refine_axis(lines[best][0], foot, 2, queries, index)
    u, q, _ = polish_axis(u, q, 2, dataclasses.replace(test, queries=test.queries[:1000]))
    u = u - (u @ d) * d  # across the axis, exactly
    u = u / u.norm()
    t = rotation_transforms(u, q, torch.tensor([math.pi], dtype=d.dtype))
    ratio = float(test.ratios(t, bound=max_ratio)[0])
    floor = float(test.far_shares(rotation_transforms(d, point, torch.tensor([2.0 * math.pi / order], dtype=d.dtype)))[0])
    if ratio <= max_ratio and float(test.far_shares(t)[0]) <= floor + max_far_share:
        return [(u, q, 2, ratio)]
    return []
