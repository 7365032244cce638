"""Evaluation of detected reflection axes in images (thesis Sec. 2.4).

A detected segment ``l_e`` is correct for a ground-truth segment ``l_g`` when the angle
between them is below ``theta_t`` and the distance between their centres is below
``d_t``. Two protocols are in use on the "Detecting Symmetry in the Wild" set:

- ``"thesis"`` (Sec. 2.4): ``theta_t = 3 deg``, ``d_t = 0.025 min(w, h)``;
- ``"challenge"`` (the ICCV 2017 challenge's looser rule): ``theta_t = 10 deg``,
  ``d_t = 0.2 |l_g|`` (a fifth of the ground-truth segment's length).

Detections are matched in order of decreasing score; each ground-truth axis is matched
at most once (a second correct detection of the same axis is a false positive), so the
counts at every score threshold are consistent and the precision-recall curve over
scores (:func:`torchsym.metrics.precision_recall_curve`) has the thesis's max F.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import torch

from torchsym.core.checks import as_tensor, check_positive
from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError
from torchsym.metrics.pr import PRCurve, precision_recall, precision_recall_curve

__all__ = [
    "AXIS_CRITERIA",
    "AxesEvaluation",
    "axis_angle",
    "axis_center_distance",
    "evaluate_axes",
    "match_axes",
]

#: Named protocols: angle threshold in degrees and how the distance threshold is set.
AXIS_CRITERIA = {
    "thesis": {"theta_t": 3.0, "d_t": "0.025 * min(width, height)"},
    "challenge": {"theta_t": 10.0, "d_t": "0.2 * ground-truth length"},
}


def _segments(x: Any, name: str) -> torch.Tensor:
    t = as_tensor(x, name, dtype=torch.float64)
    if t.dim() == 1 and t.numel() == 0:
        t = t.reshape(0, 4)
    if t.dim() != 2 or t.shape[1] != 4:
        raise InputShapeError(f"{name}: expected (K, 4) segments x1, y1, x2, y2, got {tuple(t.shape)}")
    return t


def axis_angle(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Angle in degrees, in [0, 90], between segments ``a (..., 4)`` and ``b (..., 4)`` (undirected)."""
    va = a[..., 2:] - a[..., :2]
    vb = b[..., 2:] - b[..., :2]
    cross = (va[..., 0] * vb[..., 1] - va[..., 1] * vb[..., 0]).abs()
    dot = (va * vb).sum(-1).abs()
    return torch.rad2deg(torch.atan2(cross, dot))


