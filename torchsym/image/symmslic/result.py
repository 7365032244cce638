"""The result of SymmSLIC."""

from __future__ import annotations

import dataclasses

import torch

from torchsym.core.results import Result

__all__ = ["SymmSlicResult"]


@dataclasses.dataclass(frozen=True)
class SymmSlicResult(Result):
    """Superpixels that keep an image's reflection symmetry (thesis Sec. 4.2).

    Attributes:
        labels: ``(H, W)`` int64 superpixel of every pixel, ``0 .. n_superpixels - 1``.
        n_superpixels: superpixels produced (SLIC's count differs from the one asked).
        pairs: ``(P, 2)`` int64 mirror superpixel pairs ``(left, right)``: the right one is
            the left one's reflection about the pair's axis.
        pair_axis: ``(P,)`` int64 axis of each pair (index into ``normals``).
        normals: ``(A, 2)`` unit normals of the symmetry axes (pixel coordinates ``(x, y)``).
        offsets: ``(A,)`` offsets: axis ``a`` is ``normals[a] . (x, y) + offsets[a] = 0``.
        mirror_left: ``(Q, 2)`` mirror pixel pairs found on boundaries (the set L).
        mirror_right: ``(Q, 2)`` their mirror pixels (the set R).
        mask: ``(H, W)`` bool, the symmetric object: the union of the mirror superpixel
            pairs (unsupervised segmentation, Sec. 4.3.1).
        score: share of the image covered by mirror superpixel pairs, in [0, 1]; 0 when the
            pairs are about the axis stage's best-ranked axis that it did not accept (no
            symmetry found).
        notes: what the caller should know (no edges, no axis: plain SLIC).
        timings: seconds per stage (``pairs``, ``init``, ``slic``, ``connectivity``, ``total``).
    """

    labels: torch.Tensor
    n_superpixels: int
    pairs: torch.Tensor
    pair_axis: torch.Tensor
    normals: torch.Tensor
    offsets: torch.Tensor
    mirror_left: torch.Tensor
    mirror_right: torch.Tensor
    mask: torch.Tensor
    score: float
    notes: list[str]
    timings: dict[str, float]
