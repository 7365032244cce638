"""Symmetric SLIC: SLIC's k-means on (Lab colour, position) where mirror superpixels stay
mirror images (thesis Sec. 4.2.2, Algorithm 4).

All centres' ``2S x 2S`` windows are scored in one tensor pass per iteration (the usual
GPU formulation of SLIC). A centre is *unpaired* (SLIC's grid, outside the symmetric
region), the *left* member of a mirror pair, or its *right* member, the left one's
reflection about the pair's axis. A left member competes only for pixels on its side of
the axis whose mirror lies in the image, with the cost of the thesis's objective for the pixel and its mirror image
(``|c - x|^2 + lambda |I(c) - I(x)|^2 + |c' - x'|^2 + lambda |I(c') - I(x')|^2``, halved);
the right member's pixels are then exactly the mirror images of the left member's
(each pixel of the right side takes the label of its mirror pixel, the symmetric
assignment of Algorithm 4 read in the pull direction, so the reflected superpixel has
no holes). The update moves the left centre to its pixels' mean and the right centre to
its reflection, which is the mean of the right pixels (Claim 4.2.1).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["Centres", "MirrorMaps", "absorb_slivers", "enforce_connectivity", "mirror_labels", "slic_iterations"]


@dataclasses.dataclass
class Centres:
    """Cluster centres (mutable state of the k-means; the solver owns it).

    Attributes:
        xy: ``(K, 2)`` positions ``(x, y)``.
        lab: ``(K, 3)`` mean Lab colours.
        partner: ``(K,)`` index of the mirror centre, -1 for unpaired.
        left: ``(K,)`` bool, the left member of a pair.
        axis: ``(K,)`` the pair's axis index into ``normals`` / ``offsets`` (-1: none).
        normals: ``(A, 2)`` axes' unit normals; ``offsets (A,)``: ``n . x + b = 0``.
    """

    xy: torch.Tensor
    lab: torch.Tensor
    partner: torch.Tensor
    left: torch.Tensor
    axis: torch.Tensor
    normals: torch.Tensor
    offsets: torch.Tensor


@dataclasses.dataclass(frozen=True)
class MirrorMaps:
    """Per axis, each pixel's mirror pixel and its side.

    Attributes:
        index: ``(A, H * W)`` int64 flat index of the nearest pixel to each pixel's
            reflection, -1 where it falls outside the image.
        left: ``(A, H * W)`` bool, the pixel lies on the axis or its negative side.
    """

    index: torch.Tensor
    left: torch.Tensor

    @staticmethod
    def build(normals: torch.Tensor, offsets: torch.Tensor, h: int, w: int) -> "MirrorMaps":
        ys, xs = torch.meshgrid(torch.arange(h, dtype=torch.float64), torch.arange(w, dtype=torch.float64), indexing="ij")
        grid = torch.stack([xs, ys], -1).reshape(-1, 2)  # (H W, 2)
        index, left = [], []
        for a in range(normals.shape[0]):
            side = grid @ normals[a] + offsets[a]
            m = _reflect(grid, normals[a], offsets[a]).round().long()
            inside = (m[:, 0] >= 0) & (m[:, 0] < w) & (m[:, 1] >= 0) & (m[:, 1] < h)
            index.append(torch.where(inside, m[:, 1] * w + m[:, 0], torch.full_like(m[:, 0], -1)))
            left.append(side <= 0)
        if not index:
            return MirrorMaps(torch.zeros(0, h * w, dtype=torch.int64), torch.zeros(0, h * w, dtype=torch.bool))
        return MirrorMaps(torch.stack(index), torch.stack(left))


def _reflect(xy: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor) -> torch.Tensor:
    d = (xy * normal).sum(-1, keepdim=True) + offset.unsqueeze(-1)
    return xy - 2.0 * d * normal


def mirror_labels(labels: torch.Tensor, c: Centres, maps: MirrorMaps) -> torch.Tensor:
    """Labels ``(H, W)`` with every pixel on the right of an axis whose mirror pixel
    belongs to a left member of that axis relabelled to that member's partner."""
    flat = labels.reshape(-1)
    out = flat.clone()
    for a in range(maps.index.shape[0]):
        src = maps.index[a]
        mirrored = torch.where(src >= 0, flat[src.clamp(min=0)], torch.full_like(src, -1))
        m = mirrored.clamp(min=0)
        ok = ~maps.left[a] & (mirrored >= 0) & c.left[m] & (c.axis[m] == a)
        out[ok] = c.partner[mirrored[ok]]
    return out.reshape(labels.shape)


