"""Eigenfunction correction on SO(k) (thesis Sec. 6.2.6, Eq. 6.4, gradients of Appendix 6.5).

Finds a rotation ``R`` of the truncated eigenbasis ``Phi`` such that the rotated basis
``Phi R`` still nearly diagonalises the Laplacian and maps pairs of intrinsically
symmetric functions onto each other under the diagonal functional map ``C``::

    min_{R in SO(k)}  off(R^T D R) + ||R^T D R - D||_F^2 + mu ||R^T Fb - C R^T Gb||_F^2

with ``D = diag(lambda)``, ``Fb = Phi^T F`` and ``Gb = Phi^T G`` the basis coefficients
of the paired functions. Solved by the Riemannian trust-region method
(:func:`torchsym.optim.trust_region`) with the analytic Euclidean gradient and Hessian.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

from torchsym.core.checks import check_positive
from torchsym.core.results import Result
from torchsym.errors import InputShapeError
from torchsym.manifolds import SpecialOrthogonal
from torchsym.optim import trust_region

__all__ = ["CorrectionResult", "correct_eigenfunctions", "correction_cost"]


def _off(m: torch.Tensor) -> torch.Tensor:
    return m - torch.diag_embed(torch.diagonal(m))


def correction_cost(
    r: torch.Tensor, evals: torch.Tensor, fb: torch.Tensor, gb: torch.Tensor, signs: torch.Tensor, mu: float
) -> torch.Tensor:
    """The cost of Eq. 6.4 at ``r (k, k)``; ``evals (k,)``, ``fb, gb (k, m)``, ``signs (k,)``."""
    d = torch.diag(evals)  # (k, k)
    m = r.T @ d @ r  # (k, k)
    e = (r.T @ fb - signs[:, None] * (r.T @ gb)) * signs.abs()[:, None]  # (k, m), unused rows zero
    return (_off(m) ** 2).sum() + ((m - d) ** 2).sum() + mu * (e**2).sum()


@dataclasses.dataclass(frozen=True)
class CorrectionResult(Result):
    """The rotation of Eq. 6.4 and how its optimisation ended.

    Attributes:
        rotation: ``(k, k)`` rotation ``R`` in SO(k).
        cost_before: the cost at ``R = I``.
        cost: the cost at ``rotation``.
        iterations: trust-region iterations.
        converged: whether the trust-region method stopped on its gradient or step test.
        stop_reason: the optimiser's reason for stopping.
    """

    rotation: torch.Tensor
    cost_before: float
    cost: float
    iterations: int
    converged: bool
    stop_reason: str


def correct_eigenfunctions(
    evals: np.ndarray,
    fb: np.ndarray,
    gb: np.ndarray,
    signs: np.ndarray,
    *,
    mu: float = 1.0,
    r0: np.ndarray | None = None,
    max_iter: int = 50,
    min_grad_norm: float = 1e-6,
) -> CorrectionResult:
    """Solve Eq. 6.4 for the rotation ``R`` of the eigenbasis (Sec. 6.2.6).

    Args:
        evals: ``(k,)`` eigenvalues (the diagonal of ``D``).
        fb: ``(k, m)`` basis coefficients ``Phi^T F`` of ``m`` functions.
        gb: ``(k, m)`` coefficients ``Phi^T G`` of their intrinsic images.
        signs: ``(k,)`` the diagonal of ``C`` (+1 even, -1 odd, 0: the eigenfunction is
            left out of the pairing term).
        mu: weight of the pairing term (the thesis uses 1).
        r0: ``(k, k)`` starting rotation; identity when None.
        max_iter: trust-region iterations at most.
        min_grad_norm: stop when the Riemannian gradient norm is below this.

    Returns:
        A :class:`CorrectionResult`.
    """
    k = int(np.asarray(evals).shape[0])
    if fb.shape != gb.shape or fb.ndim != 2 or fb.shape[0] != k:
        raise InputShapeError(f"fb, gb: expected equal shapes (k, m) with k = {k}, got {fb.shape} and {gb.shape}")
    mu = check_positive(mu, "mu", allow_zero=True)
    lam = torch.as_tensor(evals, dtype=torch.float64)  # (k,)
    d = torch.diag(lam)  # (k, k)
    f_t = torch.as_tensor(fb, dtype=torch.float64)  # (k, m)
    g_t = torch.as_tensor(gb, dtype=torch.float64)  # (k, m)
    s = torch.as_tensor(signs, dtype=torch.float64)  # (k,)

    def cost(r: torch.Tensor) -> torch.Tensor:
        return correction_cost(r, lam, f_t, g_t, s, mu)

    used = s.abs()[:, None]  # (k, 1): rows of unused eigenfunctions leave the pairing term

    def egrad(r: torch.Tensor) -> torch.Tensor:
        m = r.T @ d @ r  # (k, k)
        e = (r.T @ f_t - s[:, None] * (r.T @ g_t)) * used  # (k, m)
        # d/dR off(M)^2 = 4 D R off(M); d/dR ||M - D||^2 = 4 D R (M - D)
        g = 4.0 * d @ r @ _off(m) + 4.0 * d @ r @ (m - d)
        # d/dR ||E||^2 with E = R^T Fb - C R^T Gb: 2 (Fb E^T - Gb E^T C)
        return g + 2.0 * mu * (f_t @ e.T - g_t @ (e.T * s[None, :]))

    def ehess(r: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        m = r.T @ d @ r  # (k, k)
        dm = u.T @ d @ r + r.T @ d @ u  # (k, k)
        de = (u.T @ f_t - s[:, None] * (u.T @ g_t)) * used  # (k, m)
        h = 4.0 * d @ u @ _off(m) + 4.0 * d @ r @ _off(dm)
        h = h + 4.0 * d @ u @ (m - d) + 4.0 * d @ r @ dm
        return h + 2.0 * mu * (f_t @ de.T - g_t @ (de.T * s[None, :]))

    x0 = torch.eye(k, dtype=torch.float64) if r0 is None else torch.as_tensor(r0, dtype=torch.float64)
    before = float(cost(x0))
    res = trust_region(
        SpecialOrthogonal(k), cost, x0, egrad=egrad, ehess=ehess, max_iter=max_iter, min_grad_norm=min_grad_norm
    )
    return CorrectionResult(
        rotation=res.x.detach(),
        cost_before=before,
        cost=float(res.cost),
        iterations=int(res.iterations),
        converged=bool(res.converged),
        stop_reason=str(res.stop_reason),
    )
