"""Point clouds with planted reflection symmetry, and the corruptions of thesis Sec. 5.2.4.

Everything takes a ``torch.Generator``; the same seed gives the same cloud.
"""

from __future__ import annotations

import dataclasses
import math

import torch

from torchsym.core.checks import as_tensor, check_finite, check_in_range, check_int, check_points, check_positive
from torchsym.errors import InputShapeError, InputValueError
from torchsym.core.random import make_generator
from torchsym.core.results import Result
from torchsym.geometry.reflection import reflect_points
from torchsym.manifolds.special_orthogonal import SpecialOrthogonal
from torchsym.geometry.sampling import sample_surface  # re-exported beside the other samplers

__all__ = [
    "SymmetricCloud",
    "add_outliers",
    "mirror_complete",
    "perturb",
    "planted_symmetric_cloud",
    "random_rigid_motion",
    "remove_part",
    "sample_surface",
]


@dataclasses.dataclass(frozen=True)
class SymmetricCloud(Result):
    """A cloud with a known reflection plane.

    Attributes:
        points: ``(N, 3)`` points.
        normal: ``(3,)`` unit normal of the true plane.
        offset: ``()`` its offset (``normal . x + offset = 0``).
        mirror: ``(N,)`` int64 index of each point's true mirror point, -1 where it has
            none (outliers, points whose mirror was removed).
    """

    points: torch.Tensor
    normal: torch.Tensor
    offset: torch.Tensor
    mirror: torch.Tensor


def random_rigid_motion(
    cloud: SymmetricCloud, *, translation: float = 1.0, generator: torch.Generator | int | None = None
) -> SymmetricCloud:
    """Apply a uniformly random rotation and a Gaussian translation (std ``translation``)."""
    gen = make_generator(generator)
    dt = cloud.points.dtype
    rot = SpecialOrthogonal(3).random_point(generator=gen).to(dt)  # Haar-uniform
    t = torch.randn(3, generator=gen, dtype=torch.float64).to(dt) * translation
    pts = cloud.points @ rot.T + t
    n = rot @ cloud.normal
    # plane n.x + b = 0 moves to (R n).(y - t) + b = 0
    b = cloud.offset - (n * t).sum()
    return SymmetricCloud(pts, n, b, cloud.mirror)


def _mirror_half(half: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor) -> SymmetricCloud:
    m = half.shape[0]
    pts = torch.cat([half, reflect_points(half, normal, offset)])
    mirror = torch.cat([torch.arange(m, 2 * m), torch.arange(m)])
    return SymmetricCloud(pts, normal, offset, mirror)


def planted_symmetric_cloud(
    n: int = 2000, *, n_blobs: int = 6, generator: torch.Generator | int | None = None, dtype: torch.dtype = torch.float32
) -> SymmetricCloud:
    """A random asymmetric shape on one side of a random plane, completed by its mirror image.

    One half is ``n // 2`` points on the surfaces of ``n_blobs`` random ellipsoids; the
    other half is its exact reflection; then the whole is moved rigidly at random.
    """
    n = check_int(n, "n", minimum=4)
    gen = make_generator(generator)
    half_n = n // 2
    centers = torch.rand(n_blobs, 3, generator=gen, dtype=torch.float64) * torch.tensor([0.8, 1.6, 1.2]) + torch.tensor([0.1, -0.8, -0.6])
    axes = 0.1 + 0.4 * torch.rand(n_blobs, 3, generator=gen, dtype=torch.float64)
    which = torch.randint(0, n_blobs, (half_n,), generator=gen)
    d = torch.randn(half_n, 3, generator=gen, dtype=torch.float64)
    d = d / d.norm(dim=1, keepdim=True)
    half = centers[which] + d * axes[which]
    cloud = _mirror_half(half, torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64), torch.tensor(0.0, dtype=torch.float64))
    cloud = random_rigid_motion(cloud, generator=gen)
    return SymmetricCloud(cloud.points.to(dtype), cloud.normal.to(dtype), cloud.offset.to(dtype), cloud.mirror)


