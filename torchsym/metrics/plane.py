"""Evaluation of detected reflection planes (thesis Sec. 5.2.4, after Funk et al. 2017).

A detected plane is correct when the angle between its normal and the ground truth's is
below ``angle_threshold`` degrees and the centre of the detected plane inside the
object's bounding box lies within ``distance_threshold`` x the box diagonal of the
ground-truth plane. The centre is the centroid of the polygon where the plane cuts the
box (the thesis's points p_e on the box). The thesis normalises the distance by the
shortest edge between its intersection points, which depends on which three points are
taken; we normalise by the box diagonal, which does not. Precision, recall and F follow from
:mod:`torchsym.metrics.pr`; :func:`plane_pr_curve` sweeps the detection score.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Sequence

import torch

from torchsym.core.checks import as_tensor
from torchsym.core.results import Result
from torchsym.errors import InputShapeError
from torchsym.geometry.reflection import plane_angle, point_plane_distance
from torchsym.metrics.pr import PRCurve, precision_recall, precision_recall_curve

__all__ = ["PlaneMatch", "PlaneScores", "evaluate_planes", "plane_center_in_box", "plane_match", "plane_pr_curve"]


def _box_edges(lo: torch.Tensor, hi: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    corners = torch.stack([torch.stack([hi[0] if a else lo[0], hi[1] if b else lo[1], hi[2] if c else lo[2]])
                           for a, b, c in itertools.product((0, 1), repeat=3)])  # (8, 3)
    pairs = [(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1]  # 12 edges
    a = corners[[i for i, _ in pairs]]
    b = corners[[j for _, j in pairs]]
    return a, b


def plane_center_in_box(normal: torch.Tensor, offset: torch.Tensor, box_min: torch.Tensor, box_max: torch.Tensor) -> torch.Tensor:
    """``(3,)`` centroid of the polygon where the plane cuts the box; the projection of the
    box centre onto the plane when the plane misses the box."""
    n = normal.double() / normal.double().norm()
    b = offset.double() / normal.double().norm()
    lo, hi = box_min.double(), box_max.double()
    a, e = _box_edges(lo, hi)
    da, de = a @ n + b, e @ n + b  # (12,)
    cross = (da * de) <= 0
    denom = da - de
    t = torch.where(denom.abs() > 0, da / torch.where(denom.abs() > 0, denom, torch.ones_like(denom)), torch.zeros_like(da))
    pts = a + t.unsqueeze(1) * (e - a)
    pts = pts[cross]
    if pts.shape[0] == 0:
        c = 0.5 * (lo + hi)
        return c - (c @ n + b) * n
    uniq = torch.unique(torch.round(pts * 1e9) / 1e9, dim=0)
    return uniq.mean(0)


@dataclasses.dataclass(frozen=True)
class PlaneMatch(Result):
    """How a detected plane compares with the ground truth.

    Attributes:
        angle: angle between the planes in degrees, in [0, 90].
        distance: distance of the detected plane's centre in the box to the true plane,
            as a fraction of the box diagonal.
        correct: both below their thresholds.
    """

    angle: float
    distance: float
    correct: bool


def plane_match(
    normal: torch.Tensor,
    offset: torch.Tensor,
    gt_normal: torch.Tensor,
    gt_offset: torch.Tensor,
    box_min: torch.Tensor,
    box_max: torch.Tensor,
    *,
    angle_threshold: float = 5.0,
    distance_threshold: float = 0.05,
) -> PlaneMatch:
    """Compare one detected plane with the ground truth (thesis Sec. 5.2.4).

    Args:
        normal, offset: detected plane ``(3,)``, ``()``.
        gt_normal, gt_offset: ground-truth plane.
        box_min, box_max: ``(3,)`` corners of the object's axis-aligned bounding box.
        angle_threshold: largest angle in degrees for a correct detection.
        distance_threshold: largest centre distance as a fraction of the box diagonal.
    """
    for name, v in (("normal", normal), ("gt_normal", gt_normal), ("box_min", box_min), ("box_max", box_max)):
        if not isinstance(v, torch.Tensor) or v.shape != (3,):
            raise InputShapeError(f"{name}: expected a (3,) tensor, got {getattr(v, 'shape', type(v).__name__)}")
    angle = float(plane_angle(normal.double(), gt_normal.double())) * 180.0 / math.pi
    centre = plane_center_in_box(normal, torch.as_tensor(offset), box_min, box_max)
    diag = float((box_max.double() - box_min.double()).norm())
    dist = float(point_plane_distance(centre[None], gt_normal.double(), torch.as_tensor(gt_offset).double()).abs()[0])
    rel = dist / diag if diag > 0 else dist
    return PlaneMatch(angle, rel, angle < angle_threshold and rel < distance_threshold)


@dataclasses.dataclass(frozen=True)
class PlaneScores(Result):
    """Scores of a set of detections against one ground-truth plane per object.

    Attributes:
        precision, recall, f: at the given thresholds, keeping every detection.
        curve: the precision-recall curve over detection scores, with its max F.
        angles: ``(M,)`` angle error of each object's detection, degrees.
        distances: ``(M,)`` relative centre distance of each detection.
        correct: ``(M,)`` bool.
    """

    precision: float
    recall: float
    f: float
    curve: PRCurve
    angles: torch.Tensor
    distances: torch.Tensor
    correct: torch.Tensor


def evaluate_planes(
    detections: Sequence[tuple[torch.Tensor, torch.Tensor, float] | None],
    ground_truth: Sequence[tuple[torch.Tensor, torch.Tensor]],
    boxes: Sequence[tuple[torch.Tensor, torch.Tensor]],
    *,
    angle_threshold: float = 5.0,
    distance_threshold: float = 0.05,
) -> PlaneScores:
    """Precision, recall and F-score of one detection per object (None: nothing detected).

    Args:
        detections: per object ``(normal, offset, score)`` or None.
        ground_truth: per object ``(normal, offset)``.
        boxes: per object ``(box_min, box_max)``.
        angle_threshold, distance_threshold: see :func:`plane_match`.
    """
    if not (len(detections) == len(ground_truth) == len(boxes)):
        raise InputShapeError(
            f"detections: expected as many entries as ground_truth ({len(ground_truth)}) and boxes ({len(boxes)}), got {len(detections)}"
        )
    angles, dists, correct, scores, found = [], [], [], [], []
    for det, (gn, gb), (lo, hi) in zip(detections, ground_truth, boxes):
        if det is None:
            angles.append(float("nan"))
            dists.append(float("nan"))
            correct.append(False)
            continue
        n, b, s = det
        m = plane_match(n, b, gn, gb, lo, hi, angle_threshold=angle_threshold, distance_threshold=distance_threshold)
        angles.append(m.angle)
        dists.append(m.distance)
        correct.append(m.correct)
        scores.append(float(s))
        found.append(m.correct)
    tp = sum(found)
    p, r, f = precision_recall(tp, len(found) - tp, len(ground_truth) - tp)
    curve = precision_recall_curve(torch.tensor(scores, dtype=torch.float64), torch.tensor(found, dtype=torch.bool), len(ground_truth))
    return PlaneScores(p, r, f, curve, torch.tensor(angles), torch.tensor(dists), torch.tensor(correct))


def plane_pr_curve(scores: Sequence[float], correct: Sequence[bool], n_ground_truth: int) -> PRCurve:
    """The precision-recall curve over detection scores (:func:`precision_recall_curve`)."""
    return precision_recall_curve(as_tensor(list(scores), "scores"), torch.as_tensor(list(correct), dtype=torch.bool), n_ground_truth)
