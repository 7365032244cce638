"""Riemannian steepest descent with Armijo backtracking."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import torch

from torchsym.core.checks import check_int, check_positive
from torchsym.errors import InputValueError
from torchsym.manifolds.base import Manifold
from torchsym.optim._problem import Problem, check_start, finish, lincomb
from torchsym.optim._problem import stop_reason as outer_stop
from torchsym.optim.result import OptimResult

__all__ = ["gradient_descent"]


def gradient_descent(
    manifold: Manifold,
    cost: Callable[[Any], torch.Tensor],
    x0: Any,
    *,
    egrad: Callable[[Any], Any] | None = None,
    max_iter: int = 1000,
    min_grad_norm: float = 1e-6,
    min_step_size: float = 1e-10,
    max_time: float = float("inf"),
) -> OptimResult:
    """Minimise ``cost`` over ``manifold`` by steepest descent along the Riemannian gradient.

    Each step moves to ``retr(x, -a grad f(x))`` with the step ``a`` found by Armijo
    backtracking (sufficient decrease ``1e-4``, contraction ``1/2``); the first trial step
    of an iteration is twice the last accepted one (Absil, Mahony & Sepulchre 2008,
    Sec. 4.2). Slower than :func:`~torchsym.optim.trust_region` near a minimum but needs
    no Hessian.

    Args:
        manifold: a :class:`~torchsym.manifolds.Manifold`.
        cost: ``cost(x) -> scalar tensor`` (``x`` a tensor or a tuple on a product manifold).
        x0: the starting point.
        egrad: ``egrad(x)`` returning the Euclidean gradient; None uses autograd.
        max_iter: largest number of iterations.
        min_grad_norm: stop when the Riemannian gradient's norm falls below this.
        min_step_size: stop when an accepted step is shorter than this.
        max_time: stop after this many seconds.

    Returns:
        :class:`~torchsym.optim.OptimResult`.

    Raises:
        InputShapeError: ``x0`` does not have the manifold's point shape.
        InputValueError: ``x0`` is not on the manifold, or a setting is out of range.
    """
    t_start = time.perf_counter()
    x = check_start(manifold, x0)
    max_iter = check_int(max_iter, "max_iter", minimum=0)
    min_grad_norm = check_positive(min_grad_norm, "min_grad_norm", allow_zero=True)
    min_step_size = check_positive(min_step_size, "min_step_size", allow_zero=True)
    if not (isinstance(max_time, (int, float)) and max_time > 0):
        raise InputValueError(f"max_time: expected a positive number of seconds, got {max_time!r}")
    # The Hessian is never needed, so give the problem a dummy one to skip double backward graphs.
    problem = Problem(manifold, cost, egrad, ehess=lambda x, u: u)
    fx, grad, grad_norm = problem.at_with_norm(x)
    alpha = 1.0 / max(grad_norm, 1e-300) if grad_norm > 0 else 1.0
    iterations, stop_reason = 0, "max_iter"
    while True:
        reason = outer_stop(grad_norm, min_grad_norm, iterations, max_iter, t_start, max_time)
        if reason is not None:
            stop_reason = reason
            break
        iterations += 1
        g2 = grad_norm * grad_norm
        a = 2.0 * alpha
        x_new, f_new = x, fx
        for _ in range(60):
            x_try = manifold.retr(x, lincomb(-a, grad))
            f_try = problem.cost(x_try)
            if f_try <= fx - 1e-4 * a * g2:
                x_new, f_new = x_try, f_try
                break
            a *= 0.5
        else:
            a = 0.0
        step = a * grad_norm
        if a == 0.0 or step < min_step_size:
            stop_reason = "step_size"
            if a > 0.0:
                x, fx = x_new, f_new
                fx, grad, grad_norm = problem.at_with_norm(x)
            break
        alpha = a
        x = x_new
        fx, grad, grad_norm = problem.at_with_norm(x)
    return finish(x, fx, grad_norm, iterations, stop_reason, t_start)
