"""The special orthogonal group SO(n) of rotation matrices."""

from __future__ import annotations

import math

import torch

from torchsym.core.random import make_generator
from torchsym.errors import InputValueError
from torchsym.manifolds._matrix import polar, qr_unique, skew, sym
from torchsym.manifolds.base import Manifold, _float_tol

__all__ = ["SpecialOrthogonal"]

_RETRACTIONS = ("qr", "cayley", "polar", "exp")


class SpecialOrthogonal(Manifold):
    """``SO(n) = {R in R^{n x n} : R^T R = I, det R = 1}`` with the embedded metric.

    Points are ``(..., n, n)``. A tangent vector at ``R`` is stored as the ambient matrix
    ``R Omega`` with ``Omega`` skew-symmetric (thesis Eq. 7.6); the inner product is
    ``trace(Omega_1^T Omega_2)`` (Eq. 7.7), the projection ``R skew(R^T U)`` (Sec. 7.2.2)
    and the Riemannian Hessian ``proj(H - U sym(R^T G))``.

    Args:
        n: size of the matrices, ``n >= 1``.
        retraction: ``"qr"`` (Q factor of ``R + U`` with positive ``diag``, the default),
            ``"cayley"`` (``R (I - Omega/2)^{-1} (I + Omega/2)``), ``"polar"`` (orthogonal
            polar factor of ``R + U``) or ``"exp"`` (``R expm(Omega)``, the exponential map).

    Example:
        >>> so3 = SpecialOrthogonal(3)
        >>> r = so3.random_point(generator=torch.Generator().manual_seed(0))
        >>> so3.check_point(so3.retr(r, so3.random_tangent(r)))
        (True, '')
    """

    name = "SpecialOrthogonal"

    def __init__(self, n: int, retraction: str = "qr") -> None:
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise InputValueError(f"n: expected an integer >= 1, got {n!r}")
        if retraction not in _RETRACTIONS:
            raise InputValueError(f"retraction: expected one of {', '.join(map(repr, _RETRACTIONS))}, got {retraction!r}")
        self.n, self.retraction = n, retraction
        self.point_shape = (n, n)
        self.dim = n * (n - 1) // 2

    def _repr_args(self) -> str:
        return f"n={self.n}, retraction={self.retraction!r}"

    @property
    def typical_dist(self) -> float:
        return math.pi * math.sqrt(self.n)

    def _check_values(self, x: torch.Tensor) -> tuple[bool, str]:
        eye = torch.eye(self.n, dtype=x.dtype, device=x.device)
        tol = _float_tol(x.dtype, self.n)
        err = float((x.transpose(-1, -2) @ x - eye).abs().max()) if x.numel() else 0.0
        if err > tol:
            return False, f"expected an orthogonal matrix (R^T R = I), got an error of {err:.3g}"
        if x.numel() and bool((torch.linalg.det(x) < 0).any()):
            return False, "expected determinant +1, got a reflection (determinant -1)"
        return True, ""

    def proju(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return x @ skew(x.transpose(-1, -2) @ u)

    def ehess2rhess(self, x: torch.Tensor, g: torch.Tensor, h: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return self.proju(x, h - u @ sym(x.transpose(-1, -2) @ g))

    def retr(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        if self.retraction == "exp":
            return self.expmap(x, u)
        if self.retraction == "polar":
            return polar(x + u, special=True)
        if self.retraction == "cayley":
            omega = skew(x.transpose(-1, -2) @ u)
            eye = torch.eye(self.n, dtype=x.dtype, device=x.device)
            return x @ torch.linalg.solve(eye - 0.5 * omega, eye + 0.5 * omega)
        # x (I + Omega) has positive determinant, so its unique Q factor is a rotation.
        omega = skew(x.transpose(-1, -2) @ u)
        eye = torch.eye(self.n, dtype=x.dtype, device=x.device)
        return x @ qr_unique(eye + omega)

    def expmap(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return x @ torch.linalg.matrix_exp(skew(x.transpose(-1, -2) @ u))

    def projx(self, x: torch.Tensor) -> torch.Tensor:
        """The nearest rotation in Frobenius norm (polar factor with the determinant fixed)."""
        return polar(x, special=True)

    def random_point(self, *batch: int, generator: torch.Generator | None = None, dtype: torch.dtype = torch.float64) -> torch.Tensor:
        """A Haar-uniform random rotation (Q factor of a Gaussian matrix, one column flipped if det < 0)."""
        g = make_generator(generator)
        q = qr_unique(torch.randn(*batch, self.n, self.n, generator=g, dtype=dtype))
        det = torch.linalg.det(q)
        flip = torch.ones(q.shape[:-1], dtype=dtype)
        flip[..., 0] = torch.where(det < 0, -torch.ones_like(det), torch.ones_like(det))
        return q * flip.unsqueeze(-2)
