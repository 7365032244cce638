"""Normals drawn uniformly from a spherical band around a direction (NeRD's cone sampling).

NeRD (``zhou13/nerd`` ``sym/datasets.py``, ``sample_sphere``) draws training planes at an
angle between ``theta0`` and ``theta1`` from the true normal: ``cos`` of the angle
uniform in ``[cos theta1, cos theta0]`` (uniform in area on the sphere's band) and the
azimuth uniform. Here for any ``D >= 2`` (the azimuth becomes a uniform direction in the
normal's orthogonal complement) and in degrees.
"""

from __future__ import annotations

import math

import torch

from torchsym.errors import InputShapeError, InputValueError

__all__ = ["sample_cone"]


def sample_cone(
    normal: torch.Tensor,
    n_samples: int,
    min_angle: float = 0.0,
    max_angle: float = 90.0,
    *,
    generator: torch.Generator | None = None,
) -> torch.Tensor:
    """``(..., n_samples, D)`` unit vectors at ``min_angle`` to ``max_angle`` degrees from ``normal (..., D)``.

    Args:
        normal: ``(..., D)`` centre directions (any non-zero length).
        n_samples: vectors per centre.
        min_angle, max_angle: band in degrees, ``0 <= min_angle <= max_angle <= 180``.
        generator: torch.Generator for the random draws; None uses a fresh default one.

    In 3D the density is uniform on the band (``cos`` uniform); in other dimensions the
    same rule is used, which is uniform in ``cos``, not in area.
    """
    if not isinstance(normal, torch.Tensor) or normal.dim() < 1 or normal.shape[-1] < 2:
        raise InputShapeError(f"normal: expected a (..., D) tensor with D >= 2, got {getattr(normal, 'shape', type(normal).__name__)}")
    if not 0 <= min_angle <= max_angle <= 180:
        raise InputValueError(f"min_angle, max_angle: expected 0 <= min <= max <= 180, got {min_angle}, {max_angle}")
    if generator is None:
        generator = torch.Generator(device=normal.device)
    v = normal / normal.norm(dim=-1, keepdim=True)
    shape = (*v.shape[:-1], n_samples)
    c0, c1 = math.cos(math.radians(max_angle)), math.cos(math.radians(min_angle))
    cos = c0 + (c1 - c0) * torch.rand(shape, generator=generator, dtype=v.dtype, device=v.device)
    g = torch.randn((*shape, v.shape[-1]), generator=generator, dtype=v.dtype, device=v.device)
    vv = v.unsqueeze(-2)
    g = g - (g * vv).sum(-1, keepdim=True) * vv  # orthogonal to v
    g = g / g.norm(dim=-1, keepdim=True).clamp_min(torch.finfo(v.dtype).tiny)
    sin = (1 - cos * cos).clamp_min(0).sqrt()
    return cos.unsqueeze(-1) * vv + sin.unsqueeze(-1) * g
