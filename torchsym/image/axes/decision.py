"""The decision: a score comparable across photographs, and which axes to believe.

The raw correlation of an axis's support with its reflection depends on the photograph
(a smooth or a regular texture correlates with its mirror about many lines). Its
*contrast* takes that out: the same support turned about its centre by 30, 60, 90, 120 and
150 degrees is the photograph's own chance level, and ``contrast = ncc - mean(ncc turned)``.
A logistic function of the contrast, the segment's length and the candidate's own
mirrored-gradient evidence, fitted on photographs with known axes, gives the probability
that the axis is right; an axis is accepted at or above the threshold.
"""

from __future__ import annotations

import torch

from torchsym.image.axes.mirror_ncc import AxisParams, mirror_ncc
from torchsym.image.axes.settings import Decision

__all__ = ["NULL_TURNS", "calibrated_score", "turned_ncc"]

#: Turns (degrees) of the chance-level supports.
NULL_TURNS = (30.0, 60.0, 90.0, 120.0, 150.0)


def turned_ncc(level: torch.Tensor, axes: AxisParams, *, n_along: int, n_across: int) -> torch.Tensor:
    """:func:`mirror_ncc` of each axis's support turned by each of :data:`NULL_TURNS`: ``(N, 5)``."""
    n, k = axes.centre.shape[0], len(NULL_TURNS)
    turns = torch.deg2rad(torch.tensor(NULL_TURNS, device=axes.centre.device))
    turned = AxisParams(
        axes.centre.repeat_interleave(k, 0), (axes.angle[:, None] + turns).reshape(-1),
        axes.half_length.repeat_interleave(k), axes.half_width.repeat_interleave(k),
    )
    return mirror_ncc(level, turned, n_along=n_along, n_across=n_across)[0].reshape(n, k)


def calibrated_score(contrast: torch.Tensor, length: torch.Tensor, evidence: torch.Tensor, registration: torch.Tensor,
                     from_map: torch.Tensor, decision: Decision) -> torch.Tensor:
    """The probability that each axis is right, ``(N,)`` in [0, 1], from its ``contrast (N,)``,
    its segment's ``length (N,)`` over the image's longer side, its candidate's
    mirrored-gradient ``evidence (N,)`` in [0, 1], the ``registration (N,)`` correlation at
    the axis and ``from_map (N,)`` (1 for an axis the registration proposed)
    (:class:`~torchsym.image.axes.settings.Decision`)."""
    z = (decision.intercept + decision.w_contrast * contrast + decision.w_length * torch.log(length.clamp_min(1e-3))
         + decision.w_evidence * torch.sqrt(evidence.clamp_min(0.0)) + decision.w_registration * registration
         + decision.w_from_map * from_map)
    return torch.sigmoid(z)
