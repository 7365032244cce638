"""SLIC's last step on SymmSLIC's labels: connectivity enforced as Achanta et al.'s code
does it, and the slivers that reflected superpixels leave absorbed (thesis Sec. 4.2.2)."""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["absorb_slivers", "enforce_connectivity"]


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
