"""The reflection of thesis Eq. 7.1 as rotations and a translation, and its cost and derivatives.

A reflection of R^d is written ``x' = T E T^T (x - t) + t`` with ``T = R_1 R_2 ... R_{d-1}``,
``E = diag(1, ..., 1, -1)`` and each ``R_u`` a rotation in one coordinate plane (Sec. 7.2.1).
Here ``R_u`` (``u = 1 .. d-1``) turns the plane of axes ``(u-1, d-1)`` (0-based), so that
``T e_d`` can reach every unit vector and is the plane's normal (Theorem 7.2.3); ``t`` lies on
the plane.

For fixed correspondences, the cost ``f(R, t) = sum_i w_i |T E T^T (x_i - t) + t - y_i|^2`` (the
symmetry error of Eq. 7.5, ``y_i`` the mirror of ``x_i`` chosen by ``P``, ``w_i`` 1 for matched
points and 0 for unmatched ones) depends on the points only through a few sums, computed
once per correspondence step by :func:`pair_statistics`; every evaluation afterwards costs
``O(d)`` products of ``d x d`` matrices regardless of the number of points (the gradient and
the Hessian product too, through the partial products of :func:`_partial_products`).
"""

from __future__ import annotations

import dataclasses

import torch

from torchsym.manifolds import Euclidean, PlaneRotations, ProductManifold

__all__ = [
    "PairStatistics",
    "compose",
    "egrad",
    "ehess",
    "normal_from_rotations",
    "pair_statistics",
    "reflection_cost",
    "reflection_from_rotations",
    "rotation_manifold",
    "rotations_from_normal",
    "symmetry_error",
    "thesis_rgrad",
    "thesis_rhess",
]


def rotation_manifold(d: int) -> ProductManifold:
    """``SO(2, d)^(d-1) x R^d``: the constraint set M of Sec. 7.2.1 (rotations, then translation)."""
    return ProductManifold(*(PlaneRotations(d, (u, d - 1)) for u in range(d - 1)), Euclidean(d))


def compose(mats: list[torch.Tensor] | tuple[torch.Tensor, ...], d: int, dtype: torch.dtype) -> torch.Tensor:
    """``M_1 M_2 ... M_k`` (the identity when empty), ``(d, d)``."""
    out = torch.eye(d, dtype=dtype)
    for m in mats:
        out = out @ m
    return out


def _e(d: int, dtype: torch.dtype) -> torch.Tensor:
    e = torch.ones(d, dtype=dtype)
    e[-1] = -1.0
    return torch.diag(e)


def reflection_from_rotations(rotations) -> torch.Tensor:
    """``S = T E T^T`` with ``T = R_1 ... R_{d-1}``; ``(d, d)``."""
    d = rotations[0].shape[-1]
    t = compose(rotations, d, rotations[0].dtype)
    return t @ _e(d, t.dtype) @ t.T


def normal_from_rotations(rotations) -> torch.Tensor:
    """Unit normal of the plane: the null space of ``I + T E T^T`` (Theorem 7.2.3), which is ``T e_d``."""
    d = rotations[0].shape[-1]
    t = compose(rotations, d, rotations[0].dtype)
    s = torch.eye(d, dtype=t.dtype) + t @ _e(d, t.dtype) @ t.T
    _, vecs = torch.linalg.eigh(0.5 * (s + s.T))
    return vecs[:, 0]


def rotations_from_normal(normal: torch.Tensor) -> tuple[torch.Tensor, ...]:
    """Plane rotations ``R_1 .. R_{d-1}`` with ``T e_d = normal / |normal|`` (a Givens sweep)."""
    d = normal.shape[-1]
    w = normal / normal.norm()
    rots = []
    for u in range(d - 1):
        m = PlaneRotations(d, (u, d - 1))
        angle = torch.atan2(-w[u], w[d - 1])
        r = m.from_angle(angle)
        rots.append(r)
        w = r.T @ w
    return tuple(rots)


@dataclasses.dataclass(frozen=True)
class PairStatistics:
    """Sums over the pairs ``(x_i, y_i)`` with weights ``w_i`` that the cost needs.

    Attributes:
        w: ``()`` total weight ``sum w_i`` (the thesis's ``n`` when every point is matched).
        sx, sy: ``(d,)`` weighted sums of ``x_i`` and of ``y_i`` (``Xe`` and ``XPe``).
        mxy: ``(d, d)`` ``sum w_i x_i y_i^T``.
        sq: ``()`` ``sum w_i |x_i - y_i|^2``.
    """

    w: torch.Tensor
    sx: torch.Tensor
    sy: torch.Tensor
    mxy: torch.Tensor
    sq: torch.Tensor