def mirror_complete(
    points: torch.Tensor,
    *,
    normal: torch.Tensor | None = None,
    rigid_motion: bool = True,
    generator: torch.Generator | int | None = None,
    dtype: torch.dtype = torch.float32,
) -> SymmetricCloud:
    """Ground truth from real geometry: cut by a random plane through the centre of mass,
    replace the side with fewer points by the mirror of the other, move rigidly at random.

    Args:
        points: ``(N, 3)`` points of a real shape (e.g. :func:`sample_surface` of a mesh).
        normal: ``(3,)`` normal of the cutting plane (any non-zero length), or None for a
            direction uniform on the sphere. A coordinate axis with ``rigid_motion=False``
            gives the pose of the thesis's test data (Sec. 5.2.4, models of the symmetry
            challenge stored upright, their planes along the axes), where the thesis's
            z-favouring perturbation (:func:`perturb`) keeps the symmetry exact.
        rigid_motion: move the result by a uniformly random rotation and translation.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        :class:`SymmetricCloud` with about N points and the exact plane.

    Raises:
        InputShapeError: ``points`` not ``(N, 3)`` with N >= 4, or ``normal`` not ``(3,)``.
        InputValueError: NaN or infinite values, or a zero ``normal``.
    """
    pts = check_points(points, "points", dim=3, min_points=4).to(torch.float64)
    gen = make_generator(generator)
    if normal is None:
        normal = torch.randn(3, generator=gen, dtype=torch.float64)
    else:
        normal = as_tensor(normal, "normal", dtype=torch.float64)
        if normal.shape != (3,):
            raise InputShapeError(f"normal: expected a (3,) vector, got shape {tuple(normal.shape)}")
        check_finite(normal, "normal")
        if float(normal.norm()) == 0.0:
            raise InputValueError("normal: expected a non-zero vector, got a zero vector")
    normal = normal / normal.norm()
    offset = -(normal * pts.mean(0)).sum()
    side = pts @ normal + offset
    half = pts[side >= 0] if int((side >= 0).sum()) >= int((side < 0).sum()) else pts[side < 0]
    cloud = _mirror_half(half, normal, offset)
    if rigid_motion:
        cloud = random_rigid_motion(cloud, translation=float((pts.max(0).values - pts.min(0).values).norm()), generator=gen)
    return SymmetricCloud(cloud.points.to(dtype), cloud.normal.to(dtype), cloud.offset.to(dtype), cloud.mirror)


def add_outliers(cloud: SymmetricCloud, tau: float, *, generator: torch.Generator | int | None = None) -> SymmetricCloud:
    """Add ``tau`` percent of ``N`` outliers uniform in the bounding box enlarged to twice its size (thesis 5.2.4)."""
    check_positive(tau, "tau", allow_zero=True)
    gen = make_generator(generator)
    pts = cloud.points
    m = int(round(tau * pts.shape[0] / 100.0))
    lo, hi = pts.min(0).values, pts.max(0).values
    mid, ext = 0.5 * (lo + hi), hi - lo
    noise = mid + (torch.rand(m, 3, generator=gen, dtype=torch.float64).to(pts.dtype) - 0.5) * 2.0 * ext
    mirror = torch.cat([cloud.mirror, torch.full((m,), -1, dtype=torch.int64)])
    return SymmetricCloud(torch.cat([pts, noise]), cloud.normal, cloud.offset, mirror)


def perturb(
    cloud: SymmetricCloud, w: float, *, isotropic: bool = False, generator: torch.Generator | int | None = None
) -> SymmetricCloud:
    """Move every point by ``r (sin t cos p, sin t sin p, cos t)`` with ``r ~ U(0, h)``,
    ``t ~ U(0, pi)``, ``p ~ U(0, 2 pi)`` and ``h = w x min box side / 100`` (thesis 5.2.4).

    Drawing ``t`` uniformly, as the thesis does, puts twice the variance on the z axis as
    on x or y: on a cloud whose plane is not upright this anisotropy itself breaks the
    symmetry. ``isotropic=True`` draws ``cos t ~ U(-1, 1)`` instead (directions uniform on
    the sphere), which blurs the shape without favouring any direction.
    """
    check_positive(w, "w", allow_zero=True)
    gen = make_generator(generator)
    pts = cloud.points
    ext = pts.max(0).values - pts.min(0).values
    h = w * float(ext.min()) / 100.0
    n = pts.shape[0]
    r = torch.rand(n, generator=gen, dtype=torch.float64) * h
    u = torch.rand(n, generator=gen, dtype=torch.float64)
    t = torch.acos(1.0 - 2.0 * u) if isotropic else u * math.pi
    p = torch.rand(n, generator=gen, dtype=torch.float64) * 2 * math.pi
    d = torch.stack([r * torch.sin(t) * torch.cos(p), r * torch.sin(t) * torch.sin(p), r * torch.cos(t)], 1)
    return SymmetricCloud(pts + d.to(pts.dtype), cloud.normal, cloud.offset, cloud.mirror)


def remove_part(cloud: SymmetricCloud, eta: float, *, generator: torch.Generator | int | None = None) -> SymmetricCloud:
    """Remove a contiguous part holding ``eta`` of the points: the ``eta N`` points nearest
    to a random point of the cloud (thesis 5.2.4 "missing parts")."""
    check_in_range(eta, "eta", 0.0, 0.95)
    gen = make_generator(generator)
    pts = cloud.points
    n = pts.shape[0]
    m = int(round(eta * n))
    if m == 0:
        return cloud
    seed = pts[int(torch.randint(0, n, (1,), generator=gen))]
    gone = (pts - seed).norm(dim=1).argsort()[:m]
    keep = torch.ones(n, dtype=torch.bool)
    keep[gone] = False
    new_index = torch.full((n,), -1, dtype=torch.int64)
    new_index[keep] = torch.arange(int(keep.sum()))
    old_mirror = cloud.mirror[keep]
    mirror = torch.where(old_mirror >= 0, new_index[old_mirror.clamp_min(0)], old_mirror)
    return SymmetricCloud(pts[keep], cloud.normal, cloud.offset, mirror)
