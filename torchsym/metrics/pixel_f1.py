"""Pixel-map F1 of 2D axis detection, EquiSym's protocol (``PointEvaluation`` in ``ahyunSeo/EquiSym`` ``utils.py``).

The one-pixel ground-truth axes are dilated by a disc of radius ``max_dist`` (5 px); a
predicted map in ``[0, 1]`` is thresholded at ``n`` levels ``linspace(1/(n+1), 1 - 1/(n+1), n)``;
at each level ``tp`` counts predicted pixels inside the dilated axes, precision is
``tp / predicted`` (0 when nothing is predicted, after Funk and Liu) and recall
``tp / dilated ground-truth pixels``; counts are summed over the whole data set before
the ratios. The score reported is the largest F1 over the levels.
"""

from __future__ import annotations

import dataclasses

import torch
import torch.nn.functional as F

from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError

__all__ = ["PixelF1", "axis_pixel_counts", "axis_pixel_f1", "pixel_f1_from_counts"]


@dataclasses.dataclass(frozen=True)
class PixelF1(Result):
    """Pixel-map precision, recall and F1 at each threshold.

    Attributes:
        thresholds: ``(T,)`` levels.
        precision, recall, f1: ``(T,)`` each.
        counts: ``(3, T)`` summed ``tp``, predicted pixels and dilated ground-truth pixels.
        max_f1: the best F1.
        best_threshold: the level that attains it.
    """

    thresholds: torch.Tensor
    precision: torch.Tensor
    recall: torch.Tensor
    f1: torch.Tensor
    counts: torch.Tensor
    max_f1: float
    best_threshold: float


def _disc(radius: int, device) -> torch.Tensor:
    r = torch.arange(-radius, radius + 1, device=device, dtype=torch.float32)
    return ((r.view(-1, 1) ** 2 + r.view(1, -1) ** 2) <= radius**2).float().view(1, 1, 2 * radius + 1, 2 * radius + 1)


def _dilate(x: torch.Tensor, radius: int) -> torch.Tensor:
    if radius == 0:
        return (x > 0).float()
    return (F.conv2d(x, _disc(radius, x.device), padding=radius) > 0).float()


def axis_pixel_counts(
    pred: torch.Tensor, gt: torch.Tensor, *, n_thresholds: int = 100, max_dist: int = 5, blur_pred: bool = False
) -> tuple[torch.Tensor, torch.Tensor]:
    """``thresholds (T,)`` and ``counts (3, T)`` (``tp``, predicted, dilated ground truth) of a batch.

    Args:
        pred: ``(B, 1, H, W)`` predicted axis map in ``[0, 1]``.
        gt: ``(B, 1, H, W)`` ground-truth axes (non-zero on the drawn axes).
        n_thresholds: levels ``T``.
        max_dist: dilation radius in pixels.
        blur_pred: also dilate the thresholded prediction (EquiSym's ``blur_pred``).
    """
    if not isinstance(pred, torch.Tensor) or pred.dim() != 4 or pred.shape[1] != 1:
        raise InputShapeError(f"pred: expected a (B, 1, H, W) tensor, got {getattr(pred, 'shape', type(pred).__name__)}")
    if not isinstance(gt, torch.Tensor) or gt.shape != pred.shape:
        raise InputShapeError(f"gt: expected {tuple(pred.shape)} like pred, got {getattr(gt, 'shape', type(gt).__name__)}")
    if n_thresholds < 1 or max_dist < 0:
        raise InputValueError(f"n_thresholds, max_dist: expected >= 1 and >= 0, got {n_thresholds}, {max_dist}")
    with torch.no_grad():
        p = pred.detach().float()
        g = _dilate((gt.detach() > 0).float(), max_dist)
        th = torch.linspace(1.0 / (n_thresholds + 1), 1.0 - 1.0 / (n_thresholds + 1), n_thresholds)
        counts = torch.zeros(3, n_thresholds, dtype=torch.float64)
        pos_label = float(g.sum())
        for i, t in enumerate(th.tolist()):
            binary = (p > t).float()
            if blur_pred:
                binary = _dilate(binary, max_dist)
            counts[0, i] = float((binary * g).sum())
            counts[1, i] = float(binary.sum())
            counts[2, i] = pos_label
    return th.double(), counts


def pixel_f1_from_counts(thresholds: torch.Tensor, counts: torch.Tensor) -> PixelF1:
    """:class:`PixelF1` from counts summed over a data set (each batch's from :func:`axis_pixel_counts`)."""
    if counts.dim() != 2 or counts.shape != (3, thresholds.numel()):
        raise InputShapeError(f"counts: expected (3, {thresholds.numel()}), got {tuple(counts.shape)}")
    tp, pos_pred, pos_label = counts.double()
    precision = torch.where(pos_pred > 0, tp / pos_pred.clamp_min(1), torch.zeros_like(tp))
    recall = torch.where(pos_label > 0, tp / pos_label.clamp_min(1), torch.zeros_like(tp))
    s = precision + recall
    f1 = torch.where(s > 0, 2 * precision * recall / s.clamp_min(1e-300), torch.zeros_like(tp))
    best = int(f1.argmax())
    return PixelF1(thresholds.double(), precision, recall, f1, counts.double(), float(f1[best]), float(thresholds[best]))


def axis_pixel_f1(pred: torch.Tensor, gt: torch.Tensor, *, n_thresholds: int = 100, max_dist: int = 5, blur_pred: bool = False) -> PixelF1:
    """EquiSym's pixel-map F1 of ``pred (B, 1, H, W)`` against ``gt (B, 1, H, W)`` (counts over the batch)."""
    th, counts = axis_pixel_counts(pred, gt, n_thresholds=n_thresholds, max_dist=max_dist, blur_pred=blur_pred)
    return pixel_f1_from_counts(th, counts)
