"""SymmSLIC: superpixels that keep an image's reflection symmetry (thesis Sec. 4.2).

Steps, as Algorithm 4:

1. mirror pixel pairs and their axes (Sec. 4.2.1, :mod:`.pairs`);
2. symmetric initialisation: SLIC's grid outside the symmetric region (the convex hull of
   the pairs), mirror pairs of centres inside it;
3. symmetric assignment and centre updates until the centres settle ("till
   convergence": a mean move under ``tol_shift``) or ``max_iters`` (:mod:`.slic`);
4. connectivity enforced as SLIC does (each large enough piece its own superpixel, the
   rest merged), on the left members, whose pieces then get their mirror partners.

Departure from the text: the pairs of centres sit on SLIC's grid over the left half of
the region and its reflection (the thesis's rule for filling the region when too few
pairs are detected), moved to the lowest gradient of the pair nearby, rather than at the
detected edge pixels (which the thesis moves off the edges too). The grid keeps the count
near ``k`` and the superpixels even; the thesis's count rule, ``k - s`` *pairs*, would
give up to ``2k - s`` superpixels.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import kornia
import numpy as np
import torch

from torchsym.core.checks import as_tensor, check_image
from torchsym.core.random import make_generator
from torchsym.image.axes.accepted import stage_axes_found
from torchsym.core.registry import register_solver
from torchsym.core.settings import Solver, resolve_settings
from torchsym.errors import InputShapeError, InputValueError
from torchsym.image.symmslic.connectivity import absorb_slivers, enforce_connectivity
from torchsym.image.symmslic.pairs import MirrorPixelPairs, mirror_pixel_pairs, reflect_2d
from torchsym.image.symmslic.region import symmetric_region
from torchsym.image.symmslic.result import SymmSlicResult
from torchsym.image.symmslic.settings import SymmSlicSettings
from torchsym.image.symmslic.slic import Centres, MirrorMaps, mirror_labels, slic_iterations

__all__ = ["LAB_SCALE", "SymmSlic", "symm_slic"]

#: CIELAB (L in [0, 100]) to OpenCV's 8-bit Lab scale (L in [0, 255]; a, b unchanged), so
#: that ``compactness`` means what OpenCV's ``ruler`` does
LAB_SCALE = torch.tensor([255.0 / 100.0, 1.0, 1.0])


def slic_grid(h: int, w: int, step: int) -> torch.Tensor:
    """SLIC's seed grid ``(G, 2)`` float64 ``(x, y)``: ``round(W / S)`` columns and
    ``round(H / S)`` rows from ``S // 2``, the remainder spread over the strips (as
    Achanta et al.'s code)."""

    def axis(n: int) -> np.ndarray:
        strips = max(1, int(0.5 + n / step))
        per = int((n - step * strips) / strips)  # truncated towards 0
        pos = np.arange(strips) * (step + per) + step // 2
        return pos[pos <= n - 1]

    ys, xs = np.meshgrid(axis(h), axis(w), indexing="ij")
    return torch.from_numpy(np.stack([xs.reshape(-1), ys.reshape(-1)], 1).astype(np.float64))


def _lowest(grad: torch.Tensor, cand: torch.Tensor, mir: torch.Tensor | None = None) -> torch.Tensor:
    """Index into the 9 candidates ``cand (N, 9, 2)`` of the lowest gradient (summed
    with that at the mirror points ``mir`` when given)."""
    h, w = grad.shape

    def at(p: torch.Tensor) -> torch.Tensor:
        xi, yi = p[..., 0].round().long().clamp(0, w - 1), p[..., 1].round().long().clamp(0, h - 1)
        return grad[yi, xi]

    return (at(cand) + (at(mir) if mir is not None else 0.0)).argmin(1)


