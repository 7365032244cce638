"""The global reflection plane of a 3D point cloud (thesis Sec. 5.2, Algorithms 5 and 6).

The thesis minimises ``|S (P - c 1^T) + c 1^T - P Pi|_F^2`` over reflections ``S``
(Eq. 5.3): it scores candidate normals on a sample (Algorithm 5) and alternates trimmed
nearest-neighbour correspondences with closed-form updates of ``S`` and ``c``
(Algorithm 6). The extensions beyond the thesis (principal-axis and sphere starts,
pre-alignment, the exact reflection update, the kernel stage) are switchable settings,
described with their measurements in ``docs/design/reflection_plane.md``.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from typing import Any

import torch

from torchsym.core.checks import check_points
from torchsym.core.random import make_generator
from torchsym.core.registry import register_solver
from torchsym.core.settings import Solver, resolve_settings
from torchsym.geometry.reflection import reflect_points
from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.reflection_plane.kernel import needs_kernel, refine_by_kernel
from torchsym.pointcloud.reflection_plane.polish import polish
from torchsym.pointcloud.prepare import dense_part, normalise, subsample
from torchsym.pointcloud.reflection_plane.result import ReflectionPlaneResult, make_result, mirror_pairs
from torchsym.pointcloud.score import chance_corrected_score
from torchsym.pointcloud.reflection_plane.settings import ReflectionPlaneSettings
from torchsym.pointcloud.reflection_plane.starts import principal_axes, refine_context, search_starts

log = logging.getLogger(__name__)

__all__ = ["ReflectionPlaneDetector", "detect_reflection_plane"]


def detect_reflection_plane(
    points: torch.Tensor,
    settings: ReflectionPlaneSettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | int | None = None,
    **overrides: Any,
) -> ReflectionPlaneResult:
    """Detect the global reflection plane of a 3D point cloud (thesis Sec. 5.2).

    Args:
        points: ``(N, 3)`` point cloud, N >= 4, spanning at least a plane; any finite scale.
        settings: :class:`ReflectionPlaneSettings`, a (nested) mapping, or None for the
            defaults; ``overrides`` (e.g. ``n_starts=1``, ``polish={"enabled": False}``)
            are applied on top.
        generator: the source of randomness (``torch.Generator``, or an int seed); None
            uses a fresh generator seeded with ``settings.seed``, so the same call gives
            the same bits.

    Returns:
        :class:`ReflectionPlaneResult`, in the input's dtype (float32 for integer input).

    Raises:
        InputShapeError: ``points`` is not ``(N, 3)`` with N >= 4.
        InputValueError: NaN or infinite coordinates, or all points on one line.
        ConfigError: an unknown or invalid setting.

    Example:
        >>> pts = torchsym.pointcloud.planted_symmetric_cloud(2000, generator=torch.Generator().manual_seed(0))
        >>> res = detect_reflection_plane(pts.points)
        >>> float(torchsym.geometry.plane_angle(res.normal, pts.normal)) < 1e-3
        True
    """
    t0 = time.perf_counter()
    pts = check_points(points, "points", dim=3, min_points=4)
    if not pts.is_floating_point() or pts.dtype in (torch.float16, torch.bfloat16):
        pts = pts.to(torch.float32)
    settings = resolve_settings(ReflectionPlaneSettings, settings, overrides)
    gen = make_generator(generator if generator is not None else settings.seed)

    # 1. Normalise (float64 inside, so that BLAS blocking cannot change the last bit),
    #    draw Algorithm 5's sample and the subsample the starts are refined on.
    norm = normalise(pts.to(torch.float64), pts.dtype)
    xs = norm.xs
    subs = subsample(norm, settings, gen)
    axes = principal_axes(subs.centered, subs.sample, subs.index, subs.spacing) if settings.starts.pca else []
    t_init = time.perf_counter()

    # 2. Algorithm 5's candidates (after the principal axes), each refined on the subsample;
    #    the best supported wins.
    ctx = refine_context(xs, subs, settings, gen)
    search = search_starts(axes, subs, ctx, settings)
    normal, offset = search.best[0], search.best[1]
    t_refine = time.perf_counter()

    # 3. The winner refined against the whole cloud: Algorithm 6 when the subsample is the
    #    whole cloud, else coarse-to-fine steps to its surface.
    whole = subs.sub is xs
    full_index = subs.index if whole else KNNIndex(xs)
    polished = polish(xs, full_index, normal, offset, settings, gen, whole=whole)
    normal, offset, dist, nn_idx = polished.normal, polished.offset, polished.dist, polished.nn_idx
    tol = settings.inlier_factor * max(polished.spacing, 1e-12)

    # 4. Kernel correlation when no point has an exact mirror and noise thickened the surface.
    t_kernel = 0.0
    if needs_kernel(dist, tol, subs.sub, subs.index, ctx.eigenvalues, settings.kernel):
        t_kernel = time.perf_counter()
        kpts, kindex = subs.dense if subs.dense is not None else dense_part(subs.sub, subs.index, settings.dense)
        normal, offset, refined = refine_by_kernel(
            kpts, kindex, normal, offset, [*axes, *search.ranked(settings.kernel.n_starts)], settings.kernel,
            n_directions=settings.init.n_directions, min_separation=settings.starts.min_separation, tol_se=settings.tol_se,
        )
        if refined:
            dist, nn_idx = full_index.query(reflect_points(xs, normal, offset))
        t_kernel = time.perf_counter() - t_kernel

    # 5. Mirror pairs, inliers and the centre c, in input units; the score against chance.
    found = mirror_pairs(xs, dist, nn_idx, tol, normal, offset)
    score = chance_corrected_score(xs, full_index, dist, normal, offset, tol, gen, n_planes=settings.n_chance_planes)
    t_end = time.perf_counter()
    iterations = search.iterations + polished.iterations
    log.info(
        "reflection plane: %d points, %d starts, %d steps, converged %s, init %.3f s, refine %.3f s, polish %.3f s",
        xs.shape[0], search.tried, iterations, polished.converged, t_init - t0, t_refine - t_init, t_end - t_refine,
    )
    timings = {
        "init": t_init - t0,
        "refine": t_refine - t_init,
        "polish": t_end - t_refine - t_kernel,
        "kernel": t_kernel,
        "total": t_end - t0,
    }
    return make_result(
        norm, normal, offset, found, dist, tol, score, pts.dtype,
        iterations=iterations, converged=polished.converged, n_starts=search.tried, timings=timings,
    )


@register_solver("reflection_plane", kind="pointcloud", default=True)
class ReflectionPlaneDetector(Solver):
    """Global reflection plane of a 3D point cloud (thesis Sec. 5.2); see :func:`detect_reflection_plane`.

    Every call starts a fresh generator from ``settings.seed`` unless one is given.
    """

    settings_class = ReflectionPlaneSettings

    def forward(self, points: torch.Tensor, generator: torch.Generator | None = None) -> ReflectionPlaneResult:
        gen = generator if generator is not None else make_generator(self.settings.seed)
        return detect_reflection_plane(points, self.settings, generator=gen)
