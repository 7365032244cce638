"""The axes a method that reads the axis stage works about (the dense map, SymmSLIC)."""

from __future__ import annotations

import torch

from torchsym.image.axes.settings import AxisStageSettings
from torchsym.image.axes.stage import image_axes

__all__ = ["accepted_axes", "stage_axes_found"]


def accepted_axes(
    image: torch.Tensor, settings: AxisStageSettings, *, generator: torch.Generator | None = None
) -> tuple[torch.Tensor, list[torch.Tensor]]:
    """The axes :func:`~torchsym.image.axes.image_axes` accepts on ``image (1, C, H, W)``,
    the best-ranked one when none is (the caller asks for something about an axis).

    Args:
        image: ``(1, C, H, W)`` float image in [0, 1].
        settings: the stage's settings (the caller's nested ``axes`` group).
        generator: the caller's source of randomness, passed through to the stage.

    Returns:
        ``(lines (A, 3), pairs)``: the lines ``a x + b y + c = 0`` and, per axis, its
        supporting mirror pairs ``(M_a, 4)``, in ``image``'s pixels and on its device.
    """
    lines, pairs, _ = stage_axes_found(image, settings, generator=generator)
    return lines, pairs


def stage_axes_found(
    image: torch.Tensor, settings: AxisStageSettings, *, generator: torch.Generator | None = None
) -> tuple[torch.Tensor, list[torch.Tensor], bool]:
    """:func:`accepted_axes` and whether the stage accepted them (False: the best-ranked
    axis, or none, stands in), for a caller whose score must stay low without symmetry."""
    with torch.no_grad():
        found = image_axes(image, settings, generator=generator)
    accepted = bool(found.accepted.any())
    keep = found.accepted.nonzero()[:, 0] if accepted else torch.arange(min(1, len(found)))
    pairs = [found.pairs[found.pair_axis == int(k)].to(image.device) for k in keep]
    return found.lines[keep].to(image.device), pairs, accepted