def axis_center_distance(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Distance between the centres of segments ``a (..., 4)`` and ``b (..., 4)`` (Sec. 2.4)."""
    ca = 0.5 * (a[..., :2] + a[..., 2:])
    cb = 0.5 * (b[..., :2] + b[..., 2:])
    return (ca - cb).norm(dim=-1)


def match_axes(
    pred: Any,
    gt: Any,
    *,
    image_size: tuple[int, int],
    scores: Any | None = None,
    criterion: str = "thesis",
    theta_t: float | None = None,
    d_t: float | None = None,
) -> torch.Tensor:
    """Which detected axes are correct, each ground truth matched at most once.

    Args:
        pred: ``(K, 4)`` detected segments ``x1, y1, x2, y2``.
        gt: ``(G, 4)`` ground-truth segments.
        image_size: ``(height, width)`` of the image.
        scores: ``(K,)`` detection scores; detections are matched best first. None keeps
            the given order.
        criterion: ``"thesis"`` or ``"challenge"`` (module docstring).
        theta_t: angle threshold in degrees, overriding the criterion's.
        d_t: centre-distance threshold in pixels, overriding the criterion's.

    Returns:
        ``(K,)`` bool, in the order of ``pred``.

    Example:
        >>> match_axes([[50, 0, 50, 99]], [[51, 0, 51, 99]], image_size=(100, 100))
        tensor([True])
    """
    p = _segments(pred, "pred")
    g = _segments(gt, "gt")
    if criterion not in AXIS_CRITERIA:
        raise InputValueError(f"criterion: expected one of {sorted(AXIS_CRITERIA)}, got {criterion!r}")
    if len(image_size) != 2:
        raise InputShapeError(f"image_size: expected (height, width), got {image_size!r}")
    h, w = (check_positive(v, "image_size") for v in image_size)
    theta = check_positive(theta_t, "theta_t") if theta_t is not None else AXIS_CRITERIA[criterion]["theta_t"]
    if d_t is not None:
        dist_t = torch.full((g.shape[0],), check_positive(d_t, "d_t"), dtype=torch.float64)
    elif criterion == "thesis":
        dist_t = torch.full((g.shape[0],), 0.025 * min(w, h), dtype=torch.float64)
    else:
        dist_t = 0.2 * (g[:, 2:] - g[:, :2]).norm(dim=1)
    if scores is None:
        order = torch.arange(p.shape[0])
    else:
        s = as_tensor(scores, "scores").reshape(-1)
        if s.shape[0] != p.shape[0]:
            raise InputShapeError(f"scores: expected ({p.shape[0]},) like pred, got {tuple(s.shape)}")
        order = torch.argsort(s, descending=True, stable=True)
    correct = torch.zeros(p.shape[0], dtype=torch.bool)
    if p.shape[0] == 0 or g.shape[0] == 0:
        return correct
    ok = (axis_angle(p[:, None], g[None]) < theta) & (axis_center_distance(p[:, None], g[None]) < dist_t[None])  # (K, G)
    free = torch.ones(g.shape[0], dtype=torch.bool)
    for k in order.tolist():
        hit = (ok[k] & free).nonzero().flatten()
        if hit.numel():
            cand = hit[axis_center_distance(p[k][None], g[hit]).argmin()]
            free[cand] = False
            correct[k] = True
    return correct


@dataclasses.dataclass(frozen=True)
class AxesEvaluation(Result):
    """Scores of axis detections over a set of images (thesis Sec. 2.4).

    Attributes:
        criterion: the protocol's name.
        curve: precision-recall curve over detection scores (pooled over images).
        max_f: the largest F on the curve (the thesis's reported figure).
        precision: precision keeping every detection.
        recall: recall keeping every detection.
        f: F keeping every detection.
        n_detections: detections over all images.
        n_ground_truth: ground-truth axes over all images.
    """

    criterion: str
    curve: PRCurve
    max_f: float
    precision: float
    recall: float
    f: float
    n_detections: int
    n_ground_truth: int


def evaluate_axes(
    detections: Sequence[tuple[Any, Any]],
    ground_truths: Sequence[Any],
    image_sizes: Sequence[tuple[int, int]],
    *,
    criterion: str = "thesis",
    theta_t: float | None = None,
    d_t: float | None = None,
) -> AxesEvaluation:
    """Precision, recall, F and the PR curve of axis detections over several images.

    Args:
        detections: per image, ``(axes (K, 4), scores (K,))``.
        ground_truths: per image, ``(G, 4)`` ground-truth segments.
        image_sizes: per image, ``(height, width)``.
        criterion, theta_t, d_t: as in :func:`match_axes`.

    Returns:
        :class:`AxesEvaluation`.
    """
    if not (len(detections) == len(ground_truths) == len(image_sizes)):
        raise InputShapeError(
            f"detections: expected one entry per image like ground_truths ({len(ground_truths)}) and "
            f"image_sizes ({len(image_sizes)}), got {len(detections)}"
        )
    all_scores, all_correct, n_gt = [], [], 0
    for (axes, scores), gt, size in zip(detections, ground_truths, image_sizes):
        g = _segments(gt, "ground_truths")
        a = _segments(axes, "detections")
        s = as_tensor(scores, "scores", dtype=torch.float64).reshape(-1)
        all_correct.append(match_axes(a, g, image_size=size, scores=s, criterion=criterion, theta_t=theta_t, d_t=d_t))
        all_scores.append(s)
        n_gt += int(g.shape[0])
    scores = torch.cat(all_scores) if all_scores else torch.zeros(0, dtype=torch.float64)
    correct = torch.cat(all_correct) if all_correct else torch.zeros(0, dtype=torch.bool)
    curve = precision_recall_curve(scores, correct, n_gt)
    tp = int(correct.sum())
    p, r, f = precision_recall(tp, int(correct.numel()) - tp, n_gt - tp)
    return AxesEvaluation(criterion, curve, curve.max_f, p, r, f, int(correct.numel()), n_gt)
