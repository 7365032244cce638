"""Cost, Riemannian gradient and Hessian of a problem on a manifold, and tangent-vector algebra.

Tangent vectors are tensors or (on a product manifold) tuples of tensors; the helpers
below add and scale both alike. Where the caller gives no Euclidean gradient or Hessian,
they come from autograd: the gradient by one backward pass and Hessian-vector products by
a second backward pass through the gradient ("double backward").
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.manifolds.base import Manifold
from torchsym.optim.result import OptimResult


def lincomb(a: float, u: Any, b: float = 0.0, v: Any = None) -> Any:
    """``a u + b v`` for tensors or tuples of tensors (``v`` None means ``a u``)."""
    if isinstance(u, tuple):
        if v is None:
            return tuple(lincomb(a, ui) for ui in u)
        return tuple(lincomb(a, ui, b, vi) for ui, vi in zip(u, v))
    if v is None:
        return a * u
    return a * u + b * v


def detach(x: Any) -> Any:
    if isinstance(x, tuple):
        return tuple(detach(xi) for xi in x)
    return x.detach()


def _leaf(x: Any) -> Any:
    if isinstance(x, tuple):
        return tuple(_leaf(xi) for xi in x)
    return x.detach().requires_grad_(True)


def _as_tuple(x: Any) -> tuple:
    return x if isinstance(x, tuple) else (x,)


def _like(x: Any, parts: tuple) -> Any:
    return parts if isinstance(x, tuple) else parts[0]


def check_start(manifold: Manifold, x0: Any, name: str = "x0") -> Any:
    """Raise a typed error naming ``name`` unless ``x0`` is a point of ``manifold``."""
    if not isinstance(manifold, Manifold):
        raise InputValueError(f"manifold: expected a torchsym.manifolds.Manifold, got {type(manifold).__name__}")
    if isinstance(x0, list):
        x0 = tuple(x0)
    ok, reason = manifold.check_shape(x0)
    if not ok:
        raise InputShapeError(f"{name}: {reason}")
    ok, reason = manifold.check_point(x0)
    if not ok:
        raise InputValueError(f"{name}: not a point of {manifold}: {reason}")
    return detach(x0)


def stop_reason(grad_norm: float, min_grad_norm: float, iterations: int, max_iter: int, t_start: float, max_time: float) -> str | None:
    """The outer-loop stopping test shared by every solver: ``"grad_norm"``, ``"max_iter"``,
    ``"max_time"``, or None to go on (step-size stops are each solver's own)."""
    if grad_norm < min_grad_norm:
        return "grad_norm"
    if iterations >= max_iter:
        return "max_iter"
    if time.perf_counter() - t_start >= max_time:
        return "max_time"
    return None


def finish(x: Any, fx: float, grad_norm: float, iterations: int, stop: str, t_start: float) -> OptimResult:
    """The :class:`OptimResult` of a run that stopped at ``x`` for reason ``stop``."""
    return OptimResult(
        x=detach(x),
        cost=fx,
        grad_norm=grad_norm,
        iterations=iterations,
        stop_reason=stop,
        converged=stop in ("grad_norm", "step_size"),
        time=time.perf_counter() - t_start,
    )


class Problem:
    """Evaluates a cost and its Riemannian derivatives at one point at a time.

    Args:
        manifold: where the variable lives.
        cost: ``cost(x) -> scalar tensor``.
        egrad: ``egrad(x) -> Euclidean gradient`` (same structure as x), or None for autograd.
        ehess: ``ehess(x, u) -> Euclidean Hessian-vector product``, or None for autograd.
    """

    def __init__(
        self,
        manifold: Manifold,
        cost: Callable[[Any], torch.Tensor],
        egrad: Callable[[Any], Any] | None = None,
        ehess: Callable[[Any, Any], Any] | None = None,
    ) -> None:
        self.manifold, self._cost, self._egrad, self._ehess = manifold, cost, egrad, ehess
        self.x: Any = None
        self._leaf: Any = None
        self._g: Any = None

    def cost(self, x: Any) -> float:
        with torch.no_grad():
            return float(self._cost(x))

    def _scalar(self, value: Any) -> torch.Tensor:
        if not isinstance(value, torch.Tensor) or value.numel() != 1:
            raise InputShapeError(f"cost: expected a scalar tensor, got {getattr(value, 'shape', type(value).__name__)}")
        return value.reshape(())

    def at(self, x: Any) -> tuple[float, Any]:
        """Move to ``x``; return the cost there and the Riemannian gradient."""
        self.x = x
        need_graph = self._ehess is None
        if self._egrad is not None and not need_graph:
            with torch.no_grad():
                f = float(self._scalar(self._cost(x)))
                g = self._egrad(x)
            self._leaf, self._g = None, g
        else:
            leaf = _leaf(x)
            with torch.enable_grad():
                if self._egrad is None:
                    f_t = self._scalar(self._cost(leaf))
                    parts = torch.autograd.grad(f_t, _as_tuple(leaf), create_graph=need_graph, allow_unused=True)
                    parts = tuple(torch.zeros_like(li) if p is None else p for p, li in zip(parts, _as_tuple(leaf)))
                    g = _like(x, parts)
                    f = float(f_t.detach())
                else:
                    with torch.no_grad():
                        f = float(self._scalar(self._cost(x)))
                    g = self._egrad(leaf)
            self._leaf, self._g = leaf, g
        return f, self.manifold.egrad2rgrad(x, detach(g))

    def at_with_norm(self, x: Any) -> tuple[float, Any, float]:
        """:meth:`at`, and the norm of the Riemannian gradient."""
        f, grad = self.at(x)
        return f, grad, math.sqrt(max(self.inner(grad, grad), 0.0))

    def hess(self, u: Any) -> Any:
        """The Riemannian Hessian at the current point applied to the tangent vector ``u``."""
        g = detach(self._g)
        if self._ehess is not None:
            with torch.no_grad():
                h = self._ehess(self.x, u)
        else:
            g_parts = tuple(gi for gi in _as_tuple(self._g))
            leaf_parts = _as_tuple(self._leaf)
            wanted = [gi.requires_grad for gi in g_parts]
            if any(wanted):
                outs = [gi for gi, w in zip(g_parts, wanted) if w]
                grads_out = [ui for ui, w in zip(_as_tuple(u), wanted) if w]
                with torch.enable_grad():
                    parts = torch.autograd.grad(outs, leaf_parts, grad_outputs=grads_out, retain_graph=True, allow_unused=True)
                parts = tuple(torch.zeros_like(li) if p is None else p.detach() for p, li in zip(parts, leaf_parts))
            else:
                parts = tuple(torch.zeros_like(li) for li in leaf_parts)
            h = _like(self.x, parts)
        return self.manifold.ehess2rhess(self.x, g, h, u)

    def inner(self, u: Any, v: Any) -> float:
        return float(self.manifold.inner(self.x, u, v).sum())