def _assign(lab: torch.Tensor, shape: tuple[int, int], c: Centres, maps: MirrorMaps, step: int, compactness: float) -> torch.Tensor:
    """One assignment pass over the windows of the unpaired and left centres on the
    flat ``lab (H * W, 3)``; returns the labels ``(H, W)`` after the mirror pass."""
    h, w = shape
    active = torch.nonzero((c.partner < 0) | c.left)[:, 0]  # (Ka,)
    off = torch.arange(-step, step)  # SLIC's 2S x 2S window from the centre's pixel
    oy, ox = torch.meshgrid(off, off, indexing="ij")
    ox, oy = ox.reshape(1, -1), oy.reshape(1, -1)
    cxy = c.xy[active]
    cx, cy = cxy[:, 0].floor().long(), cxy[:, 1].floor().long()
    px, py = cx[:, None] + ox, cy[:, None] + oy  # (Ka, M)
    valid = (px >= 0) & (px < w) & (py >= 0) & (py < h)
    pix = py.clamp(0, h - 1) * w + px.clamp(0, w - 1)  # (Ka, M)
    fx, fy = (cxy[:, 0] - cx).float()[:, None], (cxy[:, 1] - cy).float()[:, None]
    spatial = ((ox - fx) ** 2 + (oy - fy) ** 2) * (compactness / step) ** 2  # (Ka, M)
    dist = ((lab[pix] - c.lab[active].float()[:, None]) ** 2).sum(-1) + spatial  # (Ka, M)
    paired = c.left[active]
    if bool(paired.any()):
        k = active[paired]
        a = c.axis[k]
        ppix = pix[paired]
        mir = maps.index[a[:, None], ppix]  # (Kp, M)
        on_left = maps.left[a[:, None], ppix]
        mcost = ((lab[mir.clamp(min=0)] - c.lab[c.partner[k]].float()[:, None]) ** 2).sum(-1) + spatial[paired]
        pair_cost = 0.5 * (dist[paired] + mcost)
        dist[paired] = torch.where(on_left & (mir >= 0), pair_cost, torch.full_like(pair_cost, float("inf")))
    dist = torch.where(valid, dist, torch.full_like(dist, float("inf")))
    best = torch.full((h * w,), float("inf"), dtype=dist.dtype)
    best.scatter_reduce_(0, pix.reshape(-1), dist.reshape(-1), reduce="amin")
    is_best = (dist.reshape(-1) == best[pix.reshape(-1)]) & torch.isfinite(dist.reshape(-1))
    labels = torch.full((h * w,), torch.iinfo(torch.int64).max, dtype=torch.int64)
    cand = active[:, None].expand_as(pix).reshape(-1)
    labels.scatter_reduce_(0, pix.reshape(-1)[is_best], cand[is_best], reduce="amin")
    labels[labels == torch.iinfo(torch.int64).max] = -1
    return mirror_labels(labels.reshape(h, w), c, maps)


def _update(lab: torch.Tensor, labels: torch.Tensor, c: Centres) -> None:
    """Centres to their pixels' mean (left members), right members to the reflection."""
    k = c.xy.shape[0]
    h, w = labels.shape
    ys, xs = torch.meshgrid(torch.arange(h, dtype=c.xy.dtype), torch.arange(w, dtype=c.xy.dtype), indexing="ij")
    lbl = labels.reshape(-1)
    ok = lbl >= 0
    idx = lbl[ok]
    count = torch.bincount(idx, minlength=k).to(c.xy.dtype)
    has = count > 0
    sx = torch.bincount(idx, weights=xs.reshape(-1)[ok], minlength=k)
    sy = torch.bincount(idx, weights=ys.reshape(-1)[ok], minlength=k)
    new_xy = torch.stack([sx, sy], 1) / count.clamp_min(1)[:, None]
    flat = lab[ok].double()
    new_lab = torch.stack([torch.bincount(idx, weights=flat[:, d], minlength=k) for d in range(3)], 1)
    new_lab = new_lab / count.clamp_min(1)[:, None]
    c.xy = torch.where(has[:, None], new_xy, c.xy)
    c.lab = torch.where(has[:, None], new_lab.to(c.lab.dtype), c.lab)
    right = (c.partner >= 0) & ~c.left
    if bool(right.any()):
        src = c.partner[right]
        c.xy[right] = _reflect(c.xy[src], c.normals[c.axis[src]], c.offsets[c.axis[src]])


def slic_iterations(lab: torch.Tensor, c: Centres, maps: MirrorMaps, step: int, compactness: float, max_iters: int) -> torch.Tensor:
    """``max_iters`` rounds of symmetric assignment and update on ``lab (3, H, W)``;
    returns the labels ``(H, W)`` of the last assignment (-1 where no window reached)."""
    shape = (lab.shape[1], lab.shape[2])
    flat = lab.reshape(3, -1).T.contiguous().float()  # (H W, 3)
    labels = _assign(flat, shape, c, maps, step, compactness)
    for _ in range(max_iters - 1):
        _update(flat, labels, c)
        labels = _assign(flat, shape, c, maps, step, compactness)
    return labels


