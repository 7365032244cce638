"""SLIC's assignment step for all centres at once, cell by cell (thesis Sec. 4.2.2,
Algorithm 4, lines 5-29).

SLIC scores each centre against the pixels of its ``2S x 2S`` window,
``[floor(c) - S, floor(c) + S)`` on each axis. Cut the image into cells of ``S x S``
pixels: a pixel lies in a centre's window only if the centre's floored position lies in
the pixel's cell or one of its 8 neighbours. With one centre per cell, the candidates of
all ``S^2`` pixels of a cell are the centres of the same 9 cells, and their costs are one
small matrix product: the distance ``|l - c|^2 + (m / S)^2 |x - c_xy|^2`` is linear in the
pixel's features ``(l, x, y, 1)`` once the term ``|l|^2 + (m / S)^2 |x|^2``, the same for
all of a pixel's candidates, is dropped. The left member of a mirror pair scores the
pixel and its mirror pixel, ``(|l - c|^2 + |l' - c'|^2) / 2`` plus the spatial term, also
linear in ``(l, l', (|l'|^2 - |l|^2) / 2)``, and only on its side of the axis where the
mirror pixel lies in the image (else a cost of :data:`FORBIDDEN`). A second centre in a
cell is scored on its own window directly. The labels are SLIC's, up to float rounding
on ties.
"""

from __future__ import annotations

import dataclasses

import torch
import torch.nn.functional as F

__all__ = ["FORBIDDEN", "PixelFeatures", "assign_labels"]

#: cost of a pixel a centre may not take (outside its window, or across its pair's axis)
FORBIDDEN = 1e10


