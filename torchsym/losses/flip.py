"""Flip consistency: a network's output on a mirrored input, mirrored back, should equal its output.

For an axis heat map ``h = net(I)`` and ``h' = net(flip(I))``, a detector that respects
the image's mirror symmetry gives ``flip(h') = h``. Orientation channels also change
under the flip (an axis at angle ``theta`` becomes one at ``-theta``):
``channel_permutation`` reorders them, e.g. :func:`orientation_flip_permutation` for
EquiSym's orientation bins.
"""

from __future__ import annotations

import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.losses._common import check_reduction, reduce

__all__ = ["flip_consistency_loss", "orientation_flip_permutation"]


def orientation_flip_permutation(n_theta: int) -> torch.Tensor:
    """``(n_theta,)`` channel order of orientation bins after a left-right flip: bin ``k``
    (angle ``k * 180 / n_theta``) goes to ``(n_theta - k) % n_theta``."""
    if n_theta < 1:
        raise InputValueError(f"n_theta: expected >= 1, got {n_theta}")
    return (-torch.arange(n_theta)) % n_theta


def flip_consistency_loss(
    output: torch.Tensor,
    output_flipped: torch.Tensor,
    *,
    dims: tuple[int, ...] = (-1,),
    mask: torch.Tensor | None = None,
    kind: str = "l1",
    channel_permutation: torch.Tensor | None = None,
    reduction: str = "none",
) -> torch.Tensor:
    """Mean ``|output - unflip(output_flipped)|`` per batch entry.

    Args:
        output: ``(B, C, ...)`` output on the input.
        output_flipped: ``(B, C, ...)`` output on the input flipped along ``dims``.
        dims: flipped axes (``-1``: left-right for images).
        mask: ``(B, 1 or C, ...)`` weights of the compared entries (e.g. valid pixels).
        kind: ``"l1"`` or ``"l2"``.
        channel_permutation: ``(C,)`` new channel order after the flip, or None.
        reduction: ``"none"`` gives ``(B,)``; ``"mean"`` / ``"sum"`` a scalar.
    """
    if not isinstance(output, torch.Tensor) or output.dim() < 2:
        raise InputShapeError(f"output: expected a (B, C, ...) tensor, got {getattr(output, 'shape', type(output).__name__)}")
    if not isinstance(output_flipped, torch.Tensor) or output_flipped.shape != output.shape:
        raise InputShapeError(f"output_flipped: expected {tuple(output.shape)} like output, got {getattr(output_flipped, 'shape', None)}")
    if kind not in ("l1", "l2"):
        raise InputValueError(f"kind: expected 'l1' or 'l2', got {kind!r}")
    check_reduction(reduction)
    back = output_flipped.flip(dims)
    if channel_permutation is not None:
        back = back.index_select(1, channel_permutation.to(back.device))
    diff = output - back
    per = diff.abs() if kind == "l1" else diff**2
    dims_all = tuple(range(1, output.dim()))
    if mask is None:
        values = per.mean(dims_all)
    else:
        m = mask.to(per.dtype).expand_as(per)
        values = (per * m).sum(dims_all) / m.sum(dims_all).clamp_min(1.0)
    return reduce(values, reduction)
