"""The base class of every manifold (after geoopt's layout).

Points and tangent vectors are tensors whose *leading* dimensions are batch dimensions
and whose *trailing* ``ndim`` dimensions are the manifold's own (e.g. ``(..., n, n)`` for
SO(n)); a :class:`~torchsym.manifolds.ProductManifold` uses tuples of such tensors.
Tangent vectors are stored in the ambient (embedding) space, as the thesis does
(Sec. 7.2.2, Eq. 7.6: a tangent vector of SO(d) at R is ``R Omega``), and every metric is
the one inherited from the embedding (Eq. 7.7), so ``inner`` is a plain sum of products.
"""

from __future__ import annotations

import abc
import math

import torch

from torchsym.core.random import make_generator

__all__ = ["Manifold"]


def _float_tol(dtype: torch.dtype, size: int) -> float:
    """Tolerance for 'lies on the manifold' checks: about 1e-7 in float64, 3e-3 in float32."""
    return 10.0 * math.sqrt(torch.finfo(dtype).eps) * max(1, size)


class Manifold(abc.ABC):
    """A Riemannian manifold embedded in a Euclidean space of ``point_shape`` tensors.

    Subclasses set ``point_shape`` (the trailing dimensions of a point), ``dim`` (the
    manifold's dimension) and implement :meth:`proju`, :meth:`retr`, :meth:`projx`,
    :meth:`random_point` and :meth:`_check_values`. Every method accepts leading batch
    dimensions; :meth:`inner` and :meth:`norm` return one number per batch element.
    """

    name = "Manifold"
    point_shape: tuple[int, ...] = ()
    dim: int = 0

    @property
    def ndim(self) -> int:
        """Number of trailing dimensions that belong to one point."""
        return len(self.point_shape)

    # ----------------------------------------------------------------- shapes, checks
    def batch_shape(self, x: torch.Tensor) -> torch.Size:
        """The leading (batch) dimensions of a point or tangent vector."""
        return x.shape[: x.dim() - self.ndim]

    def total_dim(self, x: torch.Tensor) -> int:
        """Dimension of the (batched) point set ``x`` lives in: ``dim`` times the batch size."""
        return self.dim * math.prod(self.batch_shape(x))

    @property
    def typical_dist(self) -> float:
        """A typical distance between points, used to size trust regions."""
        return math.sqrt(max(self.dim, 1))

    def check_shape(self, x: object) -> tuple[bool, str]:
        """Whether ``x`` is a floating tensor of shape ``(..., *point_shape)``; ``(ok, reason)``."""
        want = "(..., " + ", ".join(str(s) for s in self.point_shape) + ")" if self.point_shape else "(...)"
        if not isinstance(x, torch.Tensor):
            return False, f"expected a tensor of shape {want}, got {type(x).__name__}"
        if not x.is_floating_point():
            return False, f"expected a floating-point tensor of shape {want}, got dtype {x.dtype}"
        if x.dim() < self.ndim or tuple(x.shape[x.dim() - self.ndim :]) != tuple(self.point_shape):
            return False, f"expected shape {want} for a point of {self}, got {tuple(x.shape)}"
        return True, ""

    def check_point(self, x: object) -> tuple[bool, str]:
        """Whether ``x`` is a point of the manifold: shape and constraints; ``(ok, reason)``.

        A pure check: it never raises for a bad point; the caller decides what to do.
        """
        ok, reason = self.check_shape(x)
        if not ok:
            return ok, reason
        if not bool(torch.isfinite(x).all()):
            return False, "expected finite entries, got NaN or infinite values"
        return self._check_values(x)

    def _check_values(self, x: torch.Tensor) -> tuple[bool, str]:
        return True, ""

    def check_vector(self, x: torch.Tensor, u: object) -> tuple[bool, str]:
        """Whether ``u`` is a tangent vector at ``x`` (shape and ``proju(x, u) == u``)."""
        ok, reason = self.check_shape(u)
        if not ok:
            return ok, reason
        err = float((self.proju(x, u) - u).abs().max()) if u.numel() else 0.0
        tol = _float_tol(u.dtype, math.prod(self.point_shape)) * max(1.0, float(u.abs().max()) if u.numel() else 1.0)
        if err > tol:
            return False, f"expected a tangent vector (proju(x, u) == u), got a normal component of size {err:.3g}"
        return True, ""

    # ----------------------------------------------------------------- metric
    def inner(self, x: torch.Tensor, u: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
        """Riemannian inner product of tangent vectors ``u, v`` at ``x``, shape ``batch``."""
        prod = u * v
        if self.ndim == 0:
            return prod
        return prod.sum(dim=tuple(range(-self.ndim, 0)))

    def norm(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """Riemannian norm of the tangent vector ``u`` at ``x``, shape ``batch``."""
        return self.inner(x, u, u).clamp_min(0).sqrt()

    # ----------------------------------------------------------------- projections
    @abc.abstractmethod
    def proju(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """Orthogonal projection of an ambient vector ``u`` onto the tangent space at ``x``."""

    @abc.abstractmethod
    def projx(self, x: torch.Tensor) -> torch.Tensor:
        """A nearby point of the manifold (the nearest one where that is cheap)."""

    def egrad2rgrad(self, x: torch.Tensor, g: torch.Tensor) -> torch.Tensor:
        """Riemannian gradient from the Euclidean gradient ``g`` (a projection, Eq. 7.8)."""
        return self.proju(x, g)

    @abc.abstractmethod
    def ehess2rhess(self, x: torch.Tensor, g: torch.Tensor, h: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """Riemannian Hessian along ``u`` from the Euclidean gradient ``g`` and Hessian-vector product ``h``."""

    # ----------------------------------------------------------------- moving
    @abc.abstractmethod
    def retr(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """Retraction: a point of the manifold near ``x + u``, with ``retr(x, 0) == x``."""

    @abc.abstractmethod
    def expmap(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """Exponential map: follow the geodesic from ``x`` with initial velocity ``u`` for time 1."""

    def transp(self, x: torch.Tensor, y: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """Vector transport of ``u`` from ``x`` to ``y`` by projection."""
        return self.proju(y, u)

    # ----------------------------------------------------------------- sampling
    @abc.abstractmethod
    def random_point(self, *batch: int, generator: torch.Generator | None = None, dtype: torch.dtype = torch.float64) -> torch.Tensor:
        """A random point of shape ``(*batch, *point_shape)``.

        Args:
            batch: leading batch dimensions (none for a single point).
            generator: the source of randomness (``torch.Generator``); None uses a fresh
                generator seeded with 0, so the same call gives the same bits.
            dtype: floating dtype of the point.
        """

    def random_tangent(self, x: torch.Tensor, generator: torch.Generator | None = None) -> torch.Tensor:
        """A random tangent vector at ``x``: a standard Gaussian projected onto the tangent space.

        Args:
            x: ``(..., *point_shape)`` point.
            generator: the source of randomness (``torch.Generator``); None uses a fresh
                generator seeded with 0, so the same call gives the same bits.
        """
        g = make_generator(generator)
        u = torch.randn(x.shape, generator=g, dtype=x.dtype).to(x.device)
        return self.proju(x, u)

    def zero_vector(self, x: torch.Tensor) -> torch.Tensor:
        """The zero tangent vector at ``x``."""
        return torch.zeros_like(x)

    def __repr__(self) -> str:
        return f"{self.name}({self._repr_args()})"

    def _repr_args(self) -> str:
        return ""
