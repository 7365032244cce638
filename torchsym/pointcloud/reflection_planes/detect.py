"""Every reflection plane of a 3D point cloud (thesis Sec. 5.2, extended to every plane).

The top function reads as its stages: the one-plane detector's starts (principal axes and
Algorithm 5's candidates, :mod:`~torchsym.pointcloud.reflection_plane.starts`), all
aligned at once on the subsample (:mod:`.align`), the supported ones merged and polished
on the whole cloud, each tested against the cloud's own sampling distance
(:mod:`.distance_test`) and against chance planes (the one-plane score), planes generated
by the accepted ones tested in turn (:mod:`.merge`), and fans of planes through an axis
replaced by the axis (:mod:`.revolution`). See ``docs/design/reflection_planes.md``.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import torch

from torchsym.core.checks import check_points
from torchsym.core.random import make_generator, random_subset
from torchsym.core.registry import register_solver
from torchsym.core.settings import Solver, resolve_settings
from torchsym.geometry.reflection import canonical_sign, reflection_transform
from torchsym.matching.knn import KNNIndex, mutual_nearest
from torchsym.pointcloud.prepare import normalise, spacing, subsample
from torchsym.pointcloud.score import chance_share, corrected_share
from torchsym.pointcloud.reflection_plane.starts import candidate_starts, principal_axes, refine_context
from torchsym.pointcloud.reflection_planes.align import (
    align_planes,
    nearest_surface,
    plane_supports,
    reflect_in_planes,
    surface_patches,
)
from torchsym.pointcloud.reflection_planes.distance_test import DistanceTest, split_test
from torchsym.pointcloud.reflection_planes.merge import conjugate_planes, distinct_planes, mirror_gaps
from torchsym.pointcloud.reflection_planes.result import ReflectionPlanesResult
from torchsym.pointcloud.reflection_planes.revolution import candidate_axes, contains_axis, test_axes
from torchsym.pointcloud.reflection_planes.settings import ReflectionPlanesSettings

__all__ = ["ReflectionPlanesDetector", "detect_reflection_planes"]

#: points whose mirror images tell whether two planes are one (median gap)
_GAP_PROBE = 200
#: most planes (lowest ratios first) reflected in each other per closure round: 12 planes
#: of a k-fold axis generate all of them, and their 132 images stay cheap to compare
_MAX_GENERATORS = 12


def detect_reflection_planes(
    points: torch.Tensor,
    settings: ReflectionPlanesSettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | int | None = None,
    **overrides: Any,
) -> ReflectionPlanesResult:
    """Find every reflection plane of a 3D point cloud, and its axes of revolution.

    Args:
        points: ``(N, 3)`` point cloud (e.g. samples of a mesh's surface), N >= 4,
            spanning at least a plane; any finite scale.
        settings: :class:`ReflectionPlanesSettings`, a (nested) mapping, or None for the
            defaults; ``overrides`` (e.g. ``accept={"max_ratio": 1.3}``) apply on top.
        generator: the source of randomness (``torch.Generator`` or int seed); None uses
            ``settings.seed``, so the same call gives the same bits.

    Returns:
        :class:`ReflectionPlanesResult` in the input's dtype (float32 for integer input):
        planes best first, duplicates merged; a surface of revolution's planes through its
        axis are reported as the axis.

    Raises:
        InputShapeError: ``points`` is not ``(N, 3)`` with N >= 4.
        InputValueError: NaN or infinite coordinates, or all points on one line.
        ConfigError: an unknown or invalid setting.

    Example:
        >>> from torchsym.pointcloud import box_mesh, sample_surface
        >>> res = detect_reflection_planes(sample_surface(box_mesh((3.0, 2.0, 1.0)), 5000, generator=0))
        >>> res.n_planes
        3
    """
    t0 = time.perf_counter()
    pts = check_points(points, "points", dim=3, min_points=4)
    if not pts.is_floating_point() or pts.dtype in (torch.float16, torch.bfloat16):
        pts = pts.to(torch.float32)
    settings = resolve_settings(ReflectionPlanesSettings, settings, overrides)
    gen = make_generator(generator if generator is not None else settings.seed)
    one = settings.one_plane()

    # 1. Normalise; the one-plane detector's subsample, tolerance and starts.
    norm = normalise(pts.to(torch.float64), pts.dtype)
    xs = norm.xs
    subs = subsample(norm, one, gen)
    ctx = refine_context(xs, subs, one, gen)
    starts = principal_axes(subs.centered, subs.sample, subs.index, subs.spacing)
    starts += candidate_starts(subs.sample, subs.index, subs.spacing, one)
    t_prep = time.perf_counter()

    # 2. Every start aligned on the subsample at once; the supported ones merged, best first.
    al = settings.align
    normals = torch.stack([s[0] for s in starts]).to(torch.float64)
    offsets = torch.stack([s[1] for s in starts]).to(torch.float64)
    queries = ctx.queries[random_subset(ctx.queries.shape[0], al.n_queries, gen)]
    normals, offsets = align_planes(
        queries, nearest_surface(ctx.sub, ctx.index, ctx.normals), normals, offsets,
        max_iters=al.max_iters, tol_angle=al.tol_angle,
    )
    support = plane_supports(ctx.queries, ctx.index, normals, offsets, ctx.tol)
    order = support.argsort(descending=True)
    order = order[support[order] >= al.min_support * ctx.reference]
    merge_tol = settings.merge_factor * ctx.tol
    kept = distinct_planes(ctx.queries[:_GAP_PROBE], normals, offsets, order, merge_tol)
    normals, offsets = normals[kept], offsets[kept]

    # 3. The kept planes polished on the whole cloud.
    whole = subs.sub is xs
    full_index = subs.index if whole else KNNIndex(xs)
    polish_q = xs[random_subset(xs.shape[0], al.polish_queries, gen)]
    match = surface_patches(xs, full_index, al.n_neighbors)
    normals, offsets = align_planes(polish_q, match, normals, offsets, max_iters=al.polish_iters, tol_angle=al.tol_angle)
    t_align = time.perf_counter()

    # 4. The distance test on a random split of the cloud.
    acc = settings.accept
    test = split_test(xs, acc.n_queries, gen, local=acc.local_baseline)
    ratios = test.plane_ratios(normals, offsets, bound=acc.max_ratio)
    ok = ratios <= acc.max_ratio
    normals, offsets, ratios = normals[ok], offsets[ok], ratios[ok]
    n_tested = int(ok.numel())

    # 5. Axes of revolution replace the planes through them (first: a fan of planes has no end);
    #    the plane across each axis is tested.
    axes: list[tuple[torch.Tensor, torch.Tensor, float]] = []
    if settings.revolution.enabled:
        normals, offsets, ratios, axes, n_across = _revolution(
            normals, offsets, ratios, xs, subs.centered, test, ctx.queries[:_GAP_PROBE], merge_tol, polish_q, match, settings
        )
        n_tested += n_across

    # 6. Planes reflected in accepted ones, tested in turn; duplicates merged.
    planes_n, planes_b, ratios, n_new = _closure(
        normals, offsets, ratios, test, ctx.queries[:_GAP_PROBE], merge_tol, polish_q, match, settings
    )
    n_tested += n_new
    t_test = time.perf_counter()

    # 7. Scores against chance planes, mirror pairs; the planes below min_score dropped.
    full_spacing = spacing(xs, full_index, gen)
    tol = settings.inlier_factor * max(full_spacing, 1e-12)
    s0 = chance_share(xs, full_index, tol, gen, n_planes=settings.n_chance_planes)
    scores, pairs = _scores_and_pairs(xs, full_index, planes_n, planes_b, tol, s0)
    keep = [k for k in sorted(range(len(scores)), key=lambda k: (-scores[k], float(ratios[k]))) if scores[k] >= acc.min_score]
    t_end = time.perf_counter()
    timings = {
        "prepare": t_prep - t0, "align": t_align - t_prep, "test": t_test - t_align, "score": t_end - t_test,
        "total": t_end - t0,
    }
    return _make_result(
        norm, planes_n, planes_b, scores, ratios, pairs, keep, axes, tol, test.base, pts.dtype,
        n_starts=len(starts), n_tested=n_tested, timings=timings,
    )


def _revolution(normals, offsets, ratios, xs, centered, test: DistanceTest, probe, merge_tol, polish_q, match, settings):
    """The axes of revolution among the candidates (:func:`~.revolution.candidate_axes`),
    the accepted planes ``normals (K, 3)``, ``offsets (K,)``, ``ratios (K,)`` without those
    through an axis, and with the plane across each axis when it passes the test (through
    the middle of the cloud's extent along the axis, whatever the density, then polished).
    Returns ``(normals, offsets, ratios, axes, planes tested)``."""
    acc, al, rev = settings.accept, settings.align, settings.revolution
    cand = candidate_axes(normals, offsets, centered, xs.mean(0), rev.eigen_gap)
    floor = float(test.far_shares(reflection_transform(normals, offsets)).min()) if normals.shape[0] else 0.0
    axes = test_axes(cand, test, rev.n_angles, acc.max_ratio, rev.merge_distance, far_floor=floor)
    if not axes:
        return normals, offsets, ratios, axes, 0
    off_axis = [
        k for k in range(normals.shape[0])
        if not any(contains_axis(normals[k], offsets[k], d, p, 2.0 * merge_tol) for d, p, _ in axes)
    ]
    normals, offsets, ratios = normals[off_axis], offsets[off_axis], ratios[off_axis]
    across_n = torch.stack([d for d, _, _ in axes])
    proj = xs @ across_n.T  # (N, A)
    across_b = -0.5 * (torch.quantile(proj, 0.005, dim=0) + torch.quantile(proj, 0.995, dim=0))
    if normals.shape[0]:
        fresh = mirror_gaps(probe, across_n, across_b, normals, offsets).min(1).values >= merge_tol
        across_n, across_b = across_n[fresh], across_b[fresh]
    across_n, across_b = align_planes(polish_q, match, across_n, across_b, max_iters=al.polish_iters, tol_angle=al.tol_angle)
    across_r = test.plane_ratios(across_n, across_b, bound=acc.max_ratio)
    ok = across_r <= acc.max_ratio
    normals, offsets = torch.cat([normals, across_n[ok]]), torch.cat([offsets, across_b[ok]])
    return normals, offsets, torch.cat([ratios, across_r[ok]]), axes, int(across_r.numel())


def _closure(normals, offsets, ratios, test: DistanceTest, probe, merge_tol, polish_q, match, settings):
    """For ``accept.closure_rounds`` rounds, the reflections of the accepted planes
    ``normals (K, 3)``, ``offsets (K,)`` (``ratios (K,)``) of ratio within
    ``accept.generator_factor`` of the least (the best ``_MAX_GENERATORS``) in each other that match no plane tested yet, polished by
    ``match`` and tested. Returns the accepted ``(normals, offsets, ratios)``, distinct,
    best first, and the number of new planes tested."""
    acc, al = settings.accept, settings.align
    tested_n, tested_b = normals, offsets
    n_new = 0
    for _ in range(acc.closure_rounds):
        if ratios.numel() == 0:
            break
        gen_ok = (ratios <= acc.generator_factor * float(ratios.min())).nonzero()[:, 0]
        gen_ok = gen_ok[ratios[gen_ok].argsort()][:_MAX_GENERATORS]
        if gen_ok.numel() < 2 or n_new >= acc.max_planes:
            break
        new_n, new_b = canonical_sign(*conjugate_planes(normals[gen_ok], offsets[gen_ok]))
        fresh = mirror_gaps(probe, new_n, new_b, tested_n, tested_b).min(1).values >= merge_tol
        idx = distinct_planes(probe, new_n, new_b, fresh.nonzero()[:, 0], merge_tol)[: acc.max_planes - n_new]
        if not idx:
            break
        new_n, new_b = align_planes(polish_q, match, new_n[idx], new_b[idx], max_iters=al.polish_iters, tol_angle=al.tol_angle)
        new_r = test.plane_ratios(new_n, new_b, bound=acc.max_ratio)
        n_new += len(idx)
        tested_n, tested_b = torch.cat([tested_n, new_n]), torch.cat([tested_b, new_b])
        ok = new_r <= acc.max_ratio
        normals, offsets, ratios = torch.cat([normals, new_n[ok]]), torch.cat([offsets, new_b[ok]]), torch.cat([ratios, new_r[ok]])
    # planes that met after polishing: the lowest ratio of each group stays
    kept = distinct_planes(probe, normals, offsets, ratios.argsort(), merge_tol)
    return normals[kept], offsets[kept], ratios[kept], n_new


def _scores_and_pairs(xs, index: KNNIndex, normals, offsets, tol: float, s0: float):
    """Each plane's chance-corrected mirror share over every point of ``xs (N, 3)`` and its
    mutual mirror pairs within ``tol``: ``(list of P floats, (M, 3) int64)``."""
    n, k = xs.shape[0], normals.shape[0]
    if k == 0:
        return [], torch.zeros(0, 3, dtype=torch.int64)
    # only "within tol" matters: a bounded search skips the far queries, the slow ones
    dist, nn = index.query(reflect_in_planes(xs, normals, offsets).reshape(-1, 3), max_distance=2.0 * tol)
    dist, nn = dist.reshape(k, n), nn.reshape(k, n)
    idx = torch.arange(n)
    scores, pairs = [], []
    for p in range(k):
        near = dist[p] <= tol
        off_plane = (xs @ normals[p] + offsets[p]).abs() > tol
        count = int(off_plane.sum())
        share = float((near & off_plane).double().sum()) / count if count else 0.0
        scores.append(corrected_share(share, s0))
        j = torch.where(near, nn[p], idx)  # far points: themselves, never a pair
        good = near & mutual_nearest(j, j) & (idx <= j)
        pairs.append(torch.stack([torch.full_like(idx[good], p), idx[good], j[good]], 1))
    return scores, torch.cat(pairs)


def _make_result(norm, normals, offsets, scores, ratios, pairs, keep, axes, tol, base, out_dtype, **extra) -> ReflectionPlanesResult:
    """The result in input units and ``out_dtype``, planes ``keep`` in that order."""
    keep_t = torch.tensor(keep, dtype=torch.int64)
    n, b = canonical_sign(normals[keep_t], offsets[keep_t])
    b_o = b * norm.scale - n @ norm.origin
    rank = torch.full((normals.shape[0] + 1,), -1, dtype=torch.int64)
    rank[keep_t] = torch.arange(len(keep))
    pairs = pairs[rank[pairs[:, 0]] >= 0]
    pairs = torch.cat([rank[pairs[:, 0]][:, None], pairs[:, 1:]], 1)
    pairs = pairs[pairs[:, 0].argsort(stable=True)]
    if axes:
        dirs = torch.stack([a[0] for a in axes])
        dirs, _ = canonical_sign(dirs, torch.zeros(dirs.shape[0], dtype=dirs.dtype))
        apts = torch.stack([a[1] for a in axes]) * norm.scale + norm.origin
        arat = torch.tensor([a[2] for a in axes], dtype=torch.float64)
    else:
        dirs = apts = torch.zeros(0, 3, dtype=torch.float64)
        arat = torch.zeros(0, dtype=torch.float64)
    center = _fixed_point(n, b_o, dirs, apts, norm.origin)
    return ReflectionPlanesResult(
        normals=n.to(out_dtype),
        offsets=b_o.to(out_dtype),
        scores=torch.tensor([scores[k] for k in keep], dtype=out_dtype),
        ratios=ratios[keep_t].to(out_dtype),
        transforms=reflection_transform(n, b_o).to(out_dtype) if len(keep) else torch.zeros(0, 4, 4, dtype=out_dtype),
        pairs=pairs,
        continuous_axes=dirs.to(out_dtype),
        axis_points=apts.to(out_dtype),
        axis_ratios=arat.to(out_dtype),
        center=center.to(out_dtype),
        tolerance=tol * norm.scale,
        sampling_distance=base * norm.scale,
        **extra,
    )


def _fixed_point(normals, offsets, dirs, points, fallback) -> torch.Tensor:
    """The least-squares point on every plane and axis, nearest to ``fallback`` (3,)."""
    rows = [normals]
    rhs = [-offsets]
    for d, p in zip(dirs, points):
        proj = torch.eye(3, dtype=d.dtype) - torch.outer(d, d)  # (3, 3) across the axis
        rows.append(proj)
        rhs.append(proj @ p)
    a, y = torch.cat(rows), torch.cat(rhs)
    if a.shape[0] == 0:
        return fallback
    # minimum-norm correction from the fallback point: exact on the constraints' span
    return fallback + torch.linalg.pinv(a, rtol=1e-2) @ (y - a @ fallback)


@register_solver("reflection_planes", kind="pointcloud")
class ReflectionPlanesDetector(Solver):
    """Every reflection plane of a 3D point cloud; see :func:`detect_reflection_planes`.

    Every call starts a fresh generator from ``settings.seed`` unless one is given.
    """

    settings_class = ReflectionPlanesSettings

    def forward(self, points: torch.Tensor, generator: torch.Generator | None = None) -> ReflectionPlanesResult:
        gen = generator if generator is not None else make_generator(self.settings.seed)
        return detect_reflection_planes(points, self.settings, generator=gen)

