"""Flip consistency: a network's output on a mirrored input, mirrored back, should equal its output.

For an axis heat map ``h = net(I)`` and ``h' = net(flip(I))``, a detector that respects
the image's mirror symmetry gives ``flip(h') = h``. Orientation channels also change
under the flip (an axis at angle ``theta`` becomes one at ``-theta``):
``channel_permutation`` reorders them, e.g. :func:`orientation_flip_permutation` for
EquiSym's orientation bins.
"""

from __future__ import annotations

import torch

from torchsym.core.checks import check_int
from torchsym.errors import InputShapeError, InputValueError
from torchsym.losses._common import _shape, check_finite_here, check_reduction, reduce

__all__ = ["flip_consistency_loss", "orientation_flip_permutation"]


def orientation_flip_permutation(n_theta: int) -> torch.Tensor:
    """``(n_theta,)`` channel order of orientation bins after a left-right flip: bin ``k``
    (angle ``k * 180 / n_theta``) goes to ``(n_theta - k) % n_theta``."""
    n_theta = check_int(n_theta, "n_theta", minimum=1)
    if n_theta > 1 << 20:
        raise InputValueError(f"n_theta: expected at most {1 << 20} orientation bins, got {n_theta}")
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
        reduction: ``"none"`` gives ``(B,)``; ``"mean"`` / ``"sum"`` a scalar (0 for an empty batch).

    Raises :class:`InputShapeError` for shapes or dtypes that do not match and
    :class:`InputValueError` for bad ``dims`` / ``channel_permutation`` / options and NaN
    or infinite entries (CPU tensors outside ``torch.compile``).
    """
    if not isinstance(output, torch.Tensor) or output.dim() < 2 or not output.is_floating_point():
        raise InputShapeError(f"output: expected a floating (B, C, ...) tensor, got {_shape(output)}"
                              + (f" of dtype {output.dtype}" if isinstance(output, torch.Tensor) else ""))
    if not isinstance(output_flipped, torch.Tensor) or output_flipped.shape != output.shape or output_flipped.dtype != output.dtype:
        raise InputShapeError(f"output_flipped: expected {tuple(output.shape)} of dtype {output.dtype} like output, got {_shape(output_flipped)}")
    if kind not in ("l1", "l2"):
        raise InputValueError(f"kind: expected 'l1' or 'l2', got {kind!r}")
    check_reduction(reduction)
    nd = output.dim()
    if (not isinstance(dims, (tuple, list)) or not all(isinstance(a, int) and not isinstance(a, bool) for a in dims)
            or not all(-nd + 2 <= a < nd and a not in (0, 1, -nd, 1 - nd) for a in dims)):
        raise InputValueError(f"dims: expected a tuple of the spatial axes (2 to {nd - 1}, or negative), got {dims!r}")
    per_row = max(1, output[:1].numel())
    check_finite_here(output, "output", squares=per_row)
    check_finite_here(output_flipped, "output_flipped", squares=per_row)
    back = output_flipped.flip(tuple(dims))
    if channel_permutation is not None:
        c = output.shape[1]
        perm = channel_permutation
        if (not isinstance(perm, torch.Tensor) or perm.shape != (c,) or perm.dtype not in (torch.int32, torch.int64)
                or (perm.device.type == "cpu" and not torch.equal(perm.sort().values, torch.arange(c, dtype=perm.dtype)))):
            raise InputValueError(f"channel_permutation: expected an integer permutation of range({c}), got {perm!r}")
        back = back.index_select(1, perm.to(back.device))
    diff = output - back
    per = diff.abs() if kind == "l1" else diff**2
    dims_all = tuple(range(1, output.dim()))
    if mask is None:
        values = per.sum(dims_all) / max(1, per[:1].numel())  # the mean per entry, 0 for an empty image
    else:
        ok = isinstance(mask, torch.Tensor) and mask.dim() == output.dim() and not mask.is_complex()
        if not ok or not all(ms in (1, os) for ms, os in zip(mask.shape, output.shape)) or mask.shape[0] != output.shape[0]:
            raise InputShapeError(f"mask: expected (B, 1 or C, ...) to broadcast to {tuple(output.shape)}, got {_shape(mask)}")
        check_finite_here(mask.to(per.dtype), "mask")
        m = mask.to(per.dtype).expand_as(per)
        values = (per * m).sum(dims_all) / m.sum(dims_all).clamp_min(1.0)
    return reduce(values, reduction)
