"""The photometric test of a candidate axis: the image against its own reflection.

An axis is parametrised by its centre ``c = (x, y)``, its direction angle ``phi`` (radians,
direction ``u = (cos phi, sin phi)``, normal ``n = (-sin phi, cos phi)``), its half-length
``L`` along ``u`` and the half-width ``W`` of its support across it. The support is
sampled on a grid ``c + t u + s n`` with ``t`` in ``[-L, L]`` and ``s`` in ``(0, W]``; each
sample is compared with its reflection ``c + t u - s n``. The score is the normalised
cross-correlation of the two sample sets (Cicconet et al. 2017 compare an image window
with its mirror the same way), pooled over colour channels.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

__all__ = ["AxisParams", "mirror_ncc", "support_grid"]


class AxisParams:
    """A batch of axes as tensors: ``centre (N, 2)``, ``angle (N,)`` radians, ``half_length
    (N,)`` and ``half_width (N,)`` px, all float32, on one device (plain holder, no logic)."""

    __slots__ = ("centre", "angle", "half_length", "half_width")

    def __init__(self, centre: torch.Tensor, angle: torch.Tensor, half_length: torch.Tensor, half_width: torch.Tensor) -> None:
        self.centre, self.angle, self.half_length, self.half_width = centre, angle, half_length, half_width


def support_grid(axes: AxisParams, n_along: int, n_across: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Sample points of each axis's support and their reflections.

    Returns:
        ``(points, mirrors)``, each ``(N, n_along, n_across, 2)`` float ``(x, y)`` px.
    """
    dev = axes.centre.device
    t = torch.linspace(-1.0, 1.0, n_along, device=dev)  # (A,)
    s = (torch.arange(n_across, device=dev, dtype=torch.float32) + 0.5) / n_across  # (S,)
    u = torch.stack([torch.cos(axes.angle), torch.sin(axes.angle)], -1)  # (N, 2)
    n = torch.stack([-u[:, 1], u[:, 0]], -1)  # (N, 2)
    along = (axes.half_length[:, None, None] * t[None, :, None])[..., None] * u[:, None, None]  # (N, A, 1, 2)
    across = (axes.half_width[:, None, None] * s[None, None, :])[..., None] * n[:, None, None]  # (N, 1, S, 2)
    base = axes.centre[:, None, None] + along  # (N, A, 1, 2)
    return base + across, base - across


def _sample(image: torch.Tensor, xy: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """``image (C, H, W)`` at ``xy (N, A, S, 2)`` px, bilinear: ``(values (N, C, A, S), inside (N, A, S))``."""
    h, w = image.shape[-2:]
    g = torch.stack([2 * xy[..., 0] / max(w - 1, 1) - 1, 2 * xy[..., 1] / max(h - 1, 1) - 1], -1)  # (N, A, S, 2)
    inside = (g.abs() <= 1).all(-1)
    v = F.grid_sample(image[None].expand(g.shape[0], -1, -1, -1), g, mode="bilinear", align_corners=True)
    return v, inside


def mirror_ncc(
    image: torch.Tensor, axes: AxisParams, *, n_along: int = 32, n_across: int = 16
) -> tuple[torch.Tensor, torch.Tensor]:
    """Normalised cross-correlation of each axis's support with its reflection.

    Args:
        image: ``(C, H, W)`` float image (any range; a pyramid level of the photo).
        axes: ``N`` axes in that image's pixels (:class:`AxisParams`).
        n_along: samples along each axis.
        n_across: samples across each half of the support.

    Samples outside the image read 0 (a band-passed level's value for "no structure"), so a
    support that leaves the image correlates less; each half's mean is removed per channel.

    Returns:
        ``(ncc (N,), inside (N,))``: the correlation in [-1, 1] (0 where a support has no
        contrast or no sample inside), and the fraction of sample pairs inside the image.
    """
    p, q = support_grid(axes, n_along, n_across)
    a, ia = _sample(image, p)  # zero outside the image: no structure there
    b, ib = _sample(image, q)
    a = a - a.mean((2, 3), keepdim=True)  # centred per channel
    b = b - b.mean((2, 3), keepdim=True)
    num = (a * b).sum((1, 2, 3))
    den = torch.sqrt((a * a).sum((1, 2, 3)) * (b * b).sum((1, 2, 3)))
    ncc = torch.where(den > 1e-8, num / den.clamp_min(1e-8), torch.zeros_like(num))
    return ncc, (ia & ib).float().mean((1, 2))
