"""Normalise a cloud and draw the samples the detector works on (thesis Sec. 5.2.3).

Every later stage works in normalised coordinates: centred at the coordinate-wise median,
unit bounding-box diagonal.
"""

from __future__ import annotations

import dataclasses
import math

import torch

from torchsym.core.random import random_subset
from torchsym.errors import InputValueError
from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.reflection_plane.settings import DenseSettings, ReflectionPlaneSettings

__all__ = ["Normalised", "Subsample", "dense_part", "nn_probe", "normalise", "spacing", "subsample"]

# coordinates beyond 2^±BIG_EXPONENT are rescaled by a power of two (exactly) before
# their squares are formed
_BIG_EXPONENT = 400


@dataclasses.dataclass(frozen=True)
class Normalised:
    """A cloud in normalised coordinates ``x = scale * xs + origin``.

    Attributes:
        xs: ``(N, 3)`` float64 points, unit bounding-box diagonal.
        origin: ``(3,)`` the coordinate-wise median, in input units.
        scale: the bounding-box diagonal, in input units.
        centered: ``(N, 3)`` the points centred at their mean (up to a power-of-two
            scale), whose covariance gives the principal axes.
    """

    xs: torch.Tensor
    origin: torch.Tensor
    scale: float
    centered: torch.Tensor


def normalise(x: torch.Tensor, input_dtype: torch.dtype) -> Normalised:
    """Centre ``x (N, 3)`` (float64) at its median and scale it to a unit diagonal.

    Coordinates of any finite magnitude are accepted: a cloud far from 1 in scale is first
    multiplied by a power of two (exact), so no square overflows or underflows.

    Raises:
        InputValueError: every point the same, all points on one line (relative to the
            rounding of ``input_dtype``), or a bounding box too large for float64.
    """
    n = x.shape[0]
    amax = float(x.abs().max())
    shift = 0
    if amax > 0 and abs(math.frexp(amax)[1]) > _BIG_EXPONENT:
        shift = math.frexp(amax)[1]
        x = torch.ldexp(x, torch.tensor(-shift, dtype=x.dtype))
    lo, hi = x.min(0).values, x.max(0).values
    scale = float((hi - lo).norm())
    centered = x - x.mean(0)
    sv = torch.linalg.svdvals(centered.double())
    # the second singular value is at rounding level of the coordinates: one line
    if scale == 0:
        raise InputValueError(f"points: expected a cloud spanning at least a plane, got {n} copies of one point")
    if float(sv[1]) <= 1e3 * torch.finfo(input_dtype).eps * float(sv[0]):
        raise InputValueError(f"points: expected a cloud spanning at least a plane, got {n} points on one line")
    origin = x.median(0).values
    xs = (x - origin) / scale  # (N, 3), diagonal 1
    if shift:
        try:
            scale = math.ldexp(scale, shift)
        except OverflowError:
            raise InputValueError(
                f"points: expected a bounding box whose diagonal is finite in float64, got coordinates up to {amax:.3g}"
            ) from None
        origin = torch.ldexp(origin, torch.tensor(shift, dtype=x.dtype))
    return Normalised(xs, origin, scale, centered)


def nn_probe(points: torch.Tensor, index: KNNIndex, generator: torch.Generator) -> torch.Tensor:
    """Distances ``(M,)`` from up to 1,000 random points to their nearest other point at
    a positive distance (among the nearest 8: a point listed up to 7 times, as in a
    cloud whose every point is there twice, still has a spacing).

    Probes with no positive distance among them are left out, unless every probe is one.
    """
    probe = points[random_subset(points.shape[0], 1000, generator)]
    k = min(8, points.shape[0])
    d, _ = index.query(probe, k=k)
    d = d.reshape(probe.shape[0], -1)[:, 1:]
    d = torch.where(d > 0, d, torch.full_like(d, float("inf"))).min(1).values if d.shape[1] else d.new_zeros(probe.shape[0])
    positive = d[torch.isfinite(d)]
    return positive if positive.numel() else torch.zeros_like(d)


def spacing(points: torch.Tensor, index: KNNIndex, generator: torch.Generator, q: float | tuple[float, ...] = 0.5):
    """Quantile ``q`` of the nearest-other-point distance on up to 1,000 random points
    (a tuple of quantiles gives a tuple, from one query)."""
    d = nn_probe(points, index, generator)
    if isinstance(q, tuple):
        return tuple(float(v) for v in d.quantile(torch.tensor(q, dtype=d.dtype, device=d.device)))
    return float(d.quantile(q))


def dense_part(points: torch.Tensor, index: KNNIndex, settings: DenseSettings | None = None) -> tuple[torch.Tensor, KNNIndex]:
    """The points of the sampled surface without most scattered points, and their index.

    A point is kept when its ``n_neighbors``-th nearest neighbour is within ``factor``
    times the ``quantile`` quantile of those distances (over positive distances). The whole
    set is returned when every point passes or fewer than 4 would.
    """
    s = settings if settings is not None else DenseSettings()
    k = min(s.n_neighbors + 1, points.shape[0])
    dk = index.query(points, k=k)[0][:, -1]
    positive = dk[dk > 0]
    if positive.numel() == 0:
        return points, index
    keep = dk <= s.factor * float(positive.quantile(s.quantile))
    if int(keep.sum()) < 4 or bool(keep.all()):
        return points, index
    return points[keep], KNNIndex(points[keep])


@dataclasses.dataclass(frozen=True)
class Subsample:
    """The samples the starts are scored and refined on.

    Attributes:
        sample: ``(n2, 3)`` points that score the candidate normals (Algorithm 5's ``Ps``).
        sub_idx: ``(M,)`` indices of the refinement subsample, or None for the whole cloud.
        sub: ``(M, 3)`` the refinement subsample.
        index: nearest-neighbour index over ``sub``.
        spacing: the ``spacing_quantile`` quantile of ``sub``'s neighbour distances.
        dense: ``sub``'s dense part and its index, when many points are sparse; else None.
        centered: ``(K, 3)`` centred points whose covariance gives the principal axes.
    """

    sample: torch.Tensor
    sub_idx: torch.Tensor | None
    sub: torch.Tensor
    index: KNNIndex
    spacing: float
    dense: tuple[torch.Tensor, KNNIndex] | None
    centered: torch.Tensor


def subsample(norm: Normalised, settings: ReflectionPlaneSettings, generator: torch.Generator) -> Subsample:
    """Draw Algorithm 5's sample and the refinement subsample; measure the spacing.

    When at least ``dense.min_sparse_share`` of the points are sparse (outliers), the
    sample and the principal axes come from the subsample's dense part.
    """
    xs, n = norm.xs, norm.xs.shape[0]
    sample = xs[random_subset(n, settings.init.n_samples, generator)]  # (n2, 3)
    sub_idx = random_subset(n, settings.refine.n_samples, generator) if n > settings.refine.n_samples else None
    sub = xs[sub_idx] if sub_idx is not None else xs
    index = KNNIndex(sub)
    probe = nn_probe(sub, index, generator)
    space = float(probe.quantile(settings.spacing_quantile))
    dense = None
    centered = norm.centered
    sparse = float((probe > settings.dense.sparse_factor * space).double().mean())
    if space > 0 and sparse >= settings.dense.min_sparse_share:
        dense = dense_part(sub, index, settings.dense)
        core = dense[0]
        if int(core.shape[0]) >= 4:
            sample = core[random_subset(core.shape[0], settings.init.n_samples, generator)]
            centered = core - core.mean(0)
    return Subsample(sample, sub_idx, sub, index, space, dense, centered)