def pair_statistics(points: torch.Tensor, mirrors: torch.Tensor, weights: torch.Tensor) -> PairStatistics:
    """:class:`PairStatistics` of ``points (N, d)``, ``mirrors (N, d)`` and ``weights (N,)``."""
    wx = points * weights[:, None]  # (N, d)
    return PairStatistics(
        w=weights.sum(),
        sx=wx.sum(0),
        sy=(mirrors * weights[:, None]).sum(0),
        mxy=wx.T @ mirrors,
        sq=(weights * ((points - mirrors) ** 2).sum(1)).sum(),
    )


def _a_matrix(st: PairStatistics, t: torch.Tensor) -> torch.Tensor:
    # A = (XP - t e^T)(X - t e^T)^T + its transpose (Eq. 7.11), from the sums.
    c = st.mxy - st.sx[:, None] * t[None, :] - t[:, None] * st.sy[None, :] + st.w * t[:, None] * t[None, :]
    return c + c.T


def reflection_cost(x, st: PairStatistics) -> torch.Tensor:
    """``f(R, t) = sum_i w_i |T E T^T (x_i - t) + t - y_i|^2`` (Eq. 7.5 for fixed P), a scalar.

    Uses ``|S a - b|^2 = |a - b|^2 + 2 a^T b - 2 b^T S a`` with ``a = x - t``, ``b = y - t`` and
    ``S = T E T^T``, so that ``f = sum w |x - y|^2 + tr((I - S) A)`` with the thesis's ``A``.
    """
    *rots, t = x
    s = reflection_from_rotations(rots)
    eye = torch.eye(s.shape[0], dtype=s.dtype)
    return st.sq + ((eye - s) * _a_matrix(st, t)).sum()


def _partial_products(mats, d: int, dtype: torch.dtype) -> tuple[list[torch.Tensor], list[torch.Tensor]]:
    """``prefix[j] = M_1 .. M_j`` and ``suffix[j] = M_(j+1) .. M_k`` for ``j = 0 .. k`` (``k + 1`` each).

    Every product the gradient and the Hessian need is one of these, so they cost ``O(k)``
    matrix products instead of ``O(k^2)`` (gradient) and ``O(k^3)`` (Hessian) if each
    were composed afresh; at ``d = 60`` that is the difference between minutes and
    milliseconds per Hessian product.
    """
    prefix = [torch.eye(d, dtype=dtype)]
    for m in mats:
        prefix.append(prefix[-1] @ m)
    suffix = [torch.eye(d, dtype=dtype)]
    for m in reversed(mats):
        suffix.append(m @ suffix[-1])
    suffix.reverse()
    return prefix, suffix


def _partial_derivatives(mats, dmats, prefix, suffix, d: int, dtype: torch.dtype) -> tuple[list[torch.Tensor], list[torch.Tensor]]:
    """Directional derivatives of ``prefix[j]`` and ``suffix[j]`` along ``(dM_1, .., dM_k)``,
    by the product rule in one sweep each: ``dP_j = dP_(j-1) M_j + P_(j-1) dM_j``."""
    zero = torch.zeros(d, d, dtype=dtype)
    dprefix = [zero]
    for j, (m, dm) in enumerate(zip(mats, dmats)):
        dprefix.append(dprefix[-1] @ m + prefix[j] @ dm)
    dsuffix = [zero]
    k = len(mats)
    for j in range(k - 1, -1, -1):
        dsuffix.append(dmats[j] @ suffix[j + 1] + mats[j] @ dsuffix[-1])
    dsuffix.reverse()
    return dprefix, dsuffix


def egrad(x, st: PairStatistics):
    """Euclidean gradient of :func:`reflection_cost`: Eq. 7.11 for each ``R_j`` and Eq. 7.10 for ``t``."""
    *rots, t = x
    d = t.shape[0]
    e = _e(d, t.dtype)
    a = _a_matrix(st, t)
    prefix, suffix = _partial_products(rots, d, t.dtype)
    full = prefix[-1]
    s = full @ e @ full.T
    eye = torch.eye(d, dtype=t.dtype)
    ate = a @ full @ e  # (d, d)
    grads = [-2.0 * prefix[j].T @ ate @ suffix[j + 1].T for j in range(len(rots))]  # Eq. 7.11
    g_t = 2.0 * (eye - s) @ (2.0 * st.w * t - st.sx - st.sy)  # Eq. 7.10
    return (*grads, g_t)


