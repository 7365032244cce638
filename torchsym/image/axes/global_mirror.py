"""The photograph registered with its own mirror image over every axis direction, by FFT.

For an axis direction ``phi`` (``u = (cos phi, sin phi)``, normal ``n = (-sin phi, cos
phi)``) the level is resampled on a square grid whose rows run along ``n`` (the axis is a
column), so the reflection about the axis at normal coordinate ``o`` maps a row's sample
``s`` to ``2 o - s``. Then, summed over rows, ``num(k) = sum a(s) a(k - s)`` is the
autoconvolution of the rows at ``k = 2 o`` (one real FFT per row), and ``energy(k) = sum
a(s)^2 m(k - s)`` (``m`` the inside mask) makes it a correlation in [-1, 1]: the
photograph against its mirror about every line of that direction at once (after the
global registration of Cicconet et al. 2017, whose detector registers an image with its
mirror by correlation). Offsets where the overlap of the image and its mirror is under
``min_overlap`` of the image are left out (a sliver of overlap correlates by chance).
"""

from __future__ import annotations

import functools
import math

import torch
import torch.nn.functional as F

from torchsym.image.axes.mirror_ncc import AxisParams

__all__ = ["MirrorMap", "axis_correlation", "mirror_map", "map_peaks"]


class MirrorMap:
    """The correlation of a level with its mirror: ``ncc (A, K)`` over axis angles ``angles
    (A,)`` (radians in [0, pi)) and normal coordinates ``k / 2`` (px of the rotated grid,
    whose centre ``half`` is the level's centre ``centre (2,)``); -1 where the overlap is too
    small (plain holder)."""

    __slots__ = ("angles", "ncc", "centre", "half")

    def __init__(self, angles: torch.Tensor, ncc: torch.Tensor, centre: torch.Tensor, half: float) -> None:
        self.angles, self.ncc, self.centre, self.half = angles, ncc, centre, half


def _rotated(level: torch.Tensor, angles: torch.Tensor, size: int) -> tuple[torch.Tensor, torch.Tensor]:
    """``level (C, h, w)`` resampled for each angle on a ``size x size`` grid, rows along the
    normal: ``(values (A, C, size, size), inside (A, 1, size, size))``."""
    c, h, w = level.shape
    dev = level.device
    r = torch.arange(size, dtype=torch.float32, device=dev) - (size - 1) / 2
    s, t = r[None, :], r[:, None]  # s: column (along the normal), t: row (along the axis)
    u = torch.stack([torch.cos(angles), torch.sin(angles)], -1)  # (A, 2)
    n = torch.stack([-u[:, 1], u[:, 0]], -1)
    cx, cy = (w - 1) / 2, (h - 1) / 2
    x = cx + s[None] * n[:, 0, None, None] + t[None] * u[:, 0, None, None]  # (A, size, size)
    y = cy + s[None] * n[:, 1, None, None] + t[None] * u[:, 1, None, None]
    grid = torch.stack([2 * x / max(w - 1, 1) - 1, 2 * y / max(h - 1, 1) - 1], -1)
    vals = F.grid_sample(level[None].expand(len(angles), -1, -1, -1), grid, mode="bilinear", align_corners=True)
    inside = (grid.abs() <= 1).all(-1)[:, None].float()
    return vals * inside, inside


def _fast_length(n: int) -> int:
    """The least length >= ``n`` whose only prime factors are 2, 3 and 5 (a fast FFT size)."""
    while True:
        m = n
        for p in (2, 3, 5):
            while m % p == 0:
                m //= p
        if m == 1:
            return n
        n += 1


@functools.lru_cache(maxsize=4)
def _geometry(h: int, w: int, n_angles: int, size: int, nfft: int, device: str) -> tuple[torch.Tensor, torch.Tensor]:
    """What depends on the level's size only: the rows' spectra of the inside mask ``(A, 1, S, F)``
    and the overlap of the level with its mirror ``(A, 2S)`` (cached: one photograph size after another)."""
    angles = torch.arange(n_angles, dtype=torch.float32, device=device) * (math.pi / n_angles)
    _, inside = _rotated(torch.zeros(1, h, w, device=device), angles, size)
    fi = torch.fft.rfft(inside, n=nfft, dim=-1)
    overlap = torch.fft.irfft((fi * fi).sum((1, 2)), n=nfft, dim=-1)[:, : 2 * size]
    return fi, overlap


