"""The pyramid level the photometric test runs on, and segments mapped to and from it."""

from __future__ import annotations

import math

import kornia
import torch
import torch.nn.functional as F

from torchsym.image.axes.mirror_ncc import AxisParams

__all__ = ["band_level", "from_level", "to_level"]


def band_level(image: torch.Tensor, side: int, band_sigma: float) -> tuple[torch.Tensor, tuple[float, float]]:
    """``image (1, C, H, W)`` shrunk (area) so its longer side is at most ``side``, minus its
    Gaussian blur of ``band_sigma`` px (none for 0).

    Returns:
        ``(level (C, h, w), (sx, sy))`` with ``x_level = (x + 0.5) sx - 0.5`` (likewise y).
    """
    h, w = int(image.shape[-2]), int(image.shape[-1])
    s = min(1.0, side / max(h, w))
    size = (max(8, round(h * s)), max(8, round(w * s)))
    lv = F.interpolate(image.float(), size=size, mode="area") if size != (h, w) else image.float()
    if band_sigma > 0:
        k = 2 * math.ceil(3 * band_sigma) + 1
        lv = lv - kornia.filters.gaussian_blur2d(lv, (k, k), (band_sigma, band_sigma), border_type="replicate")
    return lv[0], (size[1] / w, size[0] / h)


def to_level(segments: torch.Tensor, scale: tuple[float, float], width: float) -> AxisParams:
    """Segments ``(N, 4)`` in image pixels as :class:`AxisParams` on the level (half-width
    ``width`` times the half-length)."""
    sx, sy = scale
    seg = segments.float().clone()
    seg[:, 0::2] = (seg[:, 0::2] + 0.5) * sx - 0.5
    seg[:, 1::2] = (seg[:, 1::2] + 0.5) * sy - 0.5
    d = seg[:, 2:] - seg[:, :2]  # (N, 2)
    half = d.norm(dim=1) / 2
    return AxisParams((seg[:, :2] + seg[:, 2:]) / 2, torch.atan2(d[:, 1], d[:, 0]), half, width * half)


def from_level(axes: AxisParams, scale: tuple[float, float]) -> torch.Tensor:
    """:class:`AxisParams` on the level as segments ``(N, 4)`` ``x1, y1, x2, y2`` in image pixels."""
    sx, sy = scale
    u = torch.stack([torch.cos(axes.angle), torch.sin(axes.angle)], -1)  # (N, 2)
    seg = torch.cat([axes.centre - axes.half_length[:, None] * u, axes.centre + axes.half_length[:, None] * u], 1)
    seg[:, 0::2] = (seg[:, 0::2] + 0.5) / sx - 0.5
    seg[:, 1::2] = (seg[:, 1::2] + 0.5) / sy - 0.5
    return seg