def _init_centres(
    lab: torch.Tensor, grad: torch.Tensor, region: np.ndarray, normals: torch.Tensor, offsets: torch.Tensor, step: int
) -> Centres:
    """SLIC's grid, each seed moved within 3 x 3 to the lowest gradient; grid points in an
    axis's region on its left side become pairs with their reflections (moved to the
    lowest gradient of the pair)."""
    _, h, w = lab.shape
    g = slic_grid(h, w, step)
    a = torch.from_numpy(np.asarray(region[g[:, 1].long().numpy(), g[:, 0].long().numpy()]).reshape(-1))
    side = torch.zeros(len(g), dtype=g.dtype)
    if len(normals):
        side = torch.where(a >= 0, (g * normals[a.clamp(min=0)]).sum(1) + offsets[a.clamp(min=0)], side)
    d = torch.tensor([(dx, dy) for dy in (-1, 0, 1) for dx in (-1, 0, 1)], dtype=g.dtype)
    plain = g[a < 0]
    plain = (plain[:, None] + d[None])[torch.arange(len(plain)), _lowest(grad, plain[:, None] + d[None])]
    plain[:, 0].clamp_(0, w - 1)
    plain[:, 1].clamp_(0, h - 1)
    lefts, axes = g[(a >= 0) & (side <= 0)], a[(a >= 0) & (side <= 0)]
    if len(lefts):
        cand = lefts[:, None] + d[None]  # (L, 9, 2)
        mir = reflect_2d(cand, normals[axes][:, None], offsets[axes][:, None])
        lefts = cand[torch.arange(len(lefts)), _lowest(grad, cand, mir)]
        rights = reflect_2d(lefts, normals[axes], offsets[axes])
        inside = (rights[:, 0] >= 0) & (rights[:, 0] <= w - 1) & (rights[:, 1] >= 0) & (rights[:, 1] <= h - 1)
        plain = torch.cat([plain, lefts[~inside]])
        lefts, rights, axes = lefts[inside], rights[inside], axes[inside]
    else:
        rights = lefts
    k0, kp = len(plain), len(lefts)
    xy = torch.cat([plain, lefts, rights])
    partner = torch.cat([torch.full((k0,), -1), torch.arange(k0 + kp, k0 + 2 * kp), torch.arange(k0, k0 + kp)])
    left = torch.cat([torch.zeros(k0, dtype=torch.bool), torch.ones(kp, dtype=torch.bool), torch.zeros(kp, dtype=torch.bool)])
    axis = torch.cat([torch.full((k0,), -1), axes, axes]).long()
    xi, yi = xy[:, 0].round().long().clamp(0, w - 1), xy[:, 1].round().long().clamp(0, h - 1)
    return Centres(xy, lab[:, yi, xi].T.double(), partner.long(), left, axis, normals, offsets)


def _pair_pieces(pieces: torch.Tensor, origin: torch.Tensor, c: Centres, maps: MirrorMaps) -> tuple[torch.Tensor, Centres]:
    """Superpixels after connectivity: each piece of a left member gets a right partner
    (a new label) whose pixels are the piece's mirror pixels."""
    n = int(pieces.max()) + 1
    is_left = c.left[origin]
    right_ids = torch.full((n,), -1, dtype=torch.int64)
    right_ids[is_left] = n + torch.arange(int(is_left.sum()))
    k = n + int(is_left.sum())
    partner = torch.full((k,), -1, dtype=torch.int64)
    partner[:n] = right_ids
    partner[right_ids[is_left]] = torch.nonzero(is_left)[:, 0]
    left = torch.zeros(k, dtype=torch.bool)
    left[:n] = is_left
    axis = torch.full((k,), -1, dtype=torch.int64)
    axis[:n] = c.axis[origin]
    axis[right_ids[is_left]] = c.axis[origin][is_left]
    pieces_c = Centres(torch.zeros(k, 2, dtype=c.xy.dtype), torch.zeros(k, 3, dtype=c.lab.dtype), partner, left, axis, c.normals, c.offsets)
    return mirror_labels(pieces, pieces_c, maps), pieces_c