@dataclasses.dataclass(frozen=True)
class PixelFeatures:
    """Every pixel's features, once per image, in the cells' layout.

    Attributes:
        blocks: ``(Ny * Nx, F, S * S)`` float32 features of each cell's pixels (the image
            zero-padded to whole cells): Lab minus its mean (3); per axis the mirror
            pixel's Lab (3), ``(|l'|^2 - |l|^2) / 2`` and :data:`FORBIDDEN` where the pixel
            is on the axis's right side or its mirror leaves the image (5 per axis); ``x``
            and ``y`` within the cell; 1.
        flat: ``(H * W, F)`` the same features per pixel, row-major.
        mean: ``(3,)`` the Lab mean subtracted.
        step: the cell side ``S`` (px).
        shape: ``(H, W)``.
    """

    blocks: torch.Tensor
    flat: torch.Tensor
    mean: torch.Tensor
    step: int
    shape: tuple[int, int]

    @staticmethod
    def build(lab: torch.Tensor, shape: tuple[int, int], index: torch.Tensor, left: torch.Tensor, step: int) -> "PixelFeatures":
        """From ``lab (H * W, 3)`` and the mirror maps ``index``, ``left`` ``(A, H * W)``
        (:class:`~torchsym.image.symmslic.slic.MirrorMaps`)."""
        h, w = shape
        s = step
        ny, nx = -(-h // s), -(-w // s)
        mean = lab.float().mean(0)
        col = lab.float() - mean
        parts = [col]
        for a in range(index.shape[0]):
            mir = col[index[a].clamp(min=0)]
            half = 0.5 * ((mir * mir).sum(1) - (col * col).sum(1))
            forbid = torch.where(left[a] & (index[a] >= 0), 0.0, FORBIDDEN)
            parts += [mir, half[:, None], forbid[:, None]]
        ys, xs = torch.meshgrid(torch.arange(h), torch.arange(w), indexing="ij")
        parts += [(xs % s).reshape(-1, 1).float(), (ys % s).reshape(-1, 1).float(), torch.ones(h * w, 1)]
        flat = torch.cat(parts, 1)  # (H W, F)
        nf = flat.shape[1]
        padded = F.pad(flat.reshape(h, w, nf), (0, 0, 0, nx * s - w, 0, ny * s - h))
        blocks = padded.reshape(ny, s, nx, s, nf).permute(0, 2, 4, 1, 3).reshape(ny * nx, nf, s * s).contiguous()
        return PixelFeatures(blocks, flat, mean, s, (h, w))


def _weights(c, feats: PixelFeatures) -> tuple[torch.Tensor, torch.Tensor]:
    """Per centre (and a last row for "none"), the weights of the colour features
    ``(K + 1, F)`` (spatial columns zero) and the constant ``(K + 1,)``."""
    k = c.xy.shape[0]
    nf = feats.flat.shape[1]
    n_axes = (nf - 6) // 5
    col = c.lab.float() - feats.mean
    pcol = torch.where((c.partner >= 0)[:, None], col[c.partner.clamp(min=0)], 0.0)
    paired = c.left & (c.partner >= 0)
    wk = torch.zeros(k + 1, nf)
    wk[:k, :3] = torch.where(paired[:, None], -col, -2.0 * col)
    const = torch.full((k + 1,), FORBIDDEN)
    const[:k] = torch.where(paired, 0.5 * ((col * col).sum(1) + (pcol * pcol).sum(1)), (col * col).sum(1))
    for a in range(n_axes):
        sel = paired & (c.axis == a)
        o = 3 + 5 * a
        wk[:k, o : o + 3] = torch.where(sel[:, None], -pcol, 0.0)
        wk[:k, o + 3] = sel.float()
        wk[:k, o + 4] = sel.float()
    return wk, const


def _one_per_cell(c, feats: PixelFeatures) -> tuple[torch.Tensor, torch.Tensor]:
    """The active centres (unpaired and left members) by the cell of their floored
    position: ``(table (Ny + 2, Nx + 2), extra (E,))``, the table holding each cell's first
    centre (-1: none; a border of empty cells), ``extra`` the other centres."""
    h, w = feats.shape
    s = feats.step
    ny, nx = -(-h // s), -(-w // s)
    active = torch.nonzero((c.partner < 0) | c.left)[:, 0]
    cell = torch.div(c.xy[active].floor().long(), s, rounding_mode="floor")
    cy, cx = cell[:, 1].clamp(0, ny - 1), cell[:, 0].clamp(0, nx - 1)
    flat = cy * nx + cx
    first = torch.full((ny * nx,), torch.iinfo(torch.int64).max, dtype=torch.int64)
    first.scatter_reduce_(0, flat, active, reduce="amin")
    is_first = first[flat] == active
    table = torch.full((ny + 2, nx + 2), -1, dtype=torch.int64)
    table[cy[is_first] + 1, cx[is_first] + 1] = active[is_first]
    return table, active[~is_first]


def _cell_costs(c, feats: PixelFeatures, table: torch.Tensor, wk: torch.Tensor, const: torch.Tensor, ss: float):
    """Best cost and candidate of every pixel among its 9 cells' centres: ``(cost, label)``
    each ``(Ny * Nx, S * S)``."""
    s = feats.step
    ny, nx = table.shape[0] - 2, table.shape[1] - 2
    k = c.xy.shape[0]
    cand = torch.stack([table[1 + dy : 1 + dy + ny, 1 + dx : 1 + dx + nx] for dy in (-1, 0, 1) for dx in (-1, 0, 1)], 2)
    ci = torch.where(cand >= 0, cand, k)  # (Ny, Nx, 9), k: none
    gy, gx = torch.meshgrid(torch.arange(ny) * s, torch.arange(nx) * s, indexing="ij")
    origin = torch.stack([gx, gy], -1).float()[:, :, None]  # (Ny, Nx, 1, 2)
    xy_all = torch.cat([c.xy.float(), torch.zeros(1, 2)])
    rel = xy_all[ci] - origin  # centres relative to the cell, (Ny, Nx, 9, 2)
    wts = wk[ci]  # (Ny, Nx, 9, F)
    wts[..., -3] = -2.0 * ss * rel[..., 0]
    wts[..., -2] = -2.0 * ss * rel[..., 1]
    wts[..., -1] = const[ci] + ss * (rel * rel).sum(-1)
    cost = torch.bmm(wts.reshape(ny * nx, 9, -1), feats.blocks)  # (cells, 9, S S)
    low = torch.cat([c.xy.floor().float(), torch.zeros(1, 2)])[ci] - origin  # floored, relative
    u = torch.arange(s, dtype=torch.float32)
    dx, dy = u - low[..., 0:1], u - low[..., 1:2]  # (Ny, Nx, 9, S)
    out_x = torch.where((dx >= -s) & (dx < s), 0.0, FORBIDDEN).reshape(ny * nx, 9, 1, s)
    out_y = torch.where((dy >= -s) & (dy < s), 0.0, FORBIDDEN).reshape(ny * nx, 9, s, 1)
    cost.view(ny * nx, 9, s, s).add_(out_x).add_(out_y)  # SLIC's window
    best, slot = cost.min(1)
    return best, torch.gather(ci.reshape(ny * nx, 9), 1, slot)


def _window_costs(c, feats: PixelFeatures, extra: torch.Tensor, wk: torch.Tensor, const: torch.Tensor, ss: float):
    """Costs of the centres ``extra`` over their own windows: ``(pix (E, M), cost (E, M))``,
    ``pix`` flat pixel indices (-1 outside the image)."""
    h, w = feats.shape
    s = feats.step
    off = torch.arange(-s, s)
    low = c.xy[extra].floor().long()
    px = low[:, 0:1, None] + off[None, None, :]  # (E, 1, 2S)
    py = low[:, 1:2, None] + off[None, :, None]  # (E, 2S, 1)
    inside = ((px >= 0) & (px < w)) & ((py >= 0) & (py < h))  # (E, 2S, 2S)
    pix = (py.clamp(0, h - 1) * w + px.clamp(0, w - 1)).reshape(len(extra), -1)
    f = feats.flat[pix]  # (E, M, F)
    cost = torch.einsum("emf,ef->em", f[..., :-3], wk[extra, :-3]) + const[extra, None]
    dxy = torch.stack([(px - c.xy[extra, 0, None, None]).expand_as(inside), (py - c.xy[extra, 1, None, None]).expand_as(inside)], -1)
    sq = (dxy.reshape(len(extra), -1, 2).float() ** 2).sum(-1) - (f[..., -3:-1] ** 2).sum(-1)
    cost = cost + ss * sq
    return torch.where(inside.reshape(len(extra), -1), pix, -1), cost


def assign_labels(c, feats: PixelFeatures, compactness: float) -> torch.Tensor:
    """Each pixel's SLIC label among the unpaired and left centres of ``c``
    (:class:`~torchsym.image.symmslic.slic.Centres`) whose window holds it: ``(H, W)``
    int64, -1 where none may take it. The right members' pixels come afterwards
    (:func:`~torchsym.image.symmslic.slic.mirror_labels`)."""
    h, w = feats.shape
    s = feats.step
    ss = (compactness / s) ** 2
    wk, const = _weights(c, feats)
    table, extra = _one_per_cell(c, feats)
    best, label = _cell_costs(c, feats, table, wk, const, ss)
    ny, nx = table.shape[0] - 2, table.shape[1] - 2
    best = best.reshape(ny, nx, s, s).permute(0, 2, 1, 3).reshape(ny * s, nx * s)[:h, :w].reshape(-1)
    label = label.reshape(ny, nx, s, s).permute(0, 2, 1, 3).reshape(ny * s, nx * s)[:h, :w].reshape(-1)
    if len(extra):
        pix, cost = _window_costs(c, feats, extra, wk, const, ss)
        ok = pix >= 0
        p, v = pix[ok], cost[ok]
        e = extra[:, None].expand_as(pix)[ok]
        low = torch.full((h * w,), float("inf"))
        low.scatter_reduce_(0, p, v, reduce="amin")
        win = (v == low[p]) & (v < best[p])
        label[p[win]] = e[win]
        best = torch.minimum(best, low)
    return torch.where(best < 0.5 * FORBIDDEN, label, -1).reshape(h, w)
