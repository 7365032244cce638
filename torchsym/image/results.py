"""The result types of the image axis detectors, and how a result is assembled."""

from __future__ import annotations

import dataclasses
from typing import Any

import torch

from torchsym.core.results import Result
from torchsym.image.lines import axis_segment, clip_line_to_image

__all__ = ["ReflectionAxesBatch", "ReflectionAxesResult", "build_result", "empty_result"]


@dataclasses.dataclass(frozen=True)
class ReflectionAxesResult(Result):
    """Reflection symmetry axes found in one image (thesis Ch. 2).

    Attributes:
        axes: ``(K, 4)`` float segments ``x1, y1, x2, y2`` in input-image pixels (origin
            top-left, x right, y down), best first: each axis line clipped to the image
            and to its extent (its supporting pairs', or the evidence's).
        scores: ``(K,)`` float, decreasing: the method's axis score (see its ``score``
            setting).
        lines: ``(K, 3)`` float lines ``(a, b, c)``, ``a x + b y + c = 0`` with unit ``(a, b)``.
        pairs: ``(P, 4)`` float mirror pairs ``x1, y1, x2, y2`` found in the image.
        pair_axis: ``(P,)`` int64 index into ``axes`` of the axis each pair supports, -1
            for pairs that support none.
        image_size: ``(height, width)`` of the input image.
        method: the solver's registered name.
        converged: False when an iteration stopped at its limit or a step fell back.
        info: method-specific diagnostics (cost curves, fallbacks, timings), plain Python.
        accepted: ``(K,)`` bool, the axes the method believes at its default threshold
            (:mod:`torchsym.image.axes`); None (a method with no decision) accepts all.
    """

    axes: torch.Tensor
    scores: torch.Tensor
    lines: torch.Tensor
    pairs: torch.Tensor
    pair_axis: torch.Tensor
    image_size: tuple[int, int]
    method: str
    converged: bool = True
    info: dict[str, Any] = dataclasses.field(default_factory=dict)
    accepted: torch.Tensor | None = None

    def __post_init__(self) -> None:
        if self.accepted is None:
            object.__setattr__(self, "accepted", torch.ones(self.axes.shape[0], dtype=torch.bool, device=self.axes.device))

    def __len__(self) -> int:
        return int(self.axes.shape[0])

    @property
    def accepted_axes(self) -> torch.Tensor:
        """``(A, 4)`` the accepted axes, best first."""
        return self.axes[self.accepted]

    @property
    def score(self) -> float:
        """The photo's symmetry score in [0, 1]: the best accepted axis's score, or the best
        candidate's when none was accepted (then below the stage's threshold), 0 without one."""
        return float(self.scores.max().clamp(0, 1)) if len(self) else 0.0

    def summary(self) -> str:
        """One line: how many axes were accepted and their scores, or that none was."""
        n = int(self.accepted.sum())
        if n == 0:
            return f"{type(self).__name__}: no axis accepted ({len(self)} candidates, best score {float(self.scores.max()) if len(self) else 0.0:.3f})"
        scores = ", ".join(f"{float(s):.3f}" for s in self.scores[self.accepted])
        head = f"{type(self).__name__}: "
        return head + (f"1 axis accepted (score {scores})" if n == 1 else f"{n} axes accepted (scores {scores})")


@dataclasses.dataclass(frozen=True)
class ReflectionAxesBatch(Result):
    """Reflection axes of a batch of images.

    Attributes:
        results: one :class:`ReflectionAxesResult` per image, in batch order.
    """

    results: tuple[ReflectionAxesResult, ...]

    def __len__(self) -> int:
        return len(self.results)

    def __getitem__(self, i: int) -> ReflectionAxesResult:
        return self.results[i]


def empty_result(height: int, width: int, method: str, *, pairs: torch.Tensor | None = None, **info: Any) -> ReflectionAxesResult:
    """A result with no axes (blank image, too few features); ``pairs (P, 4)`` kept."""
    pairs = torch.zeros(0, 4) if pairs is None else pairs
    return ReflectionAxesResult(
        axes=torch.zeros(0, 4),
        scores=torch.zeros(0),
        lines=torch.zeros(0, 3),
        pairs=pairs,
        pair_axis=torch.full((pairs.shape[0],), -1, dtype=torch.int64),
        image_size=(height, width),
        method=method,
        converged=True,
        info=dict(info),
    )


def build_result(
    lines: list[torch.Tensor],
    supports: list[torch.Tensor],
    scores: list[float],
    pairs: torch.Tensor,
    height: int,
    width: int,
    method: str,
    *,
    converged: bool = True,
    extents: list[tuple[float, float] | None] | None = None,
    **info: Any,
) -> ReflectionAxesResult:
    """A result sorted by score from per-axis ``lines (3,)``, supporting pair indices and scores.

    Each axis's segment spans its supporting pairs (:func:`~torchsym.image.lines.axis_segment`)
    or, where ``extents`` gives one, the interval ``(t_lo, t_hi)`` along its line. Axes
    whose segment misses the image are dropped.
    """
    order = sorted(range(len(lines)), key=lambda k: -scores[k])
    axes, keep_lines, keep_scores = [], [], []
    pair_axis = torch.full((pairs.shape[0],), -1, dtype=torch.int64)
    for k in order:
        sup = supports[k]
        extent = None if extents is None else extents[k]
        if extent is None:
            seg = axis_segment(lines[k], pairs[sup].reshape(-1, 2), width, height)
        else:
            seg = clip_line_to_image(lines[k], extent[0], extent[1], width, height)
        if seg is None:
            continue
        pair_axis[sup] = len(axes)
        axes.append(seg)
        keep_lines.append(lines[k].double())
        keep_scores.append(float(scores[k]))
    if not axes:
        return empty_result(height, width, method, pairs=pairs, **info)
    return ReflectionAxesResult(
        axes=torch.tensor(axes, dtype=torch.float32),
        scores=torch.tensor(keep_scores, dtype=torch.float32),
        lines=torch.stack(keep_lines).float(),
        pairs=pairs.float(),
        pair_axis=pair_axis,
        image_size=(height, width),
        method=method,
        converged=converged,
        info=dict(info),
    )