def symm_slic(
    image: torch.Tensor,
    settings: SymmSlicSettings | Mapping[str, Any] | None = None,
    *,
    known_axes: torch.Tensor | None = None,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> SymmSlicResult:
    """Symmetry-aware SLIC superpixels of ``image`` (thesis Sec. 4.2, Algorithm 4).

    Args:
        image: ``(C, H, W)`` or ``(1, C, H, W)`` in [0, 1] (uint8 scaled), H, W >= 32.
        settings: :class:`SymmSlicSettings` (or a mapping); defaults: ``k = 500``,
            compactness 10, the thesis's ``p = 64``, ``sigma = 24``, ``eps = 0.2``.
        known_axes: optional ``(A, 3)`` known axes ``(n_x, n_y, offset)`` with ``n . (x, y) +
            offset = 0``; the pair search is then skipped and each axis's region is the
            set of pixels whose mirror lies in the image. None: the axis stage's accepted
            axes (``axes_from="stage"``, the default) or the pair search's (``"pairs"``).
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.
        **overrides: settings by name.

    Returns:
        :class:`SymmSlicResult`; plain SLIC and a note when no axis is found.
    """
    t_all = time.perf_counter()
    img = check_image(image, "image", min_size=32)
    if img.shape[0] != 1:
        raise InputShapeError(f"image: expected one image, (C, H, W) or (1, C, H, W), got {tuple(img.shape)}")
    img = img[0].detach().float().cpu().clamp(0, 1)
    settings = resolve_settings(SymmSlicSettings, settings, overrides)
    gen = make_generator(generator)
    _, h, w = img.shape
    if settings.n_superpixels > h * w // 4:
        raise InputValueError(f"n_superpixels: expected at most {h * w // 4} for a {h} x {w} image, got {settings.n_superpixels}")
    notes: list[str] = []
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    rgb = img.expand(3, -1, -1) if img.shape[0] == 1 else img
    axis_accepted = True  # the axes given, or accepted by the stage
    if known_axes is None and settings.axes_from == "stage":
        lines, _, axis_accepted = stage_axes_found(rgb[None], settings.axes, generator=gen)
        known_axes = lines.double().cpu()
        if known_axes.shape[0] == 0:
            notes.append("no axis found by the axis stage: plain SLIC superpixels")
        elif not axis_accepted:
            notes.append("the axis stage accepted no axis: the superpixels pair about its best-ranked axis, and the "
                         "score is 0 (no symmetry found)")
    if known_axes is not None and len(known_axes) == 0:
        none = torch.zeros(0, 2, dtype=torch.float64)
        found = MirrorPixelPairs(none, none, torch.zeros(0, dtype=torch.int64), none, torch.zeros(0, dtype=torch.float64),
                                 torch.zeros(0, dtype=torch.float64))
        normals, offsets = found.normals, found.offsets
    elif known_axes is not None:
        ax = as_tensor(known_axes, "known_axes", dtype=torch.float64)
        if ax.dim() != 2 or ax.shape[1] != 3 or not bool(torch.isfinite(ax).all()) or bool((ax[:, :2].norm(dim=1) == 0).any()):
            raise InputShapeError(f"known_axes: expected (A, 3) finite rows (n_x, n_y, offset) with a nonzero normal, got {tuple(ax.shape)}")
        scale = ax[:, :2].norm(dim=1, keepdim=True)
        normals, offsets = ax[:, :2] / scale, ax[:, 2] / scale[:, 0]
        none = torch.zeros(0, 2, dtype=torch.float64)
        found = MirrorPixelPairs(none, none, torch.zeros(0, dtype=torch.int64), normals, offsets, torch.zeros(len(ax), dtype=torch.float64))
    else:
        found = mirror_pixel_pairs(rgb, settings.pairs, gen)
        normals, offsets = found.normals, found.offsets
        if len(normals) == 0:
            notes.append("no symmetry axis found among the boundaries: plain SLIC superpixels")
    timings["pairs"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    lab = kornia.color.rgb_to_lab(rgb[None])[0] * LAB_SCALE[:, None, None]  # (3, H, W), OpenCV's 8-bit Lab scale
    gy, gx = np.gradient(lab.numpy(), axis=(1, 2))
    grad = torch.from_numpy(np.sqrt((gx**2 + gy**2).sum(0)))  # (H, W) Lab gradient magnitude
    region = symmetric_region(found, normals, offsets, h, w, lab.numpy(), settings.min_mirror_correlation)
    step = max(1, int(round(math.sqrt(h * w / settings.n_superpixels))))
    c = _init_centres(lab, grad, region, normals, offsets, step)
    timings["init"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    maps = MirrorMaps.build(normals, offsets, h, w)
    labels, _ = slic_iterations(lab, c, maps, step, settings.compactness, settings.max_iters, settings.tol_shift)
    timings["slic"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    active = ((c.partner < 0) | c.left).numpy()
    min_size = max(1, int(settings.min_size_share * h * w / max(1, len(c.xy))))
    pieces, origin = enforce_connectivity(labels.numpy(), min_size, active)
    lbl, c = _pair_pieces(torch.from_numpy(pieces), torch.from_numpy(origin), c, maps)
    lbl = torch.from_numpy(absorb_slivers(lbl.numpy()))
    used, compact = torch.unique(lbl, return_inverse=True)
    timings["connectivity"] = time.perf_counter() - t0
    remap = torch.full((len(c.partner),), -1, dtype=torch.int64)
    remap[used] = torch.arange(len(used))
    left_ids = torch.nonzero(c.left)[:, 0]
    pl, pr = remap[left_ids], remap[c.partner[left_ids]]
    ok = (pl >= 0) & (pr >= 0)
    pair_tab = torch.stack([pl[ok], pr[ok]], 1)
    pair_axis = c.axis[left_ids][ok]
    in_pair = torch.zeros(len(used), dtype=torch.bool)
    in_pair[pair_tab.reshape(-1)] = True
    mask = in_pair[compact]
    timings["total"] = time.perf_counter() - t_all
    return SymmSlicResult(
        labels=compact,
        n_superpixels=len(used),
        pairs=pair_tab,
        pair_axis=pair_axis,
        normals=normals,
        offsets=offsets,
        mirror_left=found.left,
        mirror_right=found.right,
        mask=mask,
        score=float(mask.double().mean()) if axis_accepted else 0.0,
        notes=notes,
        timings=timings,
    )


@register_solver("symmslic", kind="image")
class SymmSlic(Solver):
    """SymmSLIC superpixels and the symmetric object's mask (thesis Sec. 4.2-4.3); see
    :func:`symm_slic`."""

    settings_class = SymmSlicSettings

    def forward(self, image: torch.Tensor, generator: torch.Generator | None = None) -> SymmSlicResult:
        gen = generator if generator is not None else make_generator(self.settings.seed)
        return symm_slic(image, self.settings, generator=gen)
