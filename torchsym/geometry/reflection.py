"""Reflections through hyperplanes in R^d.

A reflection is a unit ``normal (..., D)`` and an ``offset (...)``; the hyperplane is
``{x : normal . x + offset = 0}`` and the reflection of ``x`` is the Householder map
``x - 2 (normal . x + offset) normal``. Every function takes leading batch dimensions,
keeps the input's dtype and device, and is differentiable.

The thesis (Sec. 5.2.1, Eq. 5.1) writes a 3D reflection as ``S = R^T D R`` with
``R = R_y(theta_y) R_x(theta_x)`` and ``D = diag(1, 1, -1)``; :func:`angles_to_normal`
and :func:`normal_to_angles` convert between that parametrisation and the normal.
"""

from __future__ import annotations

import math

import torch

from torchsym.errors import InputShapeError, InputValueError

__all__ = [
    "angles_to_normal",
    "canonical_sign",
    "normal_to_angles",
    "plane_angle",
    "plane_distance",
    "pair_fit_errors",
    "plane_from_pairs",
    "reflection_fit",
    "plane_from_reflection",
    "point_plane_distance",
    "reflect_points",
    "reflection_matrix",
    "reflection_matrix_from_angles",
    "reflection_transform",
    "spread_normals",
    "tangent_basis",
]


def _check_nonzero(norm: torch.Tensor, message: str) -> None:
    """Raise on a zero normal when that costs no host sync: only for CPU tensors outside
    ``torch.compile``. On an accelerator the check is skipped (a zero normal gives NaN),
    so a training loop never waits on the device."""
    if norm.device.type != "cpu" or torch.compiler.is_compiling():
        return
    if bool((norm == 0).any()):
        raise InputValueError(message)


def _unit(normal: torch.Tensor, offset: torch.Tensor | None = None):
    norm = normal.norm(dim=-1, keepdim=True)
    _check_nonzero(norm, "normal: expected a non-zero vector, got a zero vector")
    if offset is None:
        return normal / norm, None
    return normal / norm, offset / norm.squeeze(-1)


def _check_normal(normal: torch.Tensor) -> None:
    if not isinstance(normal, torch.Tensor) or normal.dim() < 1 or normal.shape[-1] < 1:
        raise InputShapeError(f"normal: expected a (..., D) tensor, got {getattr(normal, 'shape', type(normal).__name__)}")


def reflect_points(points: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor | float = 0.0) -> torch.Tensor:
    """Reflect points through the hyperplane ``normal . x + offset = 0``.

    Args:
        points: ``(..., N, D)`` points.
        normal: ``(..., D)`` plane normal (normalised here, so any non-zero length works).
        offset: ``(...)`` plane offset, scaled together with the normal.

    Returns:
        ``(..., N, D)`` reflected points: ``x - 2 (n . x + b) n``.

    Example:
        >>> reflect_points(torch.tensor([[1.0, 2.0]]), torch.tensor([1.0, 0.0]))
        tensor([[-1.,  2.]])
    """
    _check_normal(normal)
    if not isinstance(points, torch.Tensor) or points.dim() < 2:
        raise InputShapeError(f"points: expected a (..., N, D) tensor, got {getattr(points, 'shape', type(points).__name__)}")
    if points.shape[-1] != normal.shape[-1]:
        raise InputShapeError(f"points: expected (..., N, {normal.shape[-1]}) to match normal, got {tuple(points.shape)}")
    offset = torch.as_tensor(offset, dtype=points.dtype, device=points.device)
    n, b = _unit(normal, offset.expand(normal.shape[:-1]))
    signed = (points * n.unsqueeze(-2)).sum(-1) + b.unsqueeze(-1)  # (..., N)
    return points - 2.0 * signed.unsqueeze(-1) * n.unsqueeze(-2)


def reflection_matrix(normal: torch.Tensor) -> torch.Tensor:
    """The linear part ``I - 2 n n^T`` of the reflection, ``(..., D, D)``: symmetric, orthogonal, det -1."""
    _check_normal(normal)
    n, _ = _unit(normal)
    eye = torch.eye(n.shape[-1], dtype=n.dtype, device=n.device)
    return eye - 2.0 * n.unsqueeze(-1) * n.unsqueeze(-2)


