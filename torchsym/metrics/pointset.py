"""Evaluation of reflection symmetry in d-dimensional point sets (thesis Secs. 7.4.2-7.4.3)."""

from __future__ import annotations

import math
from typing import Any

import torch

from torchsym.core.checks import check_points
from torchsym.errors import InputShapeError
from torchsym.geometry.reflection import plane_angle

__all__ = [
    "normal_angle_error",
    "pointset_correspondence_rate",
    "pointset_normal_precision",
    "pointset_symmetry_errors",
]


def _check_perm(perm: Any, n: int, name: str) -> torch.Tensor:
    p = torch.as_tensor(perm)
    if p.dim() != 1 or p.shape[0] != n or p.is_floating_point():
        raise InputShapeError(f"{name}: expected ({n},) integer indices, got {tuple(p.shape)} {p.dtype}")
    return p.long()


def pointset_correspondence_rate(points: Any, permutation: Any, true_permutation: Any, thresholds: Any) -> torch.Tensor:
    """Fraction of estimated correspondences that are correct, per distance threshold (Sec. 7.4.3).

    The estimated correspondence ``(i, i'_e)`` is correct at threshold ``tau_d`` when
    ``|x_{i'_e} - x_{i'_g}| < tau_d``, ``i'_g`` the true mirror of ``i``. The rate is the number
    of correct correspondences over the number of estimated ones (unmatched points, -1 in
    ``permutation``, are not estimates); 0 when there are none.

    Args:
        points: ``(N, D)`` points.
        permutation: ``(N,)`` estimated mirror indices, -1 for unmatched.
        true_permutation: ``(N,)`` true mirror indices.
        thresholds: ``(T,)`` distance thresholds ``tau_d`` (the thesis uses 0, 0.01, .., 0.34).

    Returns:
        ``(T,)`` rates in [0, 1] in the points' dtype.

    Example:
        >>> x = torch.tensor([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]])
        >>> pointset_correspondence_rate(x, torch.tensor([1, 0, 2]), torch.tensor([1, 0, 1]), torch.tensor([0.5, 3.0]))
        tensor([0.6667, 1.0000])
    """
    x = check_points(points, "points", min_dim=1, min_points=1)
    n = x.shape[0]
    est = _check_perm(permutation, n, "permutation")
    true = _check_perm(true_permutation, n, "true_permutation")
    tau = torch.as_tensor(thresholds, dtype=x.dtype).reshape(-1)
    matched = est >= 0
    if not bool(matched.any()):
        return torch.zeros_like(tau)
    dist = (x[est[matched]] - x[true[matched]]).norm(dim=-1)  # (M,)
    return (dist[None, :] < tau[:, None]).to(x.dtype).mean(1)


def normal_angle_error(normal: Any, true_normal: Any) -> torch.Tensor:
    """Angle in degrees between estimated and true hyperplanes, ``acos(|n_g . n_e|)``, shape ``(...)``."""
    a = torch.as_tensor(normal)
    b = torch.as_tensor(true_normal, dtype=a.dtype)
    if a.shape != b.shape or a.dim() < 1:
        raise InputShapeError(f"true_normal: expected the shape of normal {tuple(a.shape)}, got {tuple(b.shape)}")
    return torch.rad2deg(plane_angle(a, b))


def pointset_normal_precision(normals: Any, true_normals: Any, thresholds_deg: Any) -> torch.Tensor:
    """Fraction of point sets whose hyperplane is correct, per angle threshold (Sec. 7.4.3).

    A detected hyperplane is correct at threshold ``tau_theta`` when
    ``acos(|n_g . n_e|) < tau_theta`` (the thesis varies ``tau_theta`` over [0, 5] degrees).

    Args:
        normals: ``(K, D)`` estimated normals, one per point set.
        true_normals: ``(K, D)`` true normals.
        thresholds_deg: ``(T,)`` angle thresholds in degrees.

    Returns:
        ``(T,)`` precision rates in [0, 1].
    """
    err = normal_angle_error(normals, true_normals).reshape(-1)  # (K,)
    tau = torch.as_tensor(thresholds_deg, dtype=err.dtype).reshape(-1)
    return (err[None, :] < tau[:, None]).to(err.dtype).mean(1)


def pointset_symmetry_errors(points: Any, permutation: Any, normal: Any, offset: Any) -> tuple[torch.Tensor, torch.Tensor]:
    """The errors ``e_d`` and ``e_m`` of Sec. 7.4.2 for correspondences and a hyperplane.

    ``e_d = mean_i |<z_i, v>|`` with ``z_i = (x_i - x_i') / |x_i - x_i'|`` and ``v`` the unit
    normal: how well the chords joining mirror points align with the normal, exactly as the
    thesis writes it (1 when every chord is parallel to the normal, so compare it with the
    value for the true correspondences and plane, as the thesis does). ``e_m = mean_i
    |v . m_i + w_0|`` with ``m_i`` the chord midpoints: how far the midpoints are from the
    hyperplane (0 for a perfect symmetry). Unmatched points (-1) and points matched to
    themselves (no chord) are left out of ``e_d``; unmatched points are left out of ``e_m``.

    Args:
        points: ``(N, D)`` points.
        permutation: ``(N,)`` mirror indices, -1 for unmatched.
        normal: ``(D,)`` hyperplane normal (normalised here).
        offset: ``()`` hyperplane offset (``normal . x + offset = 0``), scaled with the normal.

    Returns:
        ``(e_d, e_m)``, two scalar tensors (NaN when no pair qualifies).
    """
    x = check_points(points, "points", min_dim=1, min_points=1)
    n, d = x.shape
    perm = _check_perm(permutation, n, "permutation")
    v = torch.as_tensor(normal, dtype=x.dtype).reshape(-1)
    if v.shape[0] != d:
        raise InputShapeError(f"normal: expected ({d},) to match points, got {tuple(v.shape)}")
    scale = v.norm()
    v = v / scale
    w0 = torch.as_tensor(offset, dtype=x.dtype) / scale
    matched = perm >= 0
    xi, xm = x[matched], x[perm[matched]]
    chord = xi - xm
    length = chord.norm(dim=-1)
    real = length > 0
    e_d = (chord[real] / length[real, None] @ v).abs().mean() if bool(real.any()) else torch.tensor(math.nan, dtype=x.dtype)
    mids = 0.5 * (xi + xm)
    e_m = (mids @ v + w0).abs().mean() if mids.shape[0] else torch.tensor(math.nan, dtype=x.dtype)
    return e_d, e_m
