"""The Euclidean space R^{shape}."""

from __future__ import annotations

import math

import torch

from torchsym.core.random import make_generator
from torchsym.errors import InputValueError
from torchsym.manifolds.base import Manifold

__all__ = ["Euclidean"]


class Euclidean(Manifold):
    """Tensors of a fixed trailing ``shape`` with the Frobenius metric (e.g. a translation in R^d).

    Args:
        shape: the trailing dimensions of a point; ``Euclidean(3)`` is R^3 with points
            ``(..., 3)``, ``Euclidean(2, 4)`` is R^{2 x 4}, ``Euclidean()`` the reals.
    """

    name = "Euclidean"

    def __init__(self, *shape: int) -> None:
        if any(isinstance(s, bool) or not isinstance(s, int) or s < 1 for s in shape):
            raise InputValueError(f"shape: expected positive integers, got {shape!r}")
        self.point_shape = tuple(shape)
        self.dim = math.prod(shape)

    def _repr_args(self) -> str:
        return ", ".join(str(s) for s in self.point_shape)

    def proju(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return u

    def egrad2rgrad(self, x: torch.Tensor, g: torch.Tensor) -> torch.Tensor:
        return g

    def ehess2rhess(self, x: torch.Tensor, g: torch.Tensor, h: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return h

    def retr(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return x + u

    def expmap(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return x + u

    def transp(self, x: torch.Tensor, y: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return u

    def projx(self, x: torch.Tensor) -> torch.Tensor:
        return x

    def random_point(self, *batch: int, generator: torch.Generator | None = None, dtype: torch.dtype = torch.float64) -> torch.Tensor:
        g = make_generator(generator)
        return torch.randn((*batch, *self.point_shape), generator=g, dtype=dtype)
