"""The verification tail both axis detectors share: candidate axes -> gradient evidence ->
duplicate suppression -> result.

Each detector proposes candidate axes (a line and the mirror pairs supporting it); each
candidate is checked densely by its mirrored gradients (:func:`verify_axis`), and
:func:`finish_axes` keeps one axis per object and builds the sorted result.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import torch

from torchsym.image.evidence import EDGE_NOISE, axis_evidence, gradient_noise, mirror_gradients
from torchsym.image.results import ReflectionAxesResult, build_result
from torchsym.image.suppression import suppress_duplicates

__all__ = ["Axis", "GradientField", "finish_axes", "verify_axis"]


@dataclasses.dataclass(frozen=True)
class GradientField:
    """An image's smoothed gradients and their noise level, the input of :func:`verify_axis`.

    Attributes:
        gx: ``(H, W)`` float32 x-derivative (:func:`~torchsym.image.evidence.mirror_gradients`).
        gy: ``(H, W)`` float32 y-derivative.
        noise: gradient magnitude at or below which nothing counts as an edge:
            ``EDGE_NOISE`` (3) times the median magnitude.
    """

    gx: np.ndarray
    gy: np.ndarray
    noise: float

    @classmethod
    def of(cls, gray: np.ndarray) -> GradientField:
        """The field of a grayscale ``(H, W)`` image."""
        gx, gy = mirror_gradients(gray)
        return cls(gx, gy, EDGE_NOISE * gradient_noise(gx, gy))


@dataclasses.dataclass(frozen=True)
class Axis:
    """One candidate axis.

    Attributes:
        line: ``(3,)`` float64 ``a x + b y + c = 0``, unit ``(a, b)``.
        members: ``(M,)`` int64 indices of its supporting pairs.
        score: its score (> 0 for an axis worth reporting).
        extent: ``(t_lo, t_hi)`` along the line, or None for the span of its pairs.
    """

    line: np.ndarray
    members: np.ndarray
    score: float
    extent: tuple[float, float] | None = None


def verify_axis(
    field: GradientField, line: np.ndarray, pairs: np.ndarray, members: np.ndarray, *, weight: float = 1.0, **evidence: Any
) -> Axis:
    """``line`` checked by :func:`~torchsym.image.evidence.axis_evidence` on its supporting
    ``pairs[members]`` (``pairs (P, 4)``): score ``weight * symmetry * sqrt(area)`` (in [0,
    1] for ``weight <= 1``) and the grown extent.

    ``evidence``: settings of ``axis_evidence`` (``grow_threshold``, ``min_half_width``...).
    """
    ev = axis_evidence(field.gx, field.gy, line, pairs[members], noise_level=field.noise, **evidence)
    return Axis(line, members, weight * ev.score, ev.extent)


def finish_axes(
    axes: list[Axis],
    pairs: np.ndarray | torch.Tensor,
    height: int,
    width: int,
    method: str,
    *,
    duplicate_distance: float | None = None,
    converged: bool = True,
    info: dict[str, Any],
) -> ReflectionAxesResult:
    """The result of ``axes`` on ``pairs (P, 4)``, best score first.

    With ``duplicate_distance`` (px), near-duplicates of better axes are dropped
    (:func:`~torchsym.image.suppression.suppress_duplicates`, 10 deg) and
    ``info["duplicates_dropped"]`` counts them. ``info`` is updated in place.
    """
    if duplicate_distance is not None:
        keep = suppress_duplicates([a.line for a in axes], [a.extent for a in axes], [a.score for a in axes],
                                   distance=duplicate_distance)  # best first
        info["duplicates_dropped"] = len(axes) - len(keep)
        axes = [axes[k] for k in keep]
    pairs = torch.from_numpy(pairs) if isinstance(pairs, np.ndarray) else pairs
    return build_result(
        [torch.from_numpy(a.line) for a in axes], [torch.from_numpy(a.members) for a in axes], [a.score for a in axes],
        pairs, height, width, method, converged=converged, extents=[a.extent for a in axes], **info,
    )
