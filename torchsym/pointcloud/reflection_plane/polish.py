"""Algorithm 6 from the winning start on the whole cloud (thesis Sec. 5.2.3), and the
residuals of the whole cloud at the resulting plane."""

from __future__ import annotations

import dataclasses

import torch

from torchsym.core.random import random_subset
from torchsym.geometry.reflection import reflect_points
from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.reflection_plane.alternation import alternate
from torchsym.pointcloud.reflection_plane.prepare import spacing
from torchsym.pointcloud.reflection_plane.settings import ReflectionPlaneSettings

__all__ = ["Polished", "polish"]


@dataclasses.dataclass(frozen=True)
class Polished:
    """The polished plane and the whole cloud's residuals at it.

    Attributes:
        normal: ``(3,)``; offset: ``()`` (normalised units).
        iterations: Algorithm 6 steps taken (0 without the polish).
        converged: whether the steps met the tolerances.
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


def polish(
    xs: torch.Tensor,
    index: KNNIndex,
    normal: torch.Tensor,
    offset: torch.Tensor,
    settings: ReflectionPlaneSettings,
    generator: torch.Generator,
) -> Polished:
    """Run Algorithm 6 from ``(normal, offset)`` on ``xs (N, 3)`` (``index`` over it), or on
    ``polish.n_samples`` random points of a larger cloud, pairs trimmed at the inlier
    tolerance; then measure every point's mirror residual at the plane."""
    n = xs.shape[0]
    iterations, converged = 0, False
    final = full_spacing = None
    if settings.polish.enabled:
        if n > settings.polish.n_samples:
            pol = xs[random_subset(n, settings.polish.n_samples, generator)]
            pol_index = KNNIndex(pol)
            pol_spacing = spacing(pol, pol_index, generator, q=settings.spacing_quantile)
        else:
            pol, pol_index = xs, index
            pol_spacing, full_spacing = spacing(xs, index, generator, q=(settings.spacing_quantile, 0.5))
        normal, offset, iterations, converged, _, pdist, pnn = alternate(
            pol, pol_index, normal, offset, settings.alternation, max_residual=settings.inlier_factor * pol_spacing,
            tol_se=settings.tol_se,
        )
        if pol is xs and pdist is not None:
            final = (pdist, pnn)
    if final is None:
        final = index.query(reflect_points(xs, normal, offset))
    if full_spacing is None:
        full_spacing = spacing(xs, index, generator)
    return Polished(normal, offset, int(iterations), bool(converged), final[0], final[1], full_spacing)