def reflection_transform(normal: torch.Tensor, offset: torch.Tensor | float = 0.0) -> torch.Tensor:
    """The homogeneous ``(..., D+1, D+1)`` matrix of the reflection (acts on ``[x; 1]``)."""
    _check_normal(normal)
    offset = torch.as_tensor(offset, dtype=normal.dtype, device=normal.device).expand(normal.shape[:-1])
    n, b = _unit(normal, offset)
    d = n.shape[-1]
    out = torch.zeros(*n.shape[:-1], d + 1, d + 1, dtype=n.dtype, device=n.device)
    out[..., :d, :d] = reflection_matrix(n)
    out[..., :d, d] = -2.0 * b.unsqueeze(-1) * n
    out[..., d, d] = 1.0
    return out


def plane_from_reflection(matrix: torch.Tensor, point: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
    """Normal and offset of a reflection given as an orthogonal matrix and a point on its plane.

    The normal is the eigenvector of the eigenvalue -1 of ``(S + S^T) / 2``; for a
    reflection ``S = R^T D R`` (thesis Eq. 5.1) that is ``R^T e_D``. The sign is fixed so
    that the largest-magnitude component is positive.

    Args:
        matrix: ``(..., D, D)`` orthogonal matrix with determinant -1.
        point: ``(..., D)`` a point on the plane (the thesis's ``c``); origin if None.

    Returns:
        ``normal (..., D)`` unit and ``offset (...)``.
    """
    if matrix.dim() < 2 or matrix.shape[-1] != matrix.shape[-2]:
        raise InputShapeError(f"matrix: expected (..., D, D), got {tuple(matrix.shape)}")
    sym = 0.5 * (matrix + matrix.transpose(-1, -2))
    _, vecs = torch.linalg.eigh(sym)
    n = canonical_sign(vecs[..., :, 0])
    if point is None:
        b = torch.zeros(n.shape[:-1], dtype=n.dtype, device=n.device)
    else:
        b = -(n * point).sum(-1)
    return n, b


def canonical_sign(n: torch.Tensor, b: torch.Tensor | None = None):
    """Flip ``normal (..., D)`` (and ``offset (...)``) so the largest-magnitude component is positive."""
    idx = n.abs().argmax(dim=-1, keepdim=True)
    sign = torch.sign(torch.gather(n, -1, idx)).squeeze(-1)
    sign = torch.where(sign == 0, torch.ones_like(sign), sign)
    if b is None:
        return n * sign.unsqueeze(-1)
    return n * sign.unsqueeze(-1), b * sign


def plane_from_pairs(
    points: torch.Tensor,
    mirrors: torch.Tensor,
    weights: torch.Tensor | None = None,
    *,
    lam: float = 0.25,
    constraint: str = "normal",
) -> tuple[torch.Tensor, torch.Tensor]:
    """The hyperplane that best explains mirror pairs ``(p_i, q_i)`` (thesis Sec. 5.3.3, Eq. 5.6).

    Two constraints hold for a true mirror pair: the midpoint ``m_i`` lies on the plane
    (Eq. 5.5: ``n . m_i + b = 0``) and the chord ``u_i = p_i - q_i`` is parallel to the
    normal (Eq. 5.4: ``u_i x n = 0``; in d dimensions ``(|u_i|^2 I - u_i u_i^T) n = 0``).
    The energy ``sum_i w_i [(n . m_i + b)^2 + lam n^T (|u_i|^2 I - u_i u_i^T) n]`` is a
    quadratic form ``pi^T B pi`` in ``pi = [n; b]`` with the ``(D+1) x (D+1)`` matrix B
    of Eq. 5.6.

    ``constraint="plane"`` is the thesis's Eq. 5.7: the smallest eigenvector of B under
    ``|pi| = 1`` (its default weight is ``lam = 1``). That constraint depends on where the
    origin is, so the fit changes when the points are translated. ``constraint="normal"``
    (default) minimises under ``|n| = 1`` instead: the offset is eliminated in closed form
    (``b = -n . mean(m)``) and ``n`` is the smallest eigenvector of the ``D x D`` matrix
    ``lam sum w (|u|^2 I - u u^T) + sum w (m - mean m)(m - mean m)^T``. With the default
    ``lam = 1/4`` the energy equals ``1/4 sum_i w_i |reflect(p_i) - q_i|^2`` exactly, so the
    result is the least-squares reflection for the pairs, invariant to rigid motions.

    Args:
        points: ``(..., N, D)`` first points of the pairs.
        mirrors: ``(..., N, D)`` their mirror points.
        weights: ``(..., N)`` non-negative pair weights; None weighs all pairs 1.
        lam: weight of the perpendicularity constraint against the midpoint one.
        constraint: ``"normal"`` (|n| = 1, rigid-motion invariant) or ``"plane"`` (Eq. 5.7).

    Returns:
        ``normal (..., D)`` unit (largest component positive) and ``offset (...)``.

    Example:
        >>> p = torch.tensor([[1.0, 0.0], [2.0, 1.0]]); q = torch.tensor([[-1.0, 0.0], [-2.0, 1.0]])
        >>> n, b = plane_from_pairs(p, q); n.round(decimals=4), b.abs().round(decimals=4)
        (tensor([1., 0.]), tensor(0.))
    """
    if constraint not in ("normal", "plane"):
        raise InputValueError(f"constraint: expected 'normal' or 'plane', got {constraint!r}")
    w = _pair_weights(points, mirrors, weights)
    d = points.shape[-1]
    mid = 0.5 * (points + mirrors)  # (..., N, D)
    if constraint == "normal":
        mat, mean_m = _normal_form(points, mirrors, w, lam)
        _, vecs = torch.linalg.eigh(mat)
        n = vecs[..., :, 0]
        b = -(n * mean_m).sum(-1)
    else:
        chord = points - mirrors  # (..., N, D)
        wu = chord * w.unsqueeze(-1)
        eye = torch.eye(d, dtype=points.dtype, device=points.device)
        perp = (wu * chord).sum((-1, -2))[..., None, None] * eye - wu.transpose(-1, -2) @ chord  # (..., D, D)
        mh = torch.cat([mid, torch.ones_like(mid[..., :1])], dim=-1)  # (..., N, D+1)
        mat = (mh * w.unsqueeze(-1)).transpose(-1, -2) @ mh
        mat = mat.clone()
        mat[..., :d, :d] = mat[..., :d, :d] + lam * perp
        mat = 0.5 * (mat + mat.transpose(-1, -2))
        _, vecs = torch.linalg.eigh(mat)
        pi = vecs[..., :, 0]
        n, b = pi[..., :d], pi[..., d]
        norm = n.norm(dim=-1).clamp_min(torch.finfo(points.dtype).tiny)
        n, b = n / norm.unsqueeze(-1), b / norm
    return canonical_sign(n, b)


def _pair_weights(points, mirrors, weights: torch.Tensor | None) -> torch.Tensor:
    """Check the pairs ``points, mirrors (..., N, D)`` and return their weights ``(..., N)``
    in the points' dtype (1 when ``weights`` is None)."""
    if not isinstance(points, torch.Tensor) or not isinstance(mirrors, torch.Tensor):
        raise InputShapeError(
            f"points, mirrors: expected (..., N, D) tensors, got {type(points).__name__} and {type(mirrors).__name__}"
        )
    if points.shape != mirrors.shape or points.dim() < 2:
        raise InputShapeError(
            f"mirrors: expected the same (..., N, D) shape as points {tuple(points.shape)}, got {tuple(mirrors.shape)}"
        )
    if weights is None:
        return torch.ones(points.shape[:-1], dtype=points.dtype, device=points.device)
    if weights.shape != points.shape[:-1]:
        raise InputShapeError(f"weights: expected {tuple(points.shape[:-1])}, got {tuple(weights.shape)}")
    return weights.to(points.dtype)


def _normal_form(points: torch.Tensor, mirrors: torch.Tensor, w: torch.Tensor, lam: float):
    """The ``(..., D, D)`` matrix of :func:`plane_from_pairs` under ``|n| = 1`` and the
    weighted mean midpoint ``(..., D)``."""
    d = points.shape[-1]
    wsum = w.sum(-1).clamp_min(torch.finfo(points.dtype).tiny)  # (...)
    mid = 0.5 * (points + mirrors)  # (..., N, D)
    chord = points - mirrors  # (..., N, D)
    eye = torch.eye(d, dtype=points.dtype, device=points.device)
    wu = chord * w.unsqueeze(-1)
    perp = (wu * chord).sum((-1, -2))[..., None, None] * eye - wu.transpose(-1, -2) @ chord  # (..., D, D)
    mean_m = (mid * w.unsqueeze(-1)).sum(-2) / wsum.unsqueeze(-1)  # (..., D)
    mc = mid - mean_m.unsqueeze(-2)
    mat = lam * perp + (mc * w.unsqueeze(-1)).transpose(-1, -2) @ mc
    return 0.5 * (mat + mat.transpose(-1, -2)), mean_m


def pair_fit_errors(
    points: torch.Tensor, mirrors: torch.Tensor, weights: torch.Tensor | None = None
) -> tuple[torch.Tensor, torch.Tensor]:
    """Standard errors of the least-squares reflection :func:`plane_from_pairs` fits to
    the pairs ``points, mirrors (..., N, D)`` (``weights (..., N)``, default 1).

    With ``l_1 <= l_2`` the two smallest eigenvalues of the fit's matrix (the energy
    ``l_1 = 1/4 sum w |S p - q|^2``, ``D`` residual coordinates a pair), the residual
    energy per coordinate is ``s^2 = l_1 / (D m - D)`` (``m``: the effective number of
    pairs, ``(sum w)^2 / sum w^2``; ``D`` parameters fitted), and on the unit sphere the
    energy rises as ``(l_2 - l_1) t^2`` along the least determined direction, so the
    normal's standard error is ``sqrt(s^2 / (l_2 - l_1))`` radians and the offset's
    ``sqrt(s^2 / sum w)`` (the usual Gauss-Newton covariance of a least-squares fit).

    Returns:
        ``angle (...)`` in radians and ``offset (...)`` in the points' units.
    """
    w = _pair_weights(points, mirrors, weights)
    mat, _ = _normal_form(points, mirrors, w, 0.25)
    return _fit_errors(torch.linalg.eigvalsh(mat), w)


def reflection_fit(
    points: torch.Tensor, mirrors: torch.Tensor, weights: torch.Tensor | None = None
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """The least-squares reflection of the pairs ``points, mirrors (..., N, D)`` (weights
    ``(..., N)``) and its standard errors, from one eigendecomposition of the fit's matrix:
    :func:`plane_from_pairs` (``constraint="normal"``, ``lam=1/4``) and
    :func:`pair_fit_errors` together.

    Returns:
        ``normal (..., D)`` (largest component positive), ``offset (...)``, the normal's
        standard error ``(...)`` in radians and the offset's ``(...)`` in the points' units.
    """
    w = _pair_weights(points, mirrors, weights)
    mat, mean_m = _normal_form(points, mirrors, w, 0.25)
    lams, vecs = torch.linalg.eigh(mat)
    n = vecs[..., :, 0]
    normal, offset = canonical_sign(n, -(n * mean_m).sum(-1))
    return (normal, offset, *_fit_errors(lams, w))


def _fit_errors(lams: torch.Tensor, w: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Standard errors of the normal and the offset (:func:`pair_fit_errors`) from the
    ascending eigenvalues ``(..., D)`` of the fit's matrix and the weights ``(..., N)``."""
    d = lams.shape[-1]
    tiny = torch.finfo(lams.dtype).tiny
    wsum = w.sum(-1).clamp_min(tiny)
    m_eff = wsum**2 / (w * w).sum(-1).clamp_min(tiny)
    var = lams[..., 0].clamp_min(0) / (d * m_eff - d).clamp_min(1.0) * (wsum / m_eff)  # per coordinate and unit weight
    angle = (var / (lams[..., 1] - lams[..., 0]).clamp_min(tiny)).sqrt()
    return angle, (var / wsum).sqrt()


def tangent_basis(normal: torch.Tensor) -> torch.Tensor:
    """``(..., 3, 2)`` orthonormal basis ``[u, v]`` of the plane orthogonal to a unit 3D ``normal (..., 3)``.

    ``u = normal x e`` with ``e`` the first or second coordinate axis (whichever is farther
    from the normal), ``v = normal x u``: a right-handed frame ``(u, v, normal)``.
    """
    _check_normal(normal)
    if normal.shape[-1] != 3:
        raise InputShapeError(f"normal: expected (..., 3), got {tuple(normal.shape)}")
    ex = torch.tensor([1.0, 0.0, 0.0], dtype=normal.dtype, device=normal.device)
    ey = torch.tensor([0.0, 1.0, 0.0], dtype=normal.dtype, device=normal.device)
    helper = torch.where(normal[..., :1].abs() < 0.9, ex, ey)
    u = torch.linalg.cross(normal, helper)
    u = u / u.norm(dim=-1, keepdim=True)
    return torch.stack([u, torch.linalg.cross(normal, u)], -1)


def point_plane_distance(points: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor | float = 0.0) -> torch.Tensor:
    """Signed distance ``n . x + b`` of ``(..., N, D)`` points to the plane, ``(..., N)``."""
    _check_normal(normal)
    offset = torch.as_tensor(offset, dtype=points.dtype, device=points.device).expand(normal.shape[:-1])
    n, b = _unit(normal, offset)
    return (points * n.unsqueeze(-2)).sum(-1) + b.unsqueeze(-1)


def plane_angle(normal_a: torch.Tensor, normal_b: torch.Tensor, *, oriented: bool = False) -> torch.Tensor:
    """Angle in radians between two hyperplanes (their normals), ``(...)``.

    Planes have no orientation, so by default the angle is in ``[0, pi/2]`` (``n`` and
    ``-n`` are the same plane); ``oriented=True`` gives the angle in ``[0, pi]``.
    Computed as ``atan2(|a - (a.b) b|, a.b)``, which stays accurate near 0, unlike ``acos``.
    """
    _check_normal(normal_a)
    _check_normal(normal_b)
    if normal_a.shape[-1] != normal_b.shape[-1]:
        raise InputShapeError(f"normal_b: expected (..., {normal_a.shape[-1]}) like normal_a, got {tuple(normal_b.shape)}")
    a, _ = _unit(normal_a)
    b, _ = _unit(normal_b)
    cos = (a * b).sum(-1)
    if not oriented:
        sign = torch.where(cos < 0, -torch.ones_like(cos), torch.ones_like(cos))
        a = a * sign.unsqueeze(-1)
        cos = cos * sign
    sin = (a - cos.unsqueeze(-1) * b).norm(dim=-1)
    return torch.atan2(sin, cos)


def spread_normals(normals: torch.Tensor, order: torch.Tensor, count: int, min_separation: float) -> list[int]:
    """Up to ``count`` indices of ``normals (K, D)``, taken greedily in ``order``, each more
    than ``min_separation`` degrees (as planes: ``n`` and ``-n`` are one) from every index
    already kept; one matrix of ``|cos|``, not a call per pair. Used to keep several
    starting planes that are not near-copies of one another."""
    too_close = (normals @ normals.T).abs() > math.cos(math.radians(min_separation))  # (K, K)
    blocked = torch.zeros(normals.shape[0], dtype=torch.bool, device=normals.device)
    out: list[int] = []
    for k in order.tolist():
        if len(out) == count:
            break
        if not bool(blocked[k]):
            out.append(k)
            blocked |= too_close[k]
    return out


def plane_distance(
    normal_a: torch.Tensor,
    offset_a: torch.Tensor | float,
    normal_b: torch.Tensor,
    offset_b: torch.Tensor | float,
    point: torch.Tensor | None = None,
) -> torch.Tensor:
    """Distance between two hyperplanes ``n . x + b = 0`` as seen from ``point``, ``(...)``.

    The mean of two distances: from the foot of ``point`` on plane a to plane b, and from
    its foot on plane b to plane a. For parallel planes this is their separation whatever
    ``point`` is; for planes that cross it measures how far apart they are near ``point``
    (0 when ``point`` lies on their intersection), as an evaluation needs (e.g. ``point``
    the object's centre). ``point=None`` is the origin. Batched over leading dimensions
    and differentiable; any dimension ``D >= 2``; signs of the normals do not matter.

    Args:
        normal_a, normal_b: ``(..., D)`` normals (need not be unit).
        offset_a, offset_b: ``(...)`` offsets.
        point: ``(..., D)`` reference point, or None.
    """
    for name, nrm in (("normal_a", normal_a), ("normal_b", normal_b)):
        if not isinstance(nrm, torch.Tensor) or nrm.dim() < 1 or nrm.shape[-1] < 2:
            raise InputShapeError(f"{name}: expected a (..., D) tensor with D >= 2, got {getattr(nrm, 'shape', type(nrm).__name__)}")
        _check_nonzero(nrm.norm(dim=-1), f"{name}: expected non-zero normals, got a zero vector")
    if normal_a.shape[-1] != normal_b.shape[-1]:
        raise InputShapeError(f"normal_b: expected (..., {normal_a.shape[-1]}) like normal_a, got {tuple(normal_b.shape)}")
    if point is not None and not isinstance(point, torch.Tensor):
        raise InputShapeError(f"point: expected a (..., {normal_a.shape[-1]}) tensor or None, got {type(point).__name__}")
    a, ba = _unit(normal_a, torch.as_tensor(offset_a, dtype=normal_a.dtype, device=normal_a.device))
    b, bb = _unit(normal_b, torch.as_tensor(offset_b, dtype=normal_b.dtype, device=normal_b.device))
    if point is None:
        point = torch.zeros_like(a)
    elif point.shape[-1] != a.shape[-1]:
        raise InputShapeError(f"point: expected (..., {a.shape[-1]}) like the normals, got {tuple(point.shape)}")
    foot_a = point - ((point * a).sum(-1) + ba).unsqueeze(-1) * a
    foot_b = point - ((point * b).sum(-1) + bb).unsqueeze(-1) * b
    return 0.5 * (((foot_a * b).sum(-1) + bb).abs() + ((foot_b * a).sum(-1) + ba).abs())


def _rot_x(t: torch.Tensor) -> torch.Tensor:
    c, s, o, z = torch.cos(t), torch.sin(t), torch.ones_like(t), torch.zeros_like(t)
    return torch.stack([o, z, z, z, c, -s, z, s, c], -1).reshape(*t.shape, 3, 3)


def _rot_y(t: torch.Tensor) -> torch.Tensor:
    c, s, o, z = torch.cos(t), torch.sin(t), torch.ones_like(t), torch.zeros_like(t)
    return torch.stack([c, z, s, z, o, z, -s, z, c], -1).reshape(*t.shape, 3, 3)


def reflection_matrix_from_angles(theta_x: torch.Tensor, theta_y: torch.Tensor) -> torch.Tensor:
    """``S = R^T D R`` with ``R = R_y(theta_y) R_x(theta_x)``, ``D = diag(1, 1, -1)`` (Eq. 5.1), ``(..., 3, 3)``."""
    theta_x, theta_y = torch.broadcast_tensors(torch.as_tensor(theta_x), torch.as_tensor(theta_y))
    r = _rot_y(theta_y) @ _rot_x(theta_x)
    dmat = torch.diag(torch.tensor([1.0, 1.0, -1.0], dtype=r.dtype, device=r.device))
    return r.transpose(-1, -2) @ dmat @ r


def angles_to_normal(theta_x: torch.Tensor, theta_y: torch.Tensor) -> torch.Tensor:
    """Normal ``R^T e_3 = (-sin ty, sin tx cos ty, cos tx cos ty)`` of the Eq. 5.1 reflection, ``(..., 3)``.

    Angles in radians; ``[-pi/2, pi/2]^2`` covers every plane through the origin once
    (up to the sign of the normal), which is the grid domain of Algorithm 5.
    """
    theta_x, theta_y = torch.broadcast_tensors(torch.as_tensor(theta_x), torch.as_tensor(theta_y))
    cy = torch.cos(theta_y)
    return torch.stack([-torch.sin(theta_y), torch.sin(theta_x) * cy, torch.cos(theta_x) * cy], -1)


def normal_to_angles(normal: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Inverse of :func:`angles_to_normal`: ``(theta_x, theta_y)`` in radians, each ``(...)``.

    The normal's sign is chosen so that ``theta_x`` falls in ``[-pi/2, pi/2]``.
    """
    if normal.shape[-1] != 3:
        raise InputShapeError(f"normal: expected (..., 3), got {tuple(normal.shape)}")
    n, _ = _unit(normal)
    flip = torch.where(n[..., 2] < 0, -torch.ones_like(n[..., 2]), torch.ones_like(n[..., 2]))
    n = n * flip.unsqueeze(-1)
    theta_y = torch.asin((-n[..., 0]).clamp(-1.0, 1.0))
    theta_x = torch.atan2(n[..., 1], n[..., 2])
    return theta_x, theta_y
