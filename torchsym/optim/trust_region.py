"""Riemannian trust-region method with truncated conjugate gradients.

Absil, Baker & Gallivan, "Trust-region methods on Riemannian manifolds", Found. Comput.
Math. 7 (2007), Algorithm 10 (outer loop) and Algorithm 11 (the Steihaug-Toint truncated
CG inner solver). The thesis solves its (R, t) sub-problem with this method (Sec. 7.2.2).
"""

from __future__ import annotations

import logging
import math
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

__all__ = ["trust_region"]

logger = logging.getLogger(__name__)

# Reasons the inner solver stops (they decide whether the radius may grow).
_NEGATIVE_CURVATURE, _EXCEEDED_TR, _LINEAR, _SUPERLINEAR, _MAX_INNER, _MODEL_INCREASED = range(6)


def _truncated_cg(problem: Problem, grad: Any, delta: float, kappa: float, theta: float, max_inner: int):
    """Approximately minimise the model ``<grad, eta> + <eta, H eta>/2`` over ``|eta| <= delta``.

    Steihaug-Toint truncated CG (Absil et al. 2007, Algorithm 11) without preconditioner.
    Returns ``(eta, H eta, number of inner iterations, stop code)``.
    """
    m = problem.manifold
    x = problem.x
    eta = m.zero_vector(x)
    heta = m.zero_vector(x)
    r = grad
    r_r = problem.inner(r, r)
    norm_r0 = math.sqrt(r_r)
    z_r = r_r
    mdelta = lincomb(-1.0, r)
    e_pe, e_pd, d_pd = 0.0, 0.0, z_r
    model_value = 0.0
    stop = _MAX_INNER
    j = 0
    for j in range(1, max_inner + 1):
        if d_pd == 0:  # zero gradient: the zero step is the model's minimiser
            break
        hdelta = problem.hess(mdelta)
        d_hd = problem.inner(mdelta, hdelta)
        alpha = z_r / d_hd if d_hd != 0 else math.inf
        e_pe_new = e_pe + 2.0 * alpha * e_pd + alpha * alpha * d_pd
        if d_hd <= 0 or e_pe_new >= delta * delta:
            # Go to the boundary of the trust region along mdelta.
            tau = (-e_pd + math.sqrt(max(e_pd * e_pd + d_pd * (delta * delta - e_pe), 0.0))) / d_pd
            eta = lincomb(1.0, eta, tau, mdelta)
            heta = lincomb(1.0, heta, tau, hdelta)
            stop = _NEGATIVE_CURVATURE if d_hd <= 0 else _EXCEEDED_TR
            break
        e_pe = e_pe_new
        new_eta = lincomb(1.0, eta, alpha, mdelta)
        new_heta = lincomb(1.0, heta, alpha, hdelta)
        new_model = problem.inner(new_eta, grad) + 0.5 * problem.inner(new_eta, new_heta)
        if new_model >= model_value:
            stop = _MODEL_INCREASED
            break
        eta, heta, model_value = new_eta, new_heta, new_model
        r = lincomb(1.0, r, alpha, hdelta)
        r_r = problem.inner(r, r)
        norm_r = math.sqrt(max(r_r, 0.0))
        if norm_r <= norm_r0 * min(norm_r0**theta, kappa):
            stop = _LINEAR if kappa < norm_r0**theta else _SUPERLINEAR
            break
        z_r_old, z_r = z_r, r_r
        beta = z_r / z_r_old
        # Re-project onto the tangent space to keep round-off from drifting off it.
        mdelta = m.proju(x, lincomb(-1.0, r, beta, mdelta))
        e_pd = beta * (e_pd + alpha * d_pd)
        d_pd = z_r + beta * beta * d_pd
    return eta, heta, j, stop


