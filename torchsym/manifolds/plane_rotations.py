"""SO(2, d): rotations of R^d that act on one coordinate plane only (thesis Sec. 7.2.2)."""

from __future__ import annotations

import math

import torch

from torchsym.core.random import make_generator
from torchsym.errors import InputValueError
from torchsym.manifolds._matrix import sym
from torchsym.manifolds.base import Manifold, _float_tol

__all__ = ["PlaneRotations", "plane_rotation"]


def plane_rotation(angle: torch.Tensor, d: int, plane: tuple[int, int]) -> torch.Tensor:
    """The ``(..., d, d)`` rotation by ``angle (...)`` radians in the coordinate plane ``(i, j)``.

    It maps ``e_i`` to ``cos(a) e_i + sin(a) e_j``; every other axis is fixed.
    """
    i, j = plane
    c, s = torch.cos(angle), torch.sin(angle)
    out = torch.eye(d, dtype=angle.dtype, device=angle.device).expand(*angle.shape, d, d).clone()
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., j, i] = s
    out[..., i, j] = -s
    return out


class PlaneRotations(Manifold):
    """``SO(2, d)``: the one-parameter group of rotations of R^d in the plane ``(i, j)``.

    The thesis writes its reflections with ``d - 1`` such rotations, each turning one axis
    (Sec. 7.2.1, Eq. 7.1); all of them "form a SO(2) embedded in the Euclidean space
    R^{d x d}" (Sec. 7.2.2). Points are ``(..., d, d)`` matrices; the tangent space at ``R``
    is ``{theta R G}`` with the generator ``G = e_j e_i^T - e_i e_j^T``, and the metric is the
    embedded one (Eq. 7.7), so ``|theta R G| = sqrt(2) |theta|``. The exponential map is the
    exact rotation by ``theta`` and serves as the retraction. The Riemannian Hessian is
    ``proj(H - U sym(R^T G))``, the same formula as for SO(d).

    Args:
        d: dimension of the space, ``d >= 2``.
        plane: the two coordinate axes ``(i, j)`` spanning the plane, ``0 <= i != j < d``.
    """

    name = "PlaneRotations"

    def __init__(self, d: int, plane: tuple[int, int] = (0, 1)) -> None:
        if isinstance(d, bool) or not isinstance(d, int) or d < 2:
            raise InputValueError(f"d: expected an integer >= 2, got {d!r}")
        try:
            i, j = (int(v) for v in plane)
        except (TypeError, ValueError):
            raise InputValueError(f"plane: expected two axis indices (i, j), got {plane!r}") from None
        if not (0 <= i < d and 0 <= j < d and i != j):
            raise InputValueError(f"plane: expected two different axes in [0, {d}), got {plane!r}")
        self.d, self.plane = d, (i, j)
        self.point_shape = (d, d)
        self.dim = 1

    def _repr_args(self) -> str:
        return f"d={self.d}, plane={self.plane}"

    @property
    def typical_dist(self) -> float:
        return math.pi * math.sqrt(2.0)

    def angle(self, x: torch.Tensor) -> torch.Tensor:
        """The rotation angle ``(...)`` of points ``x``, in ``(-pi, pi]``."""
        i, j = self.plane
        return torch.atan2(x[..., j, i] - x[..., i, j], x[..., i, i] + x[..., j, j])

    def from_angle(self, angle: torch.Tensor) -> torch.Tensor:
        """The points ``(..., d, d)`` rotating by ``angle (...)`` radians."""
        return plane_rotation(angle, self.d, self.plane)

    def _check_values(self, x: torch.Tensor) -> tuple[bool, str]:
        i, j = self.plane
        tol = _float_tol(x.dtype, self.d)
        y = x.clone()
        y[..., [i, i, j, j], [i, j, i, j]] = 0.0
        eye = torch.eye(self.d, dtype=x.dtype, device=x.device)
        eye[[i, j], [i, j]] = 0.0
        err = float((y - eye).abs().max()) if x.numel() else 0.0
        if err > tol:
            return False, f"expected the identity outside the plane {self.plane}, got an error of {err:.3g}"
        if x.numel():
            a, b, c, dd = x[..., i, i], x[..., i, j], x[..., j, i], x[..., j, j]
            block_err = torch.stack([(a - dd).abs(), (b + c).abs(), (a * a + c * c - 1).abs()]).max()
            if float(block_err) > tol:
                return False, f"expected a rotation in the plane {self.plane}, got an error of {float(block_err):.3g}"
        return True, ""

    def _theta(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        # theta = <R G, U> / <G, G> = ((R^T U)[j, i] - (R^T U)[i, j]) / 2
        i, j = self.plane
        return 0.5 * ((x[..., :, j] * u[..., :, i]).sum(-1) - (x[..., :, i] * u[..., :, j]).sum(-1))

    def _tangent(self, x: torch.Tensor, theta: torch.Tensor) -> torch.Tensor:
        # theta R G: column i is theta R e_j, column j is -theta R e_i, the rest zero.
        i, j = self.plane
        out = torch.zeros_like(x)
        out[..., :, i] = theta.unsqueeze(-1) * x[..., :, j]
        out[..., :, j] = -theta.unsqueeze(-1) * x[..., :, i]
        return out

    def proju(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return self._tangent(x, self._theta(x, u))

    def ehess2rhess(self, x: torch.Tensor, g: torch.Tensor, h: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        return self.proju(x, h - u @ sym(x.transpose(-1, -2) @ g))

    def expmap(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        i, j = self.plane
        theta = self._theta(x, u)
        c, s = torch.cos(theta).unsqueeze(-1), torch.sin(theta).unsqueeze(-1)
        out = x.clone()
        out[..., :, i] = c * x[..., :, i] + s * x[..., :, j]
        out[..., :, j] = c * x[..., :, j] - s * x[..., :, i]
        return out

    def retr(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """The exponential map (exact and as cheap as any retraction here)."""
        return self.expmap(x, u)

    def projx(self, x: torch.Tensor) -> torch.Tensor:
        """The rotation in the plane whose 2 x 2 block is nearest to ``x``'s; identity elsewhere."""
        return self.from_angle(self.angle(x))

    def random_point(self, *batch: int, generator: torch.Generator | None = None, dtype: torch.dtype = torch.float64) -> torch.Tensor:
        g = make_generator(generator)
        angle = (torch.rand(tuple(batch), generator=g, dtype=dtype) * 2.0 - 1.0) * math.pi
        return self.from_angle(angle)
