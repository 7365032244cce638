"""Seeded synthetic point sets with a planted reflection symmetry (thesis Secs. 7.4.2-7.4.3)."""

from __future__ import annotations

import dataclasses

import torch

from torchsym.core.checks import check_int, check_positive
from torchsym.core.random import make_generator
from torchsym.core.results import Result
from torchsym.errors import InputShapeError

__all__ = ["SyntheticPointSet", "make_symmetric_pointset"]


@dataclasses.dataclass(frozen=True)
class SyntheticPointSet(Result):
    """A point set with a known reflection symmetry.

    Attributes:
        points: ``(N, D)`` the perturbed points.
        clean: ``(N, D)`` the same points before the perturbation (exactly symmetric).
        normal: ``(D,)`` unit normal of the true hyperplane ``normal . x + offset = 0``.
        offset: ``()`` its offset.
        correspondence: ``(N,)`` int64, the index of each point's true mirror (itself for
            a point generated on the plane).
        sigma2: the perturbation variance ``sigma^2``.
    """

    points: torch.Tensor
    clean: torch.Tensor
    normal: torch.Tensor
    offset: torch.Tensor
    correspondence: torch.Tensor
    sigma2: float


def make_symmetric_pointset(
    n: int,
    d: int,
    sigma2: float = 0.0,
    *,
    normal: torch.Tensor | None = None,
    shuffle: bool = True,
    dtype: torch.dtype = torch.float64,
    generator: torch.Generator | None = None,
) -> SyntheticPointSet:
    """A symmetric set built as in Sec. 7.4.2: ``n/2`` points and their reflections, then noise.

    ``n // 2`` points are drawn uniformly in ``[0, 1]^D`` and reflected through a hyperplane
    with a random (or the given) unit normal passing through the centre ``(1/2, ..., 1/2)``
    of the cube (Definition 7.2.1); for odd ``n`` one more point is placed on the hyperplane.
    Every point is then moved by independent noise ``N(0, sigma2 I)`` (the thesis's
    "perturbation radius" ``sigma^2``; it uses ``D`` in {2, 3, 6, 8}, ``n`` in 50..300 and
    ``sigma^2`` in 0..0.1).

    Args:
        n: number of points, ``n >= 2``.
        d: dimension, ``d >= 2``.
        sigma2: noise variance ``sigma^2 >= 0``.
        normal: ``(D,)`` normal of the plane; None draws one uniformly on the sphere.
        shuffle: put the points in random order (else originals first, then mirrors).
        dtype: floating dtype of the tensors.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        :class:`SyntheticPointSet`.

    Example:
        >>> s = make_symmetric_pointset(10, 3, generator=torch.Generator().manual_seed(1))
        >>> s.points.shape, bool((s.points[s.correspondence] - s.clean[s.correspondence]).abs().max() == 0)
        (torch.Size([10, 3]), True)
    """
    n = check_int(n, "n", minimum=2)
    d = check_int(d, "d", minimum=2)
    sigma2 = check_positive(sigma2, "sigma2", allow_zero=True)
    g = make_generator(generator)
    if normal is None:
        nrm = torch.randn(d, generator=g, dtype=torch.float64)
    else:
        nrm = torch.as_tensor(normal, dtype=torch.float64)
        if nrm.shape != (d,) or float(nrm.norm()) == 0.0:
            raise InputShapeError(f"normal: expected a non-zero ({d},) vector, got {tuple(nrm.shape)}")
    nrm = nrm / nrm.norm()
    centre = torch.full((d,), 0.5, dtype=torch.float64)
    offset = -(nrm @ centre)
    half = n // 2
    x = torch.rand(half, d, generator=g, dtype=torch.float64)
    mirror = x - 2.0 * ((x @ nrm + offset)[:, None]) * nrm
    parts = [x, mirror]
    corr = [torch.arange(half, 2 * half), torch.arange(half)]
    if n % 2:
        on = torch.rand(1, d, generator=g, dtype=torch.float64)
        on = on - ((on @ nrm + offset)[:, None]) * nrm
        parts.append(on)
        corr.append(torch.tensor([2 * half]))
    clean = torch.cat(parts)  # (N, D)
    correspondence = torch.cat(corr)
    if shuffle:
        order = torch.randperm(n, generator=g)
        inverse = torch.empty_like(order)
        inverse[order] = torch.arange(n)
        clean = clean[order]
        correspondence = inverse[correspondence[order]]
    noise = torch.randn(n, d, generator=g, dtype=torch.float64) * (sigma2**0.5)
    return SyntheticPointSet(
        points=(clean + noise).to(dtype),
        clean=clean.to(dtype),
        normal=nrm.to(dtype),
        offset=offset.to(dtype),
        correspondence=correspondence,
        sigma2=sigma2,
    )