def trust_region(
    manifold: Manifold,
    cost: Callable[[Any], torch.Tensor],
    x0: Any,
    *,
    egrad: Callable[[Any], Any] | None = None,
    ehess: Callable[[Any, Any], Any] | None = None,
    max_iter: int = 1000,
    min_grad_norm: float = 1e-6,
    min_step_size: float = 1e-10,
    max_time: float = float("inf"),
    Delta_bar: float | None = None,
    Delta0: float | None = None,
    kappa: float = 0.1,
    theta: float = 1.0,
    rho_prime: float = 0.1,
    max_inner: int | None = None,
) -> OptimResult:
    """Minimise ``cost`` over ``manifold`` by the Riemannian trust-region method.

    Each outer iteration approximately minimises the second-order model
    ``m(eta) = f(x) + <grad f(x), eta> + <eta, Hess f(x)[eta]> / 2`` inside the ball
    ``|eta| <= Delta`` with truncated CG (Steihaug-Toint), proposes ``retr(x, eta)``, and
    accepts it when the actual decrease is at least ``rho_prime`` times the predicted one;
    the radius shrinks by 4 after a poor step and doubles (up to ``Delta_bar``) after a
    very good step that reached the boundary (Absil, Baker & Gallivan 2007). The thesis
    uses this method for its (R, t) sub-problem (Sec. 7.2.2).

    Args:
        manifold: a :class:`~torchsym.manifolds.Manifold`.
        cost: ``cost(x) -> scalar tensor``; ``x`` is a tensor or, on a product manifold,
            a tuple of tensors. A batched ``x`` is treated as one point of the product of
            its batch elements (``cost`` must then combine them, e.g. by summing).
        x0: the starting point (same structure as ``x``).
        egrad: ``egrad(x)`` returning the Euclidean gradient of ``cost`` (same structure as
            ``x``); None computes it with autograd.
        ehess: ``ehess(x, u)`` returning the Euclidean Hessian of ``cost`` at ``x`` applied
            to ``u``; None computes it by double backward through the gradient.
        max_iter: largest number of outer iterations.
        min_grad_norm: stop when the Riemannian gradient's norm falls below this.
        min_step_size: stop when a proposed step is shorter than this.
        max_time: stop after this many seconds.
        Delta_bar: largest trust-region radius; None uses the manifold's typical distance.
        Delta0: initial radius; None uses ``Delta_bar / 8``.
        kappa: inner solver's linear convergence target (Absil et al.'s ``kappa``).
        theta: inner solver's superlinear convergence exponent (their ``theta``).
        rho_prime: accept a step when actual / predicted decrease exceeds this, in [0, 1/4).
        max_inner: largest number of inner CG iterations; None uses the manifold's dimension.

    Returns:
        :class:`~torchsym.optim.OptimResult`; ``converged`` is True when the gradient norm
        or the step size criterion stopped the solver.

    Raises:
        InputShapeError: ``x0`` does not have the manifold's point shape.
        InputValueError: ``x0`` is not on the manifold, or a setting is out of range.

    Example:
        >>> from torchsym.manifolds import SpecialOrthogonal
        >>> a = torch.eye(3, dtype=torch.float64)
        >>> m = SpecialOrthogonal(3)
        >>> res = trust_region(m, lambda r: ((r - a) ** 2).sum(), m.random_point())
        >>> bool((res.x - a).abs().max() < 1e-6), res.converged
        (True, True)
    """
    t_start = time.perf_counter()
    x = check_start(manifold, x0)
    max_iter = check_int(max_iter, "max_iter", minimum=0)
    min_grad_norm = check_positive(min_grad_norm, "min_grad_norm", allow_zero=True)
    min_step_size = check_positive(min_step_size, "min_step_size", allow_zero=True)
    if not (isinstance(max_time, (int, float)) and max_time > 0):
        raise InputValueError(f"max_time: expected a positive number of seconds, got {max_time!r}")
    if not 0.0 <= rho_prime < 0.25:
        raise InputValueError(f"rho_prime: expected a number in [0, 0.25), got {rho_prime!r}")
    check_positive(kappa, "kappa")
    check_positive(theta, "theta")
    total_dim = manifold.total_dim(x)
    Delta_bar = check_positive(Delta_bar, "Delta_bar") if Delta_bar is not None else manifold.typical_dist * math.sqrt(
        max(1, total_dim // max(1, manifold.dim))
    )
    Delta = check_positive(Delta0, "Delta0") if Delta0 is not None else Delta_bar / 8.0
    max_inner = check_int(max_inner, "max_inner", minimum=1) if max_inner is not None else max(1, total_dim)

    problem = Problem(manifold, cost, egrad, ehess)
    fx, grad, grad_norm = problem.at_with_norm(x)
    iterations = 0
    stop_reason = "max_iter"
    eps = torch.finfo(x[0].dtype if isinstance(x, tuple) else x.dtype).eps
    while True:
        reason = outer_stop(grad_norm, min_grad_norm, iterations, max_iter, t_start, max_time)
        if reason is not None:
            stop_reason = reason
            break
        iterations += 1
        eta, heta, n_inner, tcg_stop = _truncated_cg(problem, grad, Delta, kappa, theta, max_inner)
        step = math.sqrt(max(problem.inner(eta, eta), 0.0))
        x_prop = manifold.retr(x, eta)
        f_prop = problem.cost(x_prop)
        rho_reg = max(1.0, abs(fx)) * eps * 1e3
        rho_num = fx - f_prop + rho_reg
        rho_den = -(problem.inner(grad, eta) + 0.5 * problem.inner(eta, heta)) + rho_reg
        model_decreased = rho_den >= 0
        rho = rho_num / rho_den if rho_den != 0 else math.nan
        if not model_decreased or math.isnan(rho) or rho < 0.25:
            Delta /= 4.0
        elif rho > 0.75 and tcg_stop in (_NEGATIVE_CURVATURE, _EXCEEDED_TR):
            Delta = min(2.0 * Delta, Delta_bar)
        accepted = model_decreased and rho > rho_prime
        logger.debug("TR %d: f=%.6g |g|=%.3g rho=%.3g Delta=%.3g inner=%d accepted=%s", iterations, fx, grad_norm, rho, Delta, n_inner, accepted)
        if accepted:
            x = x_prop
            fx, grad, grad_norm = problem.at_with_norm(x)
        if step < min_step_size:
            stop_reason = "step_size"
            break
    return finish(x, fx, grad_norm, iterations, stop_reason, t_start)
