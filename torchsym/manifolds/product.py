"""Products of manifolds; points and tangent vectors are tuples."""

from __future__ import annotations

import math

import torch

from torchsym.core.random import make_generator
from torchsym.errors import InputValueError
from torchsym.manifolds.base import Manifold

__all__ = ["ProductManifold"]


class ProductManifold(Manifold):
    """``M_1 x ... x M_k`` with the sum metric (thesis Sec. 7.2.2, Eq. 7.7).

    A point is a tuple ``(x_1, ..., x_k)`` with ``x_i`` a point of ``M_i``; tangent
    vectors are tuples in the same order. Every operation acts componentwise; ``inner``
    adds the components' inner products. The components' batch dimensions must match.

    Args:
        manifolds: the factors, at least one.

    Example:
        >>> from torchsym.manifolds import PlaneRotations, Euclidean
        >>> m = ProductManifold(PlaneRotations(3, (0, 2)), PlaneRotations(3, (1, 2)), Euclidean(3))
        >>> r1, r2, t = m.random_point()
        >>> m.dim
        5
    """

    name = "ProductManifold"

    def __init__(self, *manifolds: Manifold) -> None:
        if not manifolds or not all(isinstance(m, Manifold) for m in manifolds):
            raise InputValueError(f"manifolds: expected one or more Manifold instances, got {manifolds!r}")
        self.manifolds = tuple(manifolds)
        self.dim = sum(m.dim for m in manifolds)

    def _repr_args(self) -> str:
        return ", ".join(repr(m) for m in self.manifolds)

    @property
    def typical_dist(self) -> float:
        return math.sqrt(sum(m.typical_dist**2 for m in self.manifolds))

    def batch_shape(self, x):
        return self.manifolds[0].batch_shape(x[0])

    def total_dim(self, x) -> int:
        return sum(m.total_dim(xi) for m, xi in zip(self.manifolds, x))

    def check_shape(self, x) -> tuple[bool, str]:
        k = len(self.manifolds)
        if not isinstance(x, (tuple, list)) or len(x) != k:
            got = f"a {type(x).__name__} of length {len(x)}" if isinstance(x, (tuple, list)) else type(x).__name__
            return False, f"expected a tuple of {k} components for {self}, got {got}"
        for i, (m, xi) in enumerate(zip(self.manifolds, x)):
            ok, reason = m.check_shape(xi)
            if not ok:
                return False, f"component {i}: {reason}"
        batches = {tuple(m.batch_shape(xi)) for m, xi in zip(self.manifolds, x)}
        if len(batches) > 1:
            return False, f"expected the same batch dimensions in every component, got {sorted(batches)}"
        return True, ""

    def check_point(self, x) -> tuple[bool, str]:
        ok, reason = self.check_shape(x)
        if not ok:
            return ok, reason
        for i, (m, xi) in enumerate(zip(self.manifolds, x)):
            ok, reason = m.check_point(xi)
            if not ok:
                return False, f"component {i}: {reason}"
        return True, ""

    def check_vector(self, x, u) -> tuple[bool, str]:
        ok, reason = self.check_shape(u)
        if not ok:
            return ok, reason
        for i, (m, xi, ui) in enumerate(zip(self.manifolds, x, u)):
            ok, reason = m.check_vector(xi, ui)
            if not ok:
                return False, f"component {i}: {reason}"
        return True, ""

    def inner(self, x, u, v) -> torch.Tensor:
        return sum(m.inner(xi, ui, vi) for m, xi, ui, vi in zip(self.manifolds, x, u, v))

    def proju(self, x, u):
        return tuple(m.proju(xi, ui) for m, xi, ui in zip(self.manifolds, x, u))

    def projx(self, x):
        return tuple(m.projx(xi) for m, xi in zip(self.manifolds, x))

    def egrad2rgrad(self, x, g):
        return tuple(m.egrad2rgrad(xi, gi) for m, xi, gi in zip(self.manifolds, x, g))

    def ehess2rhess(self, x, g, h, u):
        return tuple(m.ehess2rhess(xi, gi, hi, ui) for m, xi, gi, hi, ui in zip(self.manifolds, x, g, h, u))

    def retr(self, x, u):
        return tuple(m.retr(xi, ui) for m, xi, ui in zip(self.manifolds, x, u))

    def expmap(self, x, u):
        return tuple(m.expmap(xi, ui) for m, xi, ui in zip(self.manifolds, x, u))

    def transp(self, x, y, u):
        return tuple(m.transp(xi, yi, ui) for m, xi, yi, ui in zip(self.manifolds, x, y, u))

    def random_point(self, *batch: int, generator: torch.Generator | None = None, dtype: torch.dtype = torch.float64):
        g = make_generator(generator)
        return tuple(m.random_point(*batch, generator=g, dtype=dtype) for m in self.manifolds)

    def random_tangent(self, x, generator: torch.Generator | None = None):
        g = make_generator(generator)
        return tuple(m.random_tangent(xi, generator=g) for m, xi in zip(self.manifolds, x))

    def zero_vector(self, x):
        return tuple(m.zero_vector(xi) for m, xi in zip(self.manifolds, x))
