"""The Stiefel manifold St(n, p) of n x p matrices with orthonormal columns."""

from __future__ import annotations

import math

import torch

from torchsym.core.random import make_generator
from torchsym.errors import InputValueError
from torchsym.manifolds._matrix import polar, qr_unique, sym
from torchsym.manifolds.base import Manifold, _float_tol

__all__ = ["Stiefel"]

_RETRACTIONS = ("qr", "cayley", "polar", "exp")


class Stiefel(Manifold):
    """``St(n, p) = {X in R^{n x p} : X^T X = I_p}`` with the embedded (Frobenius) metric.

    Points are ``(..., n, p)``. The tangent space at ``X`` is ``{U : X^T U + U^T X = 0}``;
    the projection is ``U - X sym(X^T U)`` and the Riemannian Hessian
    ``proj(H - U sym(X^T G))`` (Absil, Mahony & Sepulchre 2008, Sec. 5.5).

    Args:
        n: number of rows.
        p: number of columns, ``1 <= p <= n``.
        retraction: ``"qr"`` (Q factor of ``X + U`` with positive ``diag(R)``),
            ``"cayley"`` (``(I - W/2)^{-1} (I + W/2) X`` with the skew
            ``W = P U X^T - X U^T P``, ``P = I - X X^T / 2``, Wen and Yin 2013; computed
            through the Woodbury identity with a ``2p x 2p`` solve, so ``O(n p^2)``),
            ``"polar"`` (orthogonal polar factor of ``X + U``) or ``"exp"`` (the
            geodesic, :meth:`expmap`; a ``2p x 2p`` matrix exponential).
    """

    name = "Stiefel"

    def __init__(self, n: int, p: int, retraction: str = "qr") -> None:
        if isinstance(n, bool) or not isinstance(n, int) or isinstance(p, bool) or not isinstance(p, int) or not 1 <= p <= n:
            raise InputValueError(f"n, p: expected integers with 1 <= p <= n, got n={n!r}, p={p!r}")
        if retraction not in _RETRACTIONS:
            raise InputValueError(f"retraction: expected one of {', '.join(map(repr, _RETRACTIONS))}, got {retraction!r}")
        self.n, self.p, self.retraction = n, p, retraction
        self.point_shape = (n, p)
        self.dim = n * p - p * (p + 1) // 2

    def _repr_args(self) -> str:
        return f"n={self.n}, p={self.p}, retraction={self.retraction!r}"

    @property
    def typical_dist(self) -> float:
        return math.sqrt(self.p)

    def _check_values(self, x: torch.Tensor) -> tuple[bool, str]:
        eye = torch.eye(self.p, dtype=x.dtype, device=x.device)
        err = float((x.transpose(-1, -2) @ x - eye).abs().max()) if x.numel() else 0.0
        if err > _float_tol(x.dtype, self.n):
            return False, f"expected orthonormal columns (X^T X = I), got an error of {err:.3g}"
        return True, ""

    def proju(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return u - x @ sym(x.transpose(-1, -2) @ u)

    def ehess2rhess(self, x: torch.Tensor, g: torch.Tensor, h: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return self.proju(x, h - u @ sym(x.transpose(-1, -2) @ g))

    def retr(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        if self.retraction == "polar":
            return polar(x + u)
        if self.retraction == "cayley":
            return self._cayley(x, u)
        if self.retraction == "exp":
            return self.expmap(x, u)
        return qr_unique(x + u)

    def _cayley(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        # W = A B^T with A = [P U, X], B = [X, -P U]; (I - W/2)^{-1} (I + W/2) X
        # = X + A (I - B^T A / 2)^{-1} B^T X (Woodbury).
        pu = u - 0.5 * x @ (x.transpose(-1, -2) @ u)
        a = torch.cat([pu, x], -1)  # (..., n, 2p)
        b = torch.cat([x, -pu], -1)
        eye = torch.eye(2 * self.p, dtype=x.dtype, device=x.device)
        btx = b.transpose(-1, -2) @ x  # (..., 2p, p)
        return x + a @ torch.linalg.solve(eye - 0.5 * b.transpose(-1, -2) @ a, btx)

    def expmap(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """The geodesic of the embedded metric (Edelman, Arias & Smith 1998, Eq. 2.14)."""
        p = self.p
        a = x.transpose(-1, -2) @ u  # (..., p, p)
        utu = u.transpose(-1, -2) @ u
        eye = torch.eye(p, dtype=x.dtype, device=x.device).expand_as(a)
        block = torch.cat([torch.cat([a, -utu], -1), torch.cat([eye, a], -1)], -2)  # (..., 2p, 2p)
        right = torch.cat([torch.linalg.matrix_exp(-a), torch.zeros_like(a)], -2)  # (..., 2p, p)
        return torch.cat([x, u], -1) @ torch.linalg.matrix_exp(block) @ right

    def projx(self, x: torch.Tensor) -> torch.Tensor:
        return polar(x)

    def random_point(self, *batch: int, generator: torch.Generator | None = None, dtype: torch.dtype = torch.float64) -> torch.Tensor:
        g = make_generator(generator)
        a = torch.randn(*batch, self.n, self.p, generator=g, dtype=dtype)
        return qr_unique(a)
