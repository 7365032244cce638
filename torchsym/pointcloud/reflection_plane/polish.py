"""The polish: the winning start refined against the whole cloud (thesis Sec. 5.2.3, extended),
and the residuals of the whole cloud at the resulting plane.

A cloud no larger than the subsample the starts were refined on is polished by Algorithm 6
on all of its points. A larger cloud is polished coarse to fine: the subsample's plane is
refined by a few Gauss-Newton steps that match the mirror images of ``polish.n_queries``
points to the surface of the whole cloud, until a step moves the normal by less than the
standard error its own residuals allow (see ``docs/design/reflection_plane.md``).
"""

from __future__ import annotations

import dataclasses

import torch

from torchsym.core.random import random_subset
from torchsym.geometry.reflection import plane_angle, reflect_points, reflection_fit
from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.reflection_plane.alternation import alternate, kept_pairs
from torchsym.pointcloud.neighbourhood import neighbourhood_pca
from torchsym.pointcloud.reflection_plane.prealign import point_to_plane_step
from torchsym.pointcloud.prepare import spacing
from torchsym.pointcloud.reflection_plane.settings import PolishSettings, ReflectionPlaneSettings

__all__ = ["Polished", "local_surface", "pair_steps", "polish", "surface_steps"]


@dataclasses.dataclass(frozen=True)
class Polished:
    """The polished plane and the whole cloud's residuals at it.

    Attributes:
        normal: ``(3,)``; offset: ``()`` (normalised units).
        iterations: Algorithm 6 or Gauss-Newton steps taken (0 without the polish).
        converged: whether the steps met their tolerances.
        dist: ``(N,)`` distance from each point's mirror image to its nearest point.
        nn_idx: ``(N,)`` that nearest point.
        spacing: the median nearest-other-point distance of the cloud.
    """

    normal: torch.Tensor
    offset: torch.Tensor
    iterations: int
    converged: bool
    dist: torch.Tensor
    nn_idx: torch.Tensor
    spacing: float


def local_surface(points: torch.Tensor, index: KNNIndex, at: torch.Tensor, k: int) -> tuple[torch.Tensor, torch.Tensor]:
    """The surface of ``points (N, 3)`` near each of ``at (M, 3)``: the centroid ``(M, 3)``
    of the ``k`` nearest points and their least-variance direction ``(M, 3)`` (local PCA).

    The centroid of a neighbourhood, unlike the nearest point, is hardly drawn towards the
    query by the noise across the surface.
    """
    centroid, _, vecs = neighbourhood_pca(points, index, at, k)
    return centroid, vecs[:, :, 0]


def surface_steps(
    queries: torch.Tensor,
    points: torch.Tensor,
    index: KNNIndex,
    normal: torch.Tensor,
    offset: torch.Tensor,
    settings: PolishSettings,
) -> tuple[torch.Tensor, torch.Tensor, int, bool, float]:
    """Gauss-Newton steps for the plane whose mirror images of ``queries (Q, 3)`` lie on the
    surface of ``points (N, 3)`` (``index`` over them): each step matches every mirror image
    to its local surface (:func:`local_surface`, ``settings.n_neighbors`` points) and takes
    one robust point-to-plane step (:func:`~torchsym.pointcloud.reflection_plane.prealign.point_to_plane_step`).
    Ends when the normal moves less than ``settings.tol_se`` standard errors of the step's
    fit, or after ``settings.max_iters`` steps.

    Returns ``(normal (3,), offset (), steps, converged, standard error)`` (the last step's,
    radians).
    """
    it, converged, se = 0, False, float("inf")
    for it in range(1, settings.max_iters + 1):
        centroid, nu = local_surface(points, index, reflect_points(queries, normal, offset), settings.n_neighbors)
        n_new, b_new, se = point_to_plane_step(queries, centroid, nu, normal, offset, robust=True)
        if float((n_new * normal).sum()) < 0:
            n_new, b_new = -n_new, -b_new
        moved = float(plane_angle(n_new, normal))
        normal, offset = n_new, b_new
        if moved < settings.tol_se * se:
            converged = True
            break
    return normal, offset, it, converged, se