def mirror_map(level: torch.Tensor, *, n_angles: int = 90, min_overlap: float = 0.25) -> MirrorMap:
    """The correlation of ``level (C, h, w)`` (band-passed: about zero-mean) with its mirror
    about every line, at ``n_angles`` axis directions in [0, pi) (:class:`MirrorMap`)."""
    c, h, w = level.shape
    size = int(math.ceil(math.hypot(h, w))) | 1
    angles = torch.arange(n_angles, dtype=torch.float32, device=level.device) * (math.pi / n_angles)
    vals, _ = _rotated(level.float(), angles, size)  # (A, C, S, S), zero outside the level
    nfft = _fast_length(2 * size - 1)
    fi, overlap = _geometry(h, w, n_angles, size, nfft, str(level.device))
    fa = torch.fft.rfft(vals, n=nfft, dim=-1)
    fe = torch.fft.rfft((vals * vals).sum(1, keepdim=True), n=nfft, dim=-1)
    # the sums over channels and rows are taken on the spectra: one inverse FFT per angle
    num = torch.fft.irfft((fa * fa).sum((1, 2)), n=nfft, dim=-1)[:, : 2 * size]  # (A, 2S)
    e = torch.fft.irfft((fe * fi).sum((1, 2)), n=nfft, dim=-1)[:, : 2 * size]
    ok = overlap >= min_overlap * float(h * w)
    ncc = torch.where(ok & (e > 1e-9), num / e.clamp_min(1e-9), torch.full_like(num, -1.0))
    return MirrorMap(angles, ncc.clamp(-1.0, 1.0), torch.tensor([(w - 1) / 2, (h - 1) / 2], device=level.device),
                     (size - 1) / 2)


def _offsets(mmap: MirrorMap, centre: torch.Tensor, angle: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Each axis (``centre (N, 2)``, ``angle (N,)``) as ``(angle in [0, pi), k)``: its index ``k`` on the map."""
    a = torch.remainder(angle, math.pi)
    n = torch.stack([-torch.sin(a), torch.cos(a)], -1)
    o = ((centre - mmap.centre[None]) * n).sum(-1) + mmap.half  # normal coordinate on the rotated grid
    return a, 2 * o


def axis_correlation(mmap: MirrorMap, axes: AxisParams) -> torch.Tensor:
    """The map's correlation at each axis's angle and offset (nearest angle, linear in
    offset): ``(N,)`` in [-1, 1], -1 off the map."""
    a, k = _offsets(mmap, axes.centre, axes.angle)
    n_a, n_k = mmap.ncc.shape
    ia = torch.round(a / (math.pi / n_a)).long() % n_a
    k0 = k.floor().long()
    f = k - k0
    inside = (k0 >= 0) & (k0 + 1 < n_k)
    k0c = k0.clamp(0, n_k - 2)
    v = mmap.ncc[ia, k0c] * (1 - f) + mmap.ncc[ia, k0c + 1] * f
    return torch.where(inside, v, torch.full_like(v, -1.0))


def map_peaks(mmap: MirrorMap, count: int, *, angle_gap: float = 10.0, offset_gap: float = 0.05,
              ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The ``count`` best local maxima of the map, each at least ``angle_gap`` degrees or
    ``offset_gap`` x the grid apart from a better one: ``(angle (P,), centre (P, 2), ncc (P,))``,
    each axis's centre the foot of the level's centre on its line."""
    ncc = mmap.ncc
    n_a, n_k = ncc.shape
    pooled = F.max_pool1d(ncc[:, None], 5, 1, 2)[:, 0]  # along the offset
    cand = ((ncc >= pooled) & (ncc > -1)).nonzero()
    order = ncc[cand[:, 0], cand[:, 1]].argsort(descending=True)
    picked: list[tuple[int, int]] = []
    step = 180.0 / n_a
    for i in order.tolist():
        ia, k = int(cand[i, 0]), int(cand[i, 1])
        clash = False
        for ja, kk in picked:
            da = abs(ia - ja) * step
            da = min(da, 180.0 - da)
            if da < angle_gap and abs(k - kk) / 2 < offset_gap * 2 * mmap.half:
                clash = True
                break
        if not clash:
            picked.append((ia, k))
        if len(picked) == count:
            break
    if not picked:
        z = torch.zeros(0, device=ncc.device)
        return z, torch.zeros(0, 2, device=ncc.device), z
    ia = torch.tensor([p[0] for p in picked], device=ncc.device)
    ki = torch.tensor([p[1] for p in picked], device=ncc.device)
    # sub-bin angle and offset: the vertex of a parabola through each peak and its neighbours
    def vertex(lo: torch.Tensor, mid: torch.Tensor, hi: torch.Tensor) -> torch.Tensor:
        den = lo - 2 * mid + hi
        return torch.where(den < -1e-9, 0.5 * (lo - hi) / den.clamp_max(-1e-9), torch.zeros_like(mid)).clamp(-0.5, 0.5)
    mid = ncc[ia, ki]
    da = vertex(ncc[(ia - 1) % n_a, ki], mid, ncc[(ia + 1) % n_a, ki])
    dk = vertex(ncc[ia, (ki - 1).clamp_min(0)], mid, ncc[ia, (ki + 1).clamp_max(n_k - 1)])
    angle = mmap.angles[ia] + da * (math.pi / n_a)
    kk = ki.float() + dk
    n = torch.stack([-torch.sin(angle), torch.cos(angle)], -1)
    centre = mmap.centre[None] + (kk / 2 - mmap.half)[:, None] * n
    return angle, centre, mid
