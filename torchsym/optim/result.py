"""The result of a Riemannian optimiser."""

from __future__ import annotations

import dataclasses
from typing import Any

from torchsym.core.results import Result

__all__ = ["OptimResult"]


@dataclasses.dataclass(frozen=True)
class OptimResult(Result):
    """What :func:`~torchsym.optim.trust_region` and :func:`~torchsym.optim.gradient_descent` return.

    Attributes:
        x: the last point, same structure, shape, dtype and device as ``x0`` (a tensor
            ``(..., *point_shape)`` or, on a product manifold, a tuple of them).
        cost: the cost at ``x``.
        grad_norm: the Riemannian gradient's norm at ``x``.
        iterations: number of outer iterations run.
        stop_reason: ``"grad_norm"`` (gradient norm below ``min_grad_norm``),
            ``"step_size"`` (the last step was shorter than ``min_step_size``),
            ``"max_iter"`` or ``"max_time"``.
        converged: True when the solver stopped on the gradient norm or the step size,
            False when it ran out of iterations or time.
        time: seconds spent.
    """

    x: Any
    cost: float
    grad_norm: float
    iterations: int
    stop_reason: str
    converged: bool
    time: float
