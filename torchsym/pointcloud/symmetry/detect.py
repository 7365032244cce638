"""The whole symmetry group of a 3D point cloud: reflections, rotations found directly
(chiral shapes too), rotoreflections and axes of revolution, closed into one point group.

The top function reads as its stages: every reflection plane and axis of revolution
(:func:`~torchsym.pointcloud.detect_reflection_planes`), rotation axes found directly
and tested against the cloud's own sampling (:mod:`.rotations`), rotoreflections about
them, and the closure of all of them about their common fixed point
(:func:`~torchsym.pointcloud.reflection_planes.group.group_from_generators`).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Mapping
from typing import Any

import torch

from torchsym.core.checks import check_points
from torchsym.core.random import make_generator, random_subset
from torchsym.core.registry import register_solver
from torchsym.core.settings import Solver, resolve_settings
from torchsym.geometry.reflection import reflection_matrix, tangent_basis
from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.prepare import normalise
from torchsym.pointcloud.score import chance_share, corrected_share
from torchsym.pointcloud.reflection_planes.detect import detect_reflection_planes
from torchsym.pointcloud.reflection_planes.distance_test import split_test
from torchsym.pointcloud.reflection_planes.group import (
    SymmetryGroup,
    consistent_group,
    group_from_generators,
    snap_generators,
)
from torchsym.pointcloud.reflection_planes.revolution import rotation_transforms
from torchsym.pointcloud.symmetry.result import SymmetryResult
from torchsym.pointcloud.symmetry.rotations import (
    candidate_axes,
    find_axes,
    half_turns_across,
    rotation_share,
    rotoreflection_transform,
    same_line,
)
from torchsym.pointcloud.symmetry.settings import SymmetrySettings

__all__ = ["SymmetryDetector", "detect_symmetry"]


def detect_symmetry(
    points: torch.Tensor,
    settings: SymmetrySettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | int | None = None,
    **overrides: Any,
) -> SymmetryResult:
    """Find the whole symmetry group of a 3D point cloud.

    Args:
        points: ``(N, 3)`` point cloud (e.g. samples of a mesh's surface), N >= 4,
            spanning at least a plane; any finite scale.
        settings: :class:`SymmetrySettings`, a (nested) mapping, or None for the defaults;
            ``overrides`` (e.g. ``rotations={"max_order": 8}``) apply on top.
        generator: the source of randomness; None uses ``settings.planes.seed``.

    Returns:
        :class:`SymmetryResult`: the planes, the rotation axes found directly with their
        orders, and ``group``, the point group they generate.

    Raises:
        InputShapeError: ``points`` is not ``(N, 3)`` with N >= 4.
        InputValueError: NaN or infinite coordinates, or all points on one line.
        ConfigError: an unknown or invalid setting.

    Example:
        >>> from torchsym.pointcloud import prism_mesh, sample_surface
        >>> res = detect_symmetry(sample_surface(prism_mesh(5), 5000, generator=0))
        >>> int(res.group.orders.max())
        5
    """
    t0 = time.perf_counter()
    pts = check_points(points, "points", dim=3, min_points=4)
    if not pts.is_floating_point() or pts.dtype in (torch.float16, torch.bfloat16):
        pts = pts.to(torch.float32)
    settings = resolve_settings(SymmetrySettings, settings, overrides)
    gen = make_generator(generator if generator is not None else settings.planes.seed)

    # 1. Every plane and axis of revolution.
    planes = detect_reflection_planes(pts, settings.planes, generator=gen)
    t_planes = time.perf_counter()

    # 2. Rotation axes found directly, in normalised coordinates; then rotoreflections.
    norm = normalise(torch.unique(pts.to(torch.float64), dim=0), pts.dtype)
    xs, scale, origin = norm.xs, norm.scale, norm.origin
    n_pl = planes.normals.to(torch.float64)
    b_pl = (planes.offsets.to(torch.float64) + n_pl @ origin) / scale
    cont_d = planes.continuous_axes.to(torch.float64)
    cont_p = (planes.axis_points.to(torch.float64) - origin) / scale
    rot = settings.rotations
    merge_tol = settings.planes.revolution.merge_distance
    axes, roto = [], []
    if rot.enabled:
        index = KNNIndex(xs)
        test = split_test(xs, settings.planes.accept.n_queries, gen, local=settings.planes.accept.local_baseline)
        cands = [
            (d, p) for d, p in candidate_axes(xs, n_pl, b_pl)
            if not any(same_line(d, p, cd, cp, merge_tol) for cd, cp in zip(cont_d, cont_p))
        ]
        queries = xs[random_subset(xs.shape[0], rot.n_queries, gen)]
        found = find_axes(
            xs, index, test, cands, queries, max_order=rot.max_order, max_ratio=rot.max_ratio,
            refine_ratio=rot.refine_ratio, merge_tol=merge_tol, relative=rot.relative_ratio,
            max_far_share=rot.max_far_share,
        )
        if found and not any(f[2] == 2 and abs(float(f[0] @ found[0][0])) < 0.1 for f in found[1:]):
            found += half_turns_across(
                found[0][0], found[0][1], found[0][2], xs.mean(0), test, queries, index,
                max_ratio=rot.max_ratio, max_far_share=rot.max_far_share,
            )
        tol = planes.tolerance / scale
        s0 = chance_share(xs, index, tol, gen, n_planes=settings.planes.n_chance_planes)
        for d, p, n, ratio in found:
            t = rotation_transforms(d, p, torch.tensor([2.0 * math.pi / n], dtype=d.dtype))[0]
            score = corrected_share(rotation_share(xs, index, t, d, p, tol), s0)
            if score >= rot.min_score:
                axes.append((d, p, n, ratio, score))
        if rot.rotoreflections:
            roto = _rotoreflections(xs, index, test, axes, tol, s0, rot)
    t_rot = time.perf_counter()

    # 3. One group, about the common fixed point.
    verify = None
    if rot.enabled:  # every element of the group, not only the generators, passes the test
        centre = (_fixed_point(planes, axes, scale, origin) - origin) / scale
        verify = functools.partial(_all_pass, test=test, centre=centre, max_ratio=rot.max_ratio)
    grp = _close(planes, axes, roto, scale, origin, settings, verify)
    t_end = time.perf_counter()
    f64 = torch.float64
    return SymmetryResult(
        planes=planes,
        axes=torch.stack([a[0] for a in axes]).to(pts.dtype) if axes else torch.zeros(0, 3, dtype=pts.dtype),
        axis_points=(torch.stack([a[1] for a in axes]) * scale + origin).to(pts.dtype) if axes else torch.zeros(0, 3, dtype=pts.dtype),
        orders=torch.tensor([a[2] for a in axes], dtype=torch.int64),
        axis_ratios=torch.tensor([a[3] for a in axes], dtype=f64).to(pts.dtype),
        axis_scores=torch.tensor([a[4] for a in axes], dtype=f64).to(pts.dtype),
        rotoreflections=(torch.stack([_to_input(t, scale, origin) for t in roto]) if roto else torch.zeros(0, 4, 4, dtype=f64)).to(pts.dtype),
        group=grp,
        timings={"planes": t_planes - t0, "rotations": t_rot - t_planes, "group": t_end - t_rot, "total": t_end - t0},
    )


def _all_pass(linear: torch.Tensor, *, test, centre: torch.Tensor, max_ratio: float) -> bool:
    """Whether every ``linear (K, 3, 3)`` about ``centre (3,)`` (normalised coordinates)
    passes the distance test."""
    t = torch.zeros(linear.shape[0], 4, 4, dtype=torch.float64)
    t[:, :3, :3], t[:, :3, 3], t[:, 3, 3] = linear, centre - linear @ centre, 1.0
    return bool((test.ratios(t, bound=max_ratio) <= max_ratio).all())


def _rotoreflections(xs, index, test, axes, tol, s0, rot) -> list[torch.Tensor]:
    """The rotoreflections by ``pi / n`` about each ``n``-fold axis (through the centroid's
    foot on it) and the inversion in the centroid that pass the distance test and beat
    chance: ``(4, 4)`` transforms in normalised coordinates."""
    centre = xs.mean(0)
    cands = []
    for d, p, n, _, _ in axes:
        foot = p + ((centre - p) @ d) * d
        cands.append((rotoreflection_transform(d, foot, math.pi / n), d, foot))
    inv = -torch.eye(4, dtype=xs.dtype)
    inv[3, 3], inv[:3, 3] = 1.0, 2.0 * centre
    cands.append((inv, torch.tensor([0.0, 0.0, 1.0], dtype=xs.dtype), centre))
    out = []
    ratios = test.ratios(torch.stack([c[0] for c in cands]), bound=rot.max_ratio)
    for (t, d, p), r in zip(cands, ratios):
        if float(r) <= rot.max_ratio:
            d_far = torch.zeros(3, dtype=xs.dtype)  # every point counts, none is fixed on a line
            if corrected_share(rotation_share(xs, index, t, d_far, p, tol), s0) >= rot.min_score:
                out.append(t)
    return out


def _to_input(t: torch.Tensor, scale: float, origin: torch.Tensor) -> torch.Tensor:
    """A ``(4, 4)`` transform of normalised coordinates as one of input coordinates."""
    out = t.clone()
    out[:3, 3] = t[:3, 3] * scale + origin - t[:3, :3] @ origin
    return out


def _close(planes, axes, roto, scale, origin, settings: SymmetrySettings, verify=None) -> SymmetryGroup:
    """One group, about the least-squares point on every plane and axis: the candidates,
    most trusted first (the direct rotations by exactly ``2 pi / n``, highest order
    first; the rotoreflections; the planes within ``accept.generator_factor`` of the best
    plane's ratio, best first; a plane through each axis of revolution), snapped to the principal axis (:func:`snap_generators`) and taken
    greedily while they close to a finite group whose new elements ``verify`` accepts
    (:func:`consistent_group`)."""
    g = settings.group
    cont = planes.continuous_axes.to(torch.float64)
    through = tangent_basis(cont)[..., 0] if cont.shape[0] else torch.zeros(0, 3, dtype=torch.float64)
    # planes within the closure's generator factor of the best plane's ratio (near planes,
    # 1.3-1.4 on a sparse bolt at half the head's angle, would make a 6-fold axis 12-fold)
    ratios = planes.ratios.to(torch.float64)
    trusted = ratios <= settings.planes.accept.generator_factor * float(ratios.min()) if ratios.numel() else ratios > 0
    refl_n = torch.cat([planes.normals.to(torch.float64)[trusted], through])
    cands = [rotation_transforms(d, p, torch.tensor([2.0 * math.pi / n], dtype=d.dtype))[0, :3, :3] for d, p, n, *_ in axes]
    cands += [t[:3, :3] for t in roto]
    if refl_n.shape[0]:
        mats = reflection_matrix(refl_n)
        cands += [mats[0] @ m for m in mats[1:]]  # the turns the best plane makes with the others
        cands += list(mats)
    center = _fixed_point(planes, axes, scale, origin)
    kwargs = dict(continuous_axes=cont, axis_points=planes.axis_points, max_order=g.max_order, tol=g.tol)
    if not cands:
        return group_from_generators(torch.zeros(0, 3, 3, dtype=torch.float64), center, **kwargs)
    lin = torch.stack(cands)
    if cont.shape[0]:
        principal = cont[0]
    elif axes:
        principal = axes[0][0]
    else:
        raw = group_from_generators(lin, center, **kwargs)
        principal = raw.axes[int(raw.orders.argmax())] if raw.axes.shape[0] else None
    if principal is not None:
        lin = snap_generators(lin, principal, g.max_order)
    return consistent_group(lin, center, verify=verify, **kwargs)


def _fixed_point(planes, axes, scale, origin) -> torch.Tensor:
    """The least-squares point on every plane, axis of revolution and rotation axis (input
    units), nearest to the planes' centre."""
    rows, rhs = [planes.normals.to(torch.float64)], [-planes.offsets.to(torch.float64)]
    lines = list(zip(planes.continuous_axes.to(torch.float64), planes.axis_points.to(torch.float64)))
    lines += [(d, p * scale + origin) for d, p, *_ in axes]
    for d, p in lines:
        proj = torch.eye(3, dtype=torch.float64) - torch.outer(d, d)
        rows.append(proj)
        rhs.append(proj @ p)
    a, y = torch.cat(rows), torch.cat(rhs)
    fallback = planes.center.to(torch.float64)
    if a.shape[0] == 0:
        return fallback
    return fallback + torch.linalg.pinv(a, rtol=1e-2) @ (y - a @ fallback)


@register_solver("symmetry", kind="pointcloud")
class SymmetryDetector(Solver):
    """The whole symmetry group of a 3D point cloud; see :func:`detect_symmetry`.

    Every call starts a fresh generator from ``settings.planes.seed`` unless one is given.
    """

    settings_class = SymmetrySettings

    def forward(self, points: torch.Tensor, generator: torch.Generator | None = None) -> SymmetryResult:
        gen = generator if generator is not None else make_generator(self.settings.planes.seed)
        return detect_symmetry(points, self.settings, generator=gen)