def _components(labels: np.ndarray) -> np.ndarray:
    """4-connected components of equal labels: ``(H, W)`` component ids (-1 stays -1)."""
    h, w = labels.shape
    n = h * w
    flat = labels.reshape(-1)
    idx = np.arange(n).reshape(h, w)
    rows, cols = [], []
    for a, b in ((idx[:, :-1], idx[:, 1:]), (idx[:-1, :], idx[1:, :])):
        a, b = a.reshape(-1), b.reshape(-1)
        m = (flat[a] == flat[b]) & (flat[a] >= 0)
        rows.append(a[m])
        cols.append(b[m])
    graph = coo_matrix((np.ones(sum(len(r) for r in rows), dtype=np.int8), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    _, comp = connected_components(graph, directed=False)
    return np.where(flat >= 0, comp, -1).reshape(h, w)


def _raster_neighbour(comp: np.ndarray, first: np.ndarray, heads: np.ndarray) -> np.ndarray:
    """For the components ``heads``, the flat index of the pixel SLIC's scan merges each
    into: of the 4-neighbours of the component's first pixel in raster order that belong to
    a component met earlier in the scan, the last in the order left, up, right, down (-1:
    none)."""
    h, w = comp.shape
    flat = comp.reshape(-1)
    p = first[heads]
    py, px = p // w, p % w
    out = np.full(len(heads), -1, dtype=np.int64)
    for dx, dy in ((-1, 0), (0, -1), (1, 0), (0, 1)):
        qx, qy = px + dx, py + dy
        inside = (qx >= 0) & (qx < w) & (qy >= 0) & (qy < h)
        q = np.where(inside, qy * w + qx, 0)
        cq = flat[q]
        earlier = inside & (np.where(cq >= 0, first[np.clip(cq, 0, None)], -1) < p)
        out = np.where(earlier, q, out)
    return out


def enforce_connectivity(labels: np.ndarray, min_size: int, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """SLIC's last step (Achanta et al.'s ``EnforceLabelConnectivity``): every 4-connected
    piece of at least ``min_size`` pixels of an *active* label (``active``: ``(K,)`` bool)
    becomes a superpixel of its own; a smaller piece joins, whole, the piece met just
    before it in a raster scan (the neighbour of its first pixel, as SLIC's code does).
    Pixels of inactive labels (the right members of pairs, derived afterwards from their
    partners), unlabelled pixels (-1) and small pieces whose neighbour is such a pixel
    take the label of the nearest kept pixel.

    Returns:
        ``(labels (H, W), origin (K',))``: new labels ``0 .. K'-1`` and the old label
        each came from.
    """
    h, w = labels.shape
    lbl = np.where((labels >= 0) & active[np.clip(labels, 0, None)], labels, -1)
    comp = _components(lbl)
    flat = comp.reshape(-1)
    valid = flat >= 0
    n = int(flat.max()) + 1 if valid.any() else 0
    sizes = np.bincount(flat[valid], minlength=n)
    first = np.full(n, h * w, dtype=np.int64)
    np.minimum.at(first, flat[valid], np.nonzero(valid)[0])
    big = sizes >= min_size
    if not big.any():
        return np.zeros((h, w), dtype=np.int64), np.zeros(1, dtype=np.int64) + max(int(labels.max()), 0)
    root = np.arange(n)
    heads = np.nonzero(~big)[0]
    q = _raster_neighbour(comp, first, heads)
    root[heads] = np.where(q >= 0, flat[np.clip(q, 0, None)], -1)
    while True:  # a small piece's neighbour was met earlier, so the chains end
        nxt = np.where(root >= 0, root[np.clip(root, 0, None)], -1)
        if np.array_equal(nxt, root):
            break
        root = nxt
    ids, new = np.unique(np.nonzero(big)[0], return_inverse=True)
    comp_new = np.full(n, -1, dtype=np.int64)
    comp_new[ids] = new
    out = np.where(valid, comp_new[np.where(root >= 0, root, 0)[np.clip(flat, 0, None)]], -1)
    out = np.where(valid & (root[np.clip(flat, 0, None)] >= 0), out, -1).reshape(h, w)
    origin = np.zeros(len(ids), dtype=np.int64)
    origin[new] = lbl.reshape(-1)[first[ids]]
    kept = out >= 0
    if not kept.all():
        _, (iy, ix) = ndimage.distance_transform_edt(~kept, return_indices=True)
        out = out[iy, ix]
    return out, origin


def absorb_slivers(labels: np.ndarray) -> np.ndarray:
    """Labels where every label keeps only its largest 4-connected piece; the other
    pieces (slivers cut off by the rounding of reflected pixels) take the label of the
    nearest kept pixel."""
    comp = _components(labels)
    sizes = np.bincount(comp.reshape(-1))
    flat_l, flat_c = labels.reshape(-1), comp.reshape(-1)
    order = np.lexsort((-sizes[flat_c], flat_l))
    first = np.ones(len(order), dtype=bool)
    first[1:] = flat_l[order][1:] != flat_l[order][:-1]
    largest = np.zeros(len(sizes), dtype=bool)
    largest[flat_c[order][first]] = True
    kept = largest[comp]
    if kept.all():
        return labels
    _, (iy, ix) = ndimage.distance_transform_edt(~kept, return_indices=True)
    return labels[iy, ix]
