"""Mirror pixel pairs: boundary curves, their alignment costs and a Hough vote of the
axes they define (thesis Sec. 4.2.1).

For edge pixels ``x_i, x_i'`` with curves ``c_i, c_i'`` of ``p`` pixels centred on them,
the reflection about their bisector should carry one curve onto the other: the
alignment costs ``o_ii'`` and ``o_i'i`` of Eqs. 4.3-4.4 (equal, since the reflection is an
isometric involution; the curves are compared in both directions of travel and the
better kept, as a chain's direction carries no meaning). Each edge pixel is paired with
``h`` random others (the thesis's probability argument); each pair votes for its axis
``(phi, rho)`` with weight ``exp(-(o + o') / 4 sigma^2)``; the dominant peaks of the vote
are the symmetry axes, each refitted to its pairs, refined on the image
(:func:`refine_axis_photometric`) and kept when enough of the edge pixels around its
pairs have a mirror edge pixel (the support, which separates an object's symmetry from
pairs that chance lines up). The gradient consistency of Eq. 4.5, which the thesis applies to
the pairs of each peak, is applied before the vote: a pair it rejects could not be kept,
and without its vote the peaks stand out (and the curve costs are computed for a fifth
of the random pairs).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import torch
import torch.nn.functional as F

from torchsym.image.boundary import boundary_curves
from torchsym.image.symmslic.settings import MirrorPairSettings

__all__ = ["MirrorPixelPairs", "curve_samples", "intensity_stack", "mirror_edge_matches", "mirror_pixel_pairs", "refine_axis_photometric", "reflect_2d"]


@dataclasses.dataclass(frozen=True)
class MirrorPixelPairs:
    """Mirror pixel pairs grouped by symmetry axis (the thesis's sets L and R).

    Attributes:
        left: ``(P, 2)`` float64 pixels ``(x, y)`` on the negative side of their axis.
        right: ``(P, 2)`` their mirror pixels.
        axis: ``(P,)`` int64 index of each pair's axis.
        normals: ``(A, 2)`` unit normals of the axes.
        offsets: ``(A,)`` offsets: the axis is ``normal . x + offset = 0`` (pixels).
        votes: ``(A,)`` the axes' Hough votes.
    """

    left: torch.Tensor
    right: torch.Tensor
    axis: torch.Tensor
    normals: torch.Tensor
    offsets: torch.Tensor
    votes: torch.Tensor

    def __len__(self) -> int:
        return int(self.left.shape[0])


def reflect_2d(points: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor) -> torch.Tensor:
    """Reflect ``(..., 2)`` points about the lines ``normal (..., 2) . x + offset (...) = 0``."""
    d = (points * normal).sum(-1, keepdim=True) + offset.unsqueeze(-1)
    return points - 2.0 * d * normal


def curve_samples(chains: list[np.ndarray], *, length: float, n_samples: int, stride: float) -> tuple[np.ndarray, np.ndarray]:
    """Edge pixels every ``stride`` px along each chain and the curve of ``length`` px
    centred on each: ``centres (N, 2)`` and ``curves (N, n_samples, 2)``."""
    centres, curves = [], []
    offs = np.linspace(-length / 2, length / 2, n_samples)
    for chain in chains:
        p = np.asarray(chain, dtype=np.float64)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        if s[-1] < length + 2:
            continue
        c = np.arange(length / 2 + 1, s[-1] - length / 2 - 1, stride)
        q = c[:, None] + offs[None]  # (n, S) arc-length positions
        curves.append(np.stack([np.interp(q, s, p[:, 0]), np.interp(q, s, p[:, 1])], -1))
        centres.append(np.stack([np.interp(c, s, p[:, 0]), np.interp(c, s, p[:, 1])], -1))
    if not centres:
        return np.zeros((0, 2)), np.zeros((0, n_samples, 2))
    return np.concatenate(centres), np.concatenate(curves)


def mirror_edge_matches(
    points: torch.Tensor,
    grads: torch.Tensor,
    p: torch.Tensor,
    q: torch.Tensor,
    normal: torch.Tensor,
    offset: torch.Tensor,
    radius: float = 2.5,
) -> tuple[torch.Tensor, torch.Tensor]:
    """The edge points ``points (N, 2)`` (unit gradients ``grads``) within the bounding box
    of the axis's pairs ``p, q``, reflected into it, whose reflection lands within
    ``radius`` px of an edge point with a mirrored gradient (cosine > 0.8):
    ``(matched (N,) bool, inside (N,) bool)``, ``inside`` the points considered."""
    from scipy.spatial import cKDTree

    both = torch.cat([p, q])
    lo, hi = both.min(0).values, both.max(0).values
    refl_all = points - 2.0 * (points @ normal + offset)[:, None] * normal
    inside = ((points >= lo) & (points <= hi)).all(1) & ((refl_all >= lo) & (refl_all <= hi)).all(1)
    out = torch.zeros(len(points), dtype=torch.bool)
    if int(inside.sum()) < 2:
        return out, inside
    pts, gr, refl = points[inside], grads[inside], refl_all[inside]
    dist, j = cKDTree(pts.numpy()).query(refl.numpy())
    j = torch.from_numpy(j)
    g_m = gr - 2.0 * (gr @ normal)[:, None] * normal
    consistent = (g_m * gr[j]).sum(1) > 0.8
    out[inside] = (torch.from_numpy(dist) < radius) & consistent
    return out, inside


def _support(matched: torch.Tensor, inside: torch.Tensor) -> float:
    """Share of the edge pixels considered (see :func:`mirror_edge_matches`) that have a mirror
    edge: high on a symmetric object, a few percent for edges that only chance pairs up."""
    return float(matched.sum()) / int(inside.sum()) if int(inside.sum()) >= 2 else 0.0


def intensity_stack(gray: torch.Tensor) -> torch.Tensor:
    """``(1, 3, H, W)`` float64 stack of ``gray (H, W)`` and its x and y derivatives (central
    differences), sampled by :func:`refine_axis_photometric`."""
    gy, gx = torch.gradient(gray.double())
    return torch.stack([gray.double(), gx, gy])[None]


def refine_axis_photometric(
    stack: torch.Tensor, points: torch.Tensor, grads: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor, n_iters: int = 8
) -> tuple[torch.Tensor, torch.Tensor]:
    """The axis refined so that the image across the edges at ``points (N, 2)`` (unit
    gradients ``grads``; profiles of 7 px along them) matches the image at their
    reflections: Gauss-Newton on the grey-level differences of the image in ``stack``
    (:func:`intensity_stack`), Cauchy-weighted. The refined axis is returned only if it
    lowers the Cauchy cost of the start, else the start."""
    h, w = stack.shape[-2:]

    def sample(xy: torch.Tensor) -> torch.Tensor:
        grid = torch.stack([xy[:, 0] / (w - 1) * 2 - 1, xy[:, 1] / (h - 1) * 2 - 1], -1)[None, None]
        return F.grid_sample(stack, grid, align_corners=True, padding_mode="border")[0, :, 0].T  # (M, 3)

    t = torch.arange(-3, 4, dtype=torch.float64)
    pts = (points[:, None] + t[None, :, None] * grads[:, None]).reshape(-1, 2)
    base = sample(pts)[:, 0]
    scale = float(base.std()) * 0.2 + 1e-6

    def residuals(theta: torch.Tensor, b: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        n = torch.stack([torch.cos(theta), torch.sin(theta)])
        d = pts @ n + b
        v = sample(pts - 2.0 * d[:, None] * n)
        return v[:, 0] - base, v[:, 1:], d

    def cost(r: torch.Tensor) -> float:
        return float(torch.log1p((r / scale) ** 2).sum())

    theta0 = torch.atan2(normal[1], normal[0])
    theta, b = theta0, offset.clone()
    r, gimg, d = residuals(theta, b)
    start_cost = cost(r)
    for _ in range(n_iters):
        n = torch.stack([torch.cos(theta), torch.sin(theta)])
        dn = torch.stack([-torch.sin(theta), torch.cos(theta)])
        j_theta = (gimg * (-2.0 * (pts @ dn)[:, None] * n - 2.0 * d[:, None] * dn)).sum(1)
        j_b = -2.0 * (gimg @ n)
        wts = 1.0 / (1.0 + (r / scale) ** 2)
        jac = torch.stack([j_theta, j_b], 1)
        lhs = jac.T @ (wts[:, None] * jac) + 1e-9 * torch.eye(2, dtype=jac.dtype)
        step = torch.linalg.solve(lhs, -(jac.T @ (wts * r)))
        theta, b = theta + step[0], b + step[1]
        r, gimg, d = residuals(theta, b)
    if not cost(r) < start_cost:
        return normal, offset
    return torch.stack([torch.cos(theta), torch.sin(theta)]), b


def _peaks(acc: torch.Tensor, settings: MirrorPairSettings) -> list[tuple[int, int]]:
    """Dominant peaks of the (angle, rho) accumulator, strongest first, suppressing
    the neighbourhood of each (5 degrees, 10 rho bins)."""
    smooth = F.avg_pool2d(acc[None, None], 3, stride=1, padding=1)[0, 0]
    work = smooth.clone()
    na = max(1, int(round(5.0 / settings.angle_bin)))
    out: list[tuple[int, int]] = []
    first = float(work.max())
    while len(out) < settings.max_axes and first > 0:
        v, idx = work.flatten().max(0)
        if float(v) <= 0 or float(v) < settings.min_vote_share * first:
            break
        a, r = divmod(int(idx), work.shape[1])
        out.append((a, r))
        rows = [(a + k) % work.shape[0] for k in range(-na, na + 1)]
        work[rows, max(0, r - 10) : r + 11] = 0
    return out


def mirror_pixel_pairs(
    image: torch.Tensor, settings: MirrorPairSettings, generator: torch.Generator
) -> MirrorPixelPairs:
    """Mirror pixel pairs of ``image (C, H, W)`` in [0, 1], grouped by axis (Sec. 4.2.1).

    Returns empty pairs (and no axes) when the image has too few edges or no axis
    gathers ``min_pairs`` consistent pairs.
    """
    s = settings
    _, h, w = image.shape
    chains, _ = boundary_curves(image[None].cpu(), edges="edge_drawing", sigma=s.edge_sigma, min_length=s.min_edge_length)
    centres, curves = curve_samples(chains, length=s.curve_length, n_samples=s.n_curve_samples, stride=s.stride)
    empty = MirrorPixelPairs(
        torch.zeros(0, 2, dtype=torch.float64), torch.zeros(0, 2, dtype=torch.float64), torch.zeros(0, dtype=torch.int64),
        torch.zeros(0, 2, dtype=torch.float64), torch.zeros(0, dtype=torch.float64), torch.zeros(0, dtype=torch.float64),
    )
    n = len(centres)
    if n < 2:
        return empty
    x = torch.from_numpy(centres).float()  # (N, 2)
    cv = torch.from_numpy(curves).float()  # (N, S, 2)
    gray_np = image.float().mean(0).cpu().numpy()  # (H, W)
    gy, gx = np.gradient(gray_np)
    stack = intensity_stack(torch.from_numpy(gray_np))  # for the photometric refinement of each axis
    grad = F.normalize(torch.from_numpy(np.stack([gx, gy], -1)).float(), dim=-1)  # (H, W, 2) unit gradients
    g = grad[x[:, 1].round().long().clamp(0, h - 1), x[:, 0].round().long().clamp(0, w - 1)]  # (N, 2)
    edges = torch.from_numpy(np.concatenate([np.asarray(c, dtype=np.float64) for c in chains]))  # (E, 2) every chain pixel
    edge_grads = grad[edges[:, 1].round().long().clamp(0, h - 1), edges[:, 0].round().long().clamp(0, w - 1)].double()
    hh = min(s.n_partners, n - 1)
    i = torch.arange(n).repeat_interleave(hh)  # (N h,)
    j = (i + 1 + torch.randint(0, n - 1, (n * hh,), generator=generator)) % n  # never i
    u = x[i] - x[j]
    length = u.norm(dim=1)
    nrm = u / length.clamp_min(1e-6)[:, None]  # axis normal
    gj = g[j] - 2.0 * (g[j] * nrm).sum(1, keepdim=True) * nrm  # Eq. 4.5: R Q R^T grad I(x_i')
    keep = (length > 2.0) & ((g[i] * gj).sum(1) > 1.0 - s.eps)
    i, j, nrm = i[keep], j[keep], nrm[keep]
    off = -(nrm * (0.5 * (x[i] + x[j]))).sum(1)
    mirrored = reflect_2d(cv[i], nrm[:, None, :], off[:, None])  # (P, S, 2)
    target = cv[j]
    o_fwd = ((target - mirrored) ** 2).sum(-1).mean(-1)
    o_rev = ((target.flip(1) - mirrored) ** 2).sum(-1).mean(-1)
    o = torch.minimum(o_fwd, o_rev) * s.curve_length  # Eq. 4.3 over the curve's p pixels; Eq. 4.4 equals it
    weight = torch.exp(-(2.0 * o) / (4.0 * s.sigma**2))
    theta = torch.atan2(nrm[:, 1], nrm[:, 0])
    flip = theta < 0  # normals with angle in [0, pi): the line is (cos phi, sin phi) . x = rho
    phi = torch.where(flip, theta + math.pi, theta)
    rho = torch.where(flip, off, -off)
    diag = math.hypot(h, w)
    n_a = int(round(180.0 / s.angle_bin))
    n_r = int(math.ceil(2 * diag / s.rho_bin)) + 1
    ai = (phi / math.pi * n_a).long().clamp(0, n_a - 1)
    ri = ((rho + diag) / s.rho_bin).long().clamp(0, n_r - 1)
    acc = torch.bincount(ai * n_r + ri, weights=weight.double(), minlength=n_a * n_r).reshape(n_a, n_r)
    left, right, axis, normals, offsets, votes = [], [], [], [], [], []
    for a, r in _peaks(acc, s):
        da = (ai - a).abs()
        near = (torch.minimum(da, n_a - da) <= 1) & ((ri - r).abs() <= 1)
        if int(near.sum()) < s.min_pairs:
            continue
        p, q = x[i[near]].double(), x[j[near]].double()
        ang = (a + 0.5) * math.pi / n_a
        peak = torch.tensor([math.cos(ang), math.sin(ang)], dtype=torch.float64)
        chord = F.normalize(p - q, dim=1)
        chord = torch.where((chord @ peak < 0)[:, None], -chord, chord)
        normal = F.normalize(chord.mean(0), dim=0)  # the axis refitted to its pairs
        offset = -(0.5 * (p + q) @ normal).median()
        m, _ = mirror_edge_matches(x.double(), g.double(), p, q, normal, offset)
        if int(m.sum()) >= 3:  # the axis refined on the edges that have a mirror edge
            normal, offset = refine_axis_photometric(stack, x.double()[m], g.double()[m], normal, offset)
        m, inside = mirror_edge_matches(edges, edge_grads, p, q, normal, offset, radius=1.5)
        if _support(m, inside) < s.min_support:
            continue
        side = p @ normal + offset
        lft = torch.where((side < 0)[:, None], p, q)
        rgt = torch.where((side < 0)[:, None], q, p)
        k = len(normals)
        left.append(lft)
        right.append(rgt)
        axis.append(torch.full((len(lft),), k, dtype=torch.int64))
        normals.append(normal)
        offsets.append(offset)
        votes.append(float(acc[a, r]))
    if not normals:
        return empty
    return MirrorPixelPairs(
        torch.cat(left), torch.cat(right), torch.cat(axis), torch.stack(normals), torch.stack(offsets),
        torch.tensor(votes, dtype=torch.float64),
    )
