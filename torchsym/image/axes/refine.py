"""Refinement of candidate axes by their photometric score (coarse to fine).

Each round tries every combination of ``2 k + 1`` angle steps and ``2 k + 1`` offset steps
(across the axis) around each axis's current best, keeps the best, and halves both steps;
after ``rounds`` rounds the angle is resolved to ``angle_step / 2 ** rounds`` (the default
5 rounds from 2 degrees: 0.06 degree). All axes and all their trials go through
:func:`~torchsym.image.axes.mirror_ncc.mirror_ncc` at once.
"""

from __future__ import annotations

import math

import torch

from torchsym.image.axes.mirror_ncc import AxisParams, mirror_ncc

__all__ = ["refine_axes"]


def refine_axes(
    image: torch.Tensor,
    axes: AxisParams,
    *,
    angle_step: float = 2.0,
    offset_step: float = 0.02,
    rounds: int = 5,
    k: int = 2,
    n_along: int = 32,
    n_across: int = 16,
) -> tuple[AxisParams, torch.Tensor, torch.Tensor]:
    """Angle and offset of each axis moved to maximise :func:`mirror_ncc` on ``image``.

    Args:
        image: ``(C, H, W)`` float image, the pyramid level the axes are given in.
        axes: ``N`` starting axes (:class:`AxisParams`, that level's pixels).
        angle_step: first round's angle step, degrees.
        offset_step: first round's offset step, times the image's longer side.
        rounds: rounds of the search (each halves both steps).
        k: steps each way per round.
        n_along, n_across: the support's sampling (:func:`mirror_ncc`).

    Returns:
        ``(axes, ncc (N,), inside (N,))``: the refined axes (centre moved across the axis
        only), their correlation and the fraction of their support inside the image.
    """
    n = axes.centre.shape[0]
    steps = torch.arange(-k, k + 1, dtype=torch.float32, device=axes.centre.device)
    da, do = torch.meshgrid(steps, steps, indexing="ij")
    da, do = da.reshape(-1), do.reshape(-1)  # (T,) each
    t = da.numel()
    centre, angle = axes.centre.clone(), axes.angle.clone()
    a_step, o_step = math.radians(angle_step), offset_step * max(image.shape[-2:])
    for _ in range(rounds):
        normal = torch.stack([-torch.sin(angle), torch.cos(angle)], -1)  # (N, 2)
        c = (centre[:, None] + (o_step * do)[None, :, None] * normal[:, None]).reshape(-1, 2)  # (N T, 2)
        a = (angle[:, None] + a_step * da[None]).reshape(-1)
        trial = AxisParams(c, a, axes.half_length.repeat_interleave(t), axes.half_width.repeat_interleave(t))
        ncc, _ = mirror_ncc(image, trial, n_along=n_along, n_across=n_across)
        best = ncc.reshape(n, t).argmax(1)  # (N,)
        pick = torch.arange(n, device=best.device) * t + best
        centre, angle = c[pick], a[pick]
        a_step, o_step = a_step / 2, o_step / 2
    out = AxisParams(centre, angle, axes.half_length, axes.half_width)
    ncc, inside = mirror_ncc(image, out, n_along=n_along, n_across=n_across)
    return out, ncc, inside
