"""Precision, recall and F-score, and the precision-recall curve over detection scores.

Shared by every evaluation protocol of the thesis (Secs. 2.4, 5.2.4): a protocol decides
which detections are correct; these functions count them.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import torch

from torchsym.core.checks import as_tensor
from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError

__all__ = ["PRCurve", "f_score", "precision_recall", "precision_recall_curve"]


def f_score(precision: float, recall: float) -> float:
    """Harmonic mean ``2PR / (P + R)``; 0 when both are 0."""
    return 0.0 if precision + recall == 0 else 2.0 * precision * recall / (precision + recall)


def precision_recall(tp: int, fp: int, fn: int) -> tuple[float, float, float]:
    """``(precision, recall, F)`` from counts (thesis Sec. 5.2.4: P = tp/(tp+fp), R = tp/(tp+fn)).

    With no detections precision is 1 by convention (nothing claimed, nothing wrong).
    """
    for name, v in (("tp", tp), ("fp", fp), ("fn", fn)):
        if v < 0:
            raise InputValueError(f"{name}: expected a count >= 0, got {v}")
    p = tp / (tp + fp) if tp + fp else 1.0
    r = tp / (tp + fn) if tp + fn else 1.0
    return p, r, f_score(p, r)


@dataclasses.dataclass(frozen=True)
class PRCurve(Result):
    """Precision and recall as the score threshold falls through every detection.

    Attributes:
        thresholds: ``(K,)`` detection scores, descending; point k keeps detections
            with score >= thresholds[k].
        precision: ``(K,)`` precision at each threshold.
        recall: ``(K,)`` recall at each threshold.
        f: ``(K,)`` F-score at each threshold.
        max_f: the largest F-score on the curve (0 for no detections).
        best_threshold: the score threshold that attains it (inf for none).
    """

    thresholds: torch.Tensor
    precision: torch.Tensor
    recall: torch.Tensor
    f: torch.Tensor
    max_f: float
    best_threshold: float


def precision_recall_curve(scores: Any, correct: Any, n_ground_truth: int) -> PRCurve:
    """The precision-recall curve of scored detections and its maximum F-score.

    Args:
        scores: ``(K,)`` confidence of each detection (higher is surer).
        correct: ``(K,)`` bool, whether each detection is a true positive (each ground
            truth matched at most once, as the protocol decides).
        n_ground_truth: number of ground-truth symmetries.

    Returns:
        :class:`PRCurve`. Ties in score enter together.
    """
    s = as_tensor(scores, "scores").reshape(-1).double()
    c = torch.as_tensor(correct).reshape(-1).bool()
    if s.shape != c.shape:
        raise InputShapeError(f"correct: expected shape {tuple(s.shape)} like scores, got {tuple(c.shape)}")
    if n_ground_truth < 0:
        raise InputValueError(f"n_ground_truth: expected >= 0, got {n_ground_truth}")
    if int(c.sum()) > n_ground_truth:
        raise InputValueError(f"correct: {int(c.sum())} true positives exceed n_ground_truth = {n_ground_truth}")
    if s.numel() == 0:
        e = torch.zeros(0, dtype=torch.float64)
        return PRCurve(e, e, e, e, 0.0, float("inf"))
    order = torch.argsort(s, descending=True, stable=True)
    s, c = s[order], c[order].double()
    tp = c.cumsum(0)
    k = torch.arange(1, s.numel() + 1, dtype=torch.float64)
    # keep only the last index of each run of equal scores: ties enter together
    last = torch.ones_like(s, dtype=torch.bool)
    last[:-1] = s[1:] != s[:-1]
    tp, k, s = tp[last], k[last], s[last]
    precision = tp / k
    recall = tp / n_ground_truth if n_ground_truth else torch.ones_like(tp)
    f = torch.where(precision + recall > 0, 2 * precision * recall / (precision + recall), torch.zeros_like(tp))
    best = int(f.argmax())
    return PRCurve(s, precision, recall, f, float(f[best]), float(s[best]))
