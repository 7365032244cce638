"""Evaluation of multi-view plane detection (thesis Sec. 5.3.5-5.3.6).

Two reconstructions of one scene (or a reconstruction and a rendered scene's truth) live
in frames that differ by a similarity. :func:`align_cameras` finds it from the cameras
both share (Umeyama's least squares on their centres); :func:`plane_errors` then
compares a plane with a reference in the reference's frame: the angle between the
normals and the distance between the planes at the reference's centre.
"""

from __future__ import annotations

import math

import torch

from torchsym.errors import InputShapeError, InputValueError

__all__ = ["align_cameras", "camera_centers", "plane_errors", "transform_plane"]


def camera_centers(rotations: torch.Tensor, translations: torch.Tensor) -> torch.Tensor:
    """Camera centres ``-R^T t``, ``(C, 3)``, of camera-from-world ``rotations (C, 3, 3)``
    and ``translations (C, 3)``."""
    return -(rotations.transpose(-1, -2) @ translations.unsqueeze(-1)).squeeze(-1)


def align_cameras(source: torch.Tensor, target: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The similarity ``x -> s R x + t`` taking camera centres ``source (C, 3)`` closest to
    ``target (C, 3)`` (Umeyama 1991), ``C >= 3`` not all on a line.

    Returns:
        ``scale ()``, ``rotation (3, 3)`` (det +1) and ``translation (3,)``.
    """
    if source.shape != target.shape or source.dim() != 2 or source.shape[1] != 3 or source.shape[0] < 3:
        raise InputShapeError(f"source, target: expected two (C, 3) with C >= 3, got {tuple(source.shape)} and {tuple(target.shape)}")
    src, dst = source.double(), target.double()
    ms, md = src.mean(0), dst.mean(0)
    xs, xd = src - ms, dst - md
    var = (xs * xs).sum() / len(src)
    if float(var) == 0.0:
        raise InputValueError("source: the camera centres coincide")
    u, sv, vt = torch.linalg.svd(xd.T @ xs / len(src))
    d = torch.ones(3, dtype=src.dtype)
    d[2] = torch.sign(torch.det(u @ vt))
    rot = u @ torch.diag(d) @ vt
    scale = (sv * d).sum() / var
    return scale, rot, md - scale * rot @ ms


def transform_plane(
    normal: torch.Tensor, offset: torch.Tensor, scale: torch.Tensor, rotation: torch.Tensor, translation: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """The plane ``n . x + b = 0`` moved by ``x -> s R x + t``: ``(R n, s b - R n . t)``."""
    n = rotation @ normal.double()
    return n, scale * offset.double() - n @ translation


def plane_errors(
    normal: torch.Tensor, offset: torch.Tensor, ref_normal: torch.Tensor, ref_offset: torch.Tensor, center: torch.Tensor
) -> tuple[float, float]:
    """The angle (degrees, sign-invariant) between two planes' normals and the distance,
    along the reference normal, between the two planes at the point of the reference
    plane nearest ``center (3,)`` (input units)."""
    n, rn = normal.double() / normal.double().norm(), ref_normal.double() / ref_normal.double().norm()
    b, rb = offset.double() / normal.double().norm(), ref_offset.double() / ref_normal.double().norm()
    cos = float((n @ rn).abs().clamp(max=1.0))
    angle = math.degrees(math.acos(cos))
    foot = center.double() - (rn @ center.double() + rb) * rn  # on the reference plane
    # distance from foot to the other plane along its normal
    distance = abs(float(n @ foot + b))
    return angle, distance
