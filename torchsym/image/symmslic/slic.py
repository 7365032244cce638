"""Symmetric SLIC: SLIC's k-means on (Lab colour, position) where mirror superpixels stay
mirror images (thesis Sec. 4.2.2, Algorithm 4).

All centres are scored against the pixels of their ``2S x 2S`` windows in one tensor
pass per iteration, cell by cell (:mod:`.assignment`). A centre is *unpaired* (SLIC's grid, outside the symmetric
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

import torch

from torchsym.image.symmslic.assignment import PixelFeatures, assign_labels

__all__ = ["Centres", "MirrorMaps", "mirror_labels", "slic_iterations"]


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
        pulls: per axis ``(dst (R,), src (R,))``: the pixels on the axis's positive side
            whose mirror pixel ``src`` lies in the image (what :func:`mirror_labels` reads).
    """

    index: torch.Tensor
    left: torch.Tensor
    pulls: tuple[tuple[torch.Tensor, torch.Tensor], ...] = ()

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
        pulls = []
        for idx, lft in zip(index, left):
            dst = torch.nonzero(~lft & (idx >= 0))[:, 0]
            pulls.append((dst, idx[dst]))
        return MirrorMaps(torch.stack(index), torch.stack(left), tuple(pulls))


def _reflect(xy: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor) -> torch.Tensor:
    d = (xy * normal).sum(-1, keepdim=True) + offset.unsqueeze(-1)
    return xy - 2.0 * d * normal


def mirror_labels(labels: torch.Tensor, c: Centres, maps: MirrorMaps) -> torch.Tensor:
    """Labels ``(H, W)`` with every pixel on the right of an axis whose mirror pixel
    belongs to a left member of that axis relabelled to that member's partner."""
    flat = labels.reshape(-1)
    out = flat.clone()
    for a, (dst, src) in enumerate(maps.pulls):
        mirrored = flat[src]
        m = mirrored.clamp(min=0)
        ok = (mirrored >= 0) & c.left[m] & (c.axis[m] == a)
        out[dst[ok]] = c.partner[mirrored[ok]]
    return out.reshape(labels.shape)


def _update(points: torch.Tensor, labels: torch.Tensor, c: Centres) -> None:
    """Centres to their pixels' mean of ``points (H * W, 5)`` float64 ``(x, y, L, a, b)``
    (left members and unpaired), right members to the reflection of their partner."""
    k = c.xy.shape[0]
    lbl = labels.reshape(-1)
    idx = torch.where(lbl >= 0, lbl, k)  # row k collects the unlabelled pixels
    count = torch.bincount(idx, minlength=k + 1)[:k].to(points.dtype)
    has = count > 0
    mean = torch.zeros(k + 1, 5, dtype=points.dtype).index_add_(0, idx, points)[:k] / count.clamp_min(1)[:, None]
    c.xy = torch.where(has[:, None], mean[:, :2], c.xy)
    c.lab = torch.where(has[:, None], mean[:, 2:].to(c.lab.dtype), c.lab)
    right = (c.partner >= 0) & ~c.left
    if bool(right.any()):
        src = c.partner[right]
        c.xy[right] = _reflect(c.xy[src], c.normals[c.axis[src]], c.offsets[c.axis[src]])


def slic_iterations(
    lab: torch.Tensor, c: Centres, maps: MirrorMaps, step: int, compactness: float, max_iters: int, tol_shift: float = 0.0
) -> tuple[torch.Tensor, int]:
    """Rounds of symmetric assignment and update on ``lab (3, H, W)``, at most
    ``max_iters``, fewer once the centres moved less than ``tol_shift`` px on average
    (SLIC's residual error over the centres, L1). Returns the labels ``(H, W)`` of the last
    assignment (-1 where no window reached) and the rounds run."""
    shape = (lab.shape[1], lab.shape[2])
    flat = lab.reshape(3, -1).T.contiguous().float()  # (H W, 3)
    feats = PixelFeatures.build(flat, shape, maps.index, maps.left, step)
    ys, xs = torch.meshgrid(torch.arange(shape[0], dtype=torch.float64), torch.arange(shape[1], dtype=torch.float64), indexing="ij")
    points = torch.cat([xs.reshape(-1, 1), ys.reshape(-1, 1), flat.double()], 1)  # (H W, 5)
    labels = mirror_labels(assign_labels(c, feats, compactness), c, maps)
    rounds = 1
    while rounds < max_iters:
        before = c.xy.clone()
        _update(points, labels, c)
        labels = mirror_labels(assign_labels(c, feats, compactness), c, maps)
        rounds += 1
        if float((c.xy - before).abs().sum(1).mean()) < tol_shift:
            break
    return labels, rounds