def ehess(x, u, st: PairStatistics):
    """Euclidean Hessian of :func:`reflection_cost` at ``x`` applied to ``u`` (derivative of Eqs. 7.10-7.11).

    The thesis differentiates the Riemannian gradient of each block on its own (Eqs. 7.14,
    7.15); here every cross term between the rotations and the translation is kept, so the
    trust-region model is the exact second-order one. The partial products of the
    rotations and their derivatives are built once per call (:func:`_partial_products`),
    ``O(d)`` matrix products in all.
    """
    *rots, t = x
    *drots, dt = u
    d = t.shape[0]
    dtype = t.dtype
    e = _e(d, dtype)
    eye = torch.eye(d, dtype=dtype)
    a = _a_matrix(st, t)
    dc = -st.sx[:, None] * dt[None, :] - dt[:, None] * st.sy[None, :] + st.w * (dt[:, None] * t[None, :] + t[:, None] * dt[None, :])
    da = dc + dc.T
    prefix, suffix = _partial_products(rots, d, dtype)
    dprefix, dsuffix = _partial_derivatives(rots, drots, prefix, suffix, d, dtype)
    full, dfull = prefix[-1], dprefix[-1]
    s = full @ e @ full.T
    ds = dfull @ e @ full.T + full @ e @ dfull.T
    afe = a @ full @ e
    dafe = (da @ full + a @ dfull) @ e
    hs = []
    for j in range(len(rots)):
        left, right = prefix[j], suffix[j + 1]
        dleft, dright = dprefix[j], dsuffix[j + 1]
        h = dleft.T @ afe @ right.T + left.T @ dafe @ right.T + left.T @ afe @ dright.T
        hs.append(-2.0 * h)
    h_t = -2.0 * ds @ (2.0 * st.w * t - st.sx - st.sy) + 4.0 * st.w * (eye - s) @ dt  # Eq. 7.15 plus the cross term
    return (*hs, h_t)


def thesis_rgrad(x, st: PairStatistics):
    """The Riemannian gradient written out as in Eqs. 7.12-7.13 (on SO(d) for each ``R_j``).

    ``xi_Rj = -R_j (R_1..R_j)^T A (R_1..R_{d-1}) E (R_{j+1}..R_{d-1})^T
    + R_j (R_{j+1}..R_{d-1}) E (R_1..R_{d-1})^T A (R_1..R_j)`` and ``xi_t`` = Eq. 7.10. Used to
    check :func:`egrad` followed by the manifold's projection; the solver itself projects
    further onto each ``SO(2, d)``.
    """
    *rots, t = x
    d = t.shape[0]
    e = _e(d, t.dtype)
    a = _a_matrix(st, t)
    full = compose(rots, d, t.dtype)
    out = []
    for j in range(len(rots)):
        upto = compose(rots[: j + 1], d, t.dtype)
        right = compose(rots[j + 1 :], d, t.dtype)
        out.append(-rots[j] @ upto.T @ a @ full @ e @ right.T + rots[j] @ right @ e @ full.T @ a @ upto)
    eye = torch.eye(d, dtype=t.dtype)
    s = full @ e @ full.T
    out.append(2.0 * (eye - s) @ (2.0 * st.w * t - st.sx - st.sy))
    return tuple(out)


def thesis_rhess(x, j: int, omega: torch.Tensor, st: PairStatistics) -> torch.Tensor:
    """The ``j``-th diagonal block of the Riemannian Hessian as written in Eq. 7.14 (on SO(d)).

    ``Hess_Rj[R_j Omega] = 1/2 R_j ([B_1, [R_j^T B_2 R_j, Omega]] + [[Omega, B_1], R_j^T B_2 R_j])``
    with ``B_1 = (R_{j+1}..R_{d-1}) E (R_{j+1}..R_{d-1})^T``, ``B_2 = (R_1..R_{j-1})^T A (R_1..R_{j-1})``
    and ``[U, V] = UV - VU``. Used to check :func:`ehess` (whose blocks, projected by
    :class:`~torchsym.manifolds.SpecialOrthogonal`, must agree); ``j`` is 0-based here.
    """
    *rots, t = x
    d = t.shape[0]
    e = _e(d, t.dtype)
    right = compose(rots[j + 1 :], d, t.dtype)
    left = compose(rots[:j], d, t.dtype)
    b1 = right @ e @ right.T
    b2 = left.T @ _a_matrix(st, t) @ left
    r = rots[j]
    c = r.T @ b2 @ r

    def br(u, v):
        return u @ v - v @ u

    return 0.5 * r @ (br(b1, br(c, omega)) + br(br(omega, b1), c))


def symmetry_error(points: torch.Tensor, mirrors: torch.Tensor, weights: torch.Tensor, x) -> torch.Tensor:
    """The symmetry error of Eq. 7.5 evaluated point by point (slow reference for tests), a scalar."""
    *rots, t = x
    s = reflection_from_rotations(rots)
    moved = (points - t) @ s.T + t  # (N, d)
    return (weights * ((moved - mirrors) ** 2).sum(1)).sum()