def pair_steps(
    points: torch.Tensor, index: KNNIndex, normal: torch.Tensor, offset: torch.Tensor, se: float,
    max_residual: float, max_iters: int,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor, int]:
    """Algorithm 6 steps on every point of ``points (N, 3)`` (``index`` over them; pairs as
    :func:`~torchsym.pointcloud.reflection_plane.alternation.kept_pairs`), each taken only
    when its pairs' fit has a smaller standard error than the plane it replaces (``se``,
    radians, for the first), until a step moves the normal by less than its own standard
    error, or after ``max_iters`` steps.

    Where the cloud holds exact mirror pairs, their fit tightens step by step to the exact
    plane, which steps to a local surface (an average of neighbours) do not reach; on a
    surface without them the first fit is no tighter than the steps before, or moves less
    than its error.

    Returns ``(normal (3,), offset (), residuals (N,), nearest (N,), steps taken)``: the
    whole cloud's residuals at the plane before the last step taken when that step moved
    less than its error, else at the returned plane.
    """
    dist, nn_idx = index.query(reflect_points(points, normal, offset))
    for it in range(max_iters):
        keep = kept_pairs(points, dist, nn_idx, max_residual)
        if int(keep.sum()) <= points.shape[1] + 1:
            return normal, offset, dist, nn_idx, it
        n_new, b_new, se_pairs, _ = reflection_fit(points[keep], points[nn_idx[keep]])
        se_pairs = float(se_pairs)
        if se_pairs >= se:
            return normal, offset, dist, nn_idx, it
        if float((n_new * normal).sum()) < 0:
            n_new, b_new = -n_new, -b_new
        moved = float(plane_angle(n_new, normal))
        normal, offset, se = n_new, b_new, se_pairs
        if moved < se_pairs:
            return normal, offset, dist, nn_idx, it + 1
        dist, nn_idx = index.query(reflect_points(points, normal, offset))
    return normal, offset, dist, nn_idx, max_iters


def polish(
    xs: torch.Tensor,
    index: KNNIndex,
    normal: torch.Tensor,
    offset: torch.Tensor,
    settings: ReflectionPlaneSettings,
    generator: torch.Generator,
    *,
    whole: bool,
) -> Polished:
    """Refine ``(normal, offset)`` on ``xs (N, 3)`` (``index`` over it): Algorithm 6 on every
    point when ``whole`` (the starts were refined on the whole cloud), pairs trimmed at the
    inlier tolerance; else :func:`surface_steps` from ``polish.n_queries`` random points,
    then :func:`pair_steps`. Then measure every point's mirror residual at the plane (on a
    larger cloud, possibly at the plane before the last step, which moved it by less than
    its standard error)."""
    iterations, converged = 0, False
    final = None
    full_spacing = None
    if settings.polish.enabled and whole:
        pol_spacing, full_spacing = spacing(xs, index, generator, q=(settings.spacing_quantile, 0.5))
        normal, offset, iterations, converged, _, pdist, pnn = alternate(
            xs, index, normal, offset, settings.alternation, max_residual=settings.inlier_factor * pol_spacing,
            tol_se=settings.tol_se,
        )
        if pdist is not None:
            final = (pdist, pnn)
    elif settings.polish.enabled:
        queries = xs[random_subset(xs.shape[0], settings.polish.n_queries, generator)]
        normal, offset, iterations, converged, se = surface_steps(queries, xs, index, normal, offset, settings.polish)
        full_spacing = spacing(xs, index, generator, q=(settings.spacing_quantile, 0.5))
        normal, offset, dist, nn_idx, steps = pair_steps(
            xs, index, normal, offset, se, settings.inlier_factor * full_spacing[0], settings.polish.max_iters
        )
        final, full_spacing, iterations = (dist, nn_idx), full_spacing[1], iterations + steps
    if final is None:
        final = index.query(reflect_points(xs, normal, offset))
    if full_spacing is None:
        full_spacing = spacing(xs, index, generator)
    return Polished(normal, offset, int(iterations), bool(converged), final[0], final[1], full_spacing)
