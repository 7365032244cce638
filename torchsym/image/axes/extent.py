"""Where along its line an axis holds: the local mirror correlation's run about its centre.

The whole line through each axis (clipped to the level) is cut into ``n_bins`` stretches;
each stretch's support (the axis's half-width each side) is compared with its reflection
(numerator and energies of :func:`~torchsym.image.axes.mirror_ncc.mirror_ncc`, summed
over a window of three stretches). From the stretch of best correlation within the axis's
current extent, the extent grows both ways while the correlation stays at or above
``threshold`` (a stretch without contrast, energy below a tenth of the line's median,
ends it).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from torchsym.image.axes.mirror_ncc import AxisParams, _sample, support_grid

__all__ = ["grow_extent"]


def _line_span(axes: AxisParams, h: int, w: int) -> tuple[torch.Tensor, torch.Tensor]:
    """``(t_lo, t_hi)`` ``(N,)`` each: the part of each axis's line inside the ``h x w`` image, about its centre."""
    u = torch.stack([torch.cos(axes.angle), torch.sin(axes.angle)], -1)  # (N, 2)
    lo = torch.full_like(axes.angle, -1e9)
    hi = torch.full_like(axes.angle, 1e9)
    for k, size in ((0, w), (1, h)):
        d = u[:, k]
        safe = torch.where(d.abs() < 1e-9, torch.full_like(d, 1e-9), d)
        a = (0.0 - axes.centre[:, k]) / safe
        b = (size - 1.0 - axes.centre[:, k]) / safe
        lo = torch.maximum(lo, torch.minimum(a, b))
        hi = torch.minimum(hi, torch.maximum(a, b))
    return lo, hi


def grow_extent(level: torch.Tensor, axes: AxisParams, *, threshold: float, width: float, n_bins: int = 48,
                n_across: int = 12) -> AxisParams:
    """Each axis's extent along its line re-found from the local mirror correlation.

    Args:
        level: ``(C, h, w)`` the band-passed pyramid level.
        axes: ``N`` axes on the level.
        threshold: the least local correlation of a stretch inside the extent, in [-1, 1].
        width: the new half-width, times the new half-length.
        n_bins: stretches along the whole line.
        n_across: samples across each half of a stretch's support.

    Returns:
        The axes with new ``centre`` (moved along the line), ``half_length`` and ``half_width``.
    """
    h, w = level.shape[-2:]
    n = axes.centre.shape[0]
    lo, hi = _line_span(axes, h, w)
    mid, half = (lo + hi) / 2, (hi - lo).clamp_min(1.0) / 2
    u = torch.stack([torch.cos(axes.angle), torch.sin(axes.angle)], -1)
    whole = AxisParams(axes.centre + mid[:, None] * u, axes.angle, half, axes.half_width)
    p, q = support_grid(whole, n_bins, n_across)  # (N, B, S, 2)
    a, ia = _sample(level, p)
    b, ib = _sample(level, q)
    m = (ia & ib).float()[:, None]  # (N, 1, B, S)
    num = (a * b * m).sum((1, 3))  # (N, B)
    ea, eb = (a * a * m).sum((1, 3)), (b * b * m).sum((1, 3))
    box = torch.ones(1, 1, 3, device=level.device)
    num, ea, eb = (F.conv1d(v[:, None], box, padding=1)[:, 0] for v in (num, ea, eb))
    r = num / torch.sqrt(ea * eb).clamp_min(1e-12)  # (N, B)
    flat = torch.sqrt(ea * eb) < 0.1 * torch.sqrt(ea * eb).median(1, keepdim=True).values
    good = (r >= threshold) & ~flat
    tb = mid[:, None] + half[:, None] * torch.linspace(-1, 1, n_bins, device=level.device)[None]  # (N, B): t of each stretch
    inside = (tb >= -axes.half_length[:, None]) & (tb <= axes.half_length[:, None])
    seed = torch.where(inside & ~flat, r, torch.full_like(r, -2.0)).argmax(1)  # (N,)
    new_lo, new_hi = torch.empty(n, device=level.device), torch.empty(n, device=level.device)
    step = (2 * half / max(n_bins - 1, 1))
    for i in range(n):  # a short scan per axis (N <= a few tens)
        g = good[i].tolist()
        s = int(seed[i])
        j0 = j1 = s
        while j0 > 0 and g[j0 - 1]:
            j0 -= 1
        while j1 < n_bins - 1 and g[j1 + 1]:
            j1 += 1
        new_lo[i] = tb[i, j0] - step[i] / 2
        new_hi[i] = tb[i, j1] + step[i] / 2
    new_lo, new_hi = torch.maximum(new_lo, lo), torch.minimum(new_hi, hi)
    centre = axes.centre + ((new_lo + new_hi) / 2)[:, None] * u
    hl = ((new_hi - new_lo) / 2).clamp_min(2.0)
    return AxisParams(centre, axes.angle, hl, width * hl)
