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

from torchsym.core.checks import as_tensor, check_int, check_positive
from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError
from torchsym.geometry.reflection import plane_angle, point_plane_distance
from torchsym.metrics.pr import PRCurve, precision_recall, precision_recall_curve

__all__ = [
    "PlaneMatch",
    "PlaneScores",
    "ThresholdCurve",
    "evaluate_planes",
    "plane_box_width",
    "plane_center_in_box",
    "plane_match",
    "plane_pr_curve",
    "plane_threshold_curve",
]


def _box_edges(lo: torch.Tensor, hi: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    corners = torch.stack([torch.stack([hi[0] if a else lo[0], hi[1] if b else lo[1], hi[2] if c else lo[2]])
                           for a, b, c in itertools.product((0, 1), repeat=3)])  # (8, 3)
    pairs = [(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1]  # 12 edges
    a = corners[[i for i, _ in pairs]]
    b = corners[[j for _, j in pairs]]
    return a, b


def _check_vectors(**vectors: torch.Tensor) -> None:
    """Raise :class:`InputShapeError` naming the first argument that is not a ``(3,)`` tensor."""
    for name, v in vectors.items():
        if not isinstance(v, torch.Tensor) or v.shape != (3,):
            raise InputShapeError(f"{name}: expected a (3,) tensor, got {getattr(v, 'shape', type(v).__name__)}")


def _box_polygon(normal: torch.Tensor, offset: torch.Tensor, box_min: torch.Tensor, box_max: torch.Tensor) -> torch.Tensor:
    """``(P, 3)`` distinct points where the plane crosses the box's edges (P = 0 or 3..6)."""
    n = normal.double() / normal.double().norm()
    b = offset.double() / normal.double().norm()
    a, e = _box_edges(box_min.double(), box_max.double())
    da, de = a @ n + b, e @ n + b  # (12,)
    cross = (da * de) <= 0
    denom = da - de
    t = torch.where(denom.abs() > 0, da / torch.where(denom.abs() > 0, denom, torch.ones_like(denom)), torch.zeros_like(da))
    pts = (a + t.unsqueeze(1) * (e - a))[cross]
    if pts.shape[0] == 0:
        return pts
    return torch.unique(torch.round(pts * 1e9) / 1e9, dim=0)


def plane_box_width(normal: torch.Tensor, offset: torch.Tensor, box_min: torch.Tensor, box_max: torch.Tensor) -> float:
    """The thesis's length unit for one plane (Sec. 5.2.4): the shortest edge of the
    triangle of three points where the plane cuts the box.

    The thesis takes "three points of intersection" ``p1, p2, p3`` without saying which,
    and uses ``min(|p1 - p2|, |p1 - p3|)``, which depends on which point is ``p1``. We take
    the three that span the largest triangle and the shortest of its three edges, so the
    unit depends on neither the order of the box's edges nor the labelling. 0 when the
    plane misses the box or touches it in fewer than three points.

    Raises:
        InputShapeError: ``normal``, ``box_min`` or ``box_max`` not ``(3,)``.
        InputValueError: a zero normal.
    """
    _check_vectors(normal=normal, box_min=box_min, box_max=box_max)
    if float(normal.double().norm()) == 0.0:
        raise InputValueError("normal: expected a non-zero vector, got a zero vector")
    pts = _box_polygon(normal, torch.as_tensor(offset), box_min, box_max)
    if pts.shape[0] < 3:
        return 0.0
    best, width = -1.0, 0.0
    for i, j, k in itertools.combinations(range(pts.shape[0]), 3):
        area = float(torch.linalg.cross(pts[j] - pts[i], pts[k] - pts[i]).norm())
        if area > best:
            best = area
            width = min(float((pts[i] - pts[j]).norm()), float((pts[i] - pts[k]).norm()), float((pts[j] - pts[k]).norm()))
    return width


def plane_center_in_box(normal: torch.Tensor, offset: torch.Tensor, box_min: torch.Tensor, box_max: torch.Tensor) -> torch.Tensor:
    """``(3,)`` centroid of the polygon where the plane cuts the box; the projection of the
    box centre onto the plane when the plane misses the box."""
    pts = _box_polygon(normal, offset, box_min, box_max)
    if pts.shape[0] == 0:
        n = normal.double() / normal.double().norm()
        b = offset.double() / normal.double().norm()
        c = 0.5 * (box_min.double() + box_max.double())
        return c - (c @ n + b) * n
    return pts.mean(0)


@dataclasses.dataclass(frozen=True)
class PlaneMatch(Result):
    """How a detected plane compares with the ground truth.

    Attributes:
        angle: angle between the planes in degrees, in [0, 90].
        distance: distance of the detected plane's centre in the box to the true plane,
            as a fraction of the box diagonal.
        correct: both below their thresholds.
        width: the thesis's length unit w for this pair, the smaller of
            :func:`plane_box_width` of the two planes (0 if either misses the box).
        distance_in_width: the centre distance in units of ``width``, the quantity the
            thesis thresholds by ``tau_d in [0, 2] x w`` (when ``width`` is 0: 0 if the
            distance is 0, else inf).
    """

    angle: float
    distance: float
    correct: bool
    width: float = 0.0
    distance_in_width: float = math.inf


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
    _check_vectors(normal=normal, gt_normal=gt_normal, box_min=box_min, box_max=box_max)
    angle = float(plane_angle(normal.double(), gt_normal.double())) * 180.0 / math.pi
    centre = plane_center_in_box(normal, torch.as_tensor(offset), box_min, box_max)
    diag = float((box_max.double() - box_min.double()).norm())
    dist = float(point_plane_distance(centre[None], gt_normal.double(), torch.as_tensor(gt_offset).double()).abs()[0])
    rel = dist / diag if diag > 0 else dist
    width = min(plane_box_width(normal, torch.as_tensor(offset), box_min, box_max),
                plane_box_width(gt_normal, torch.as_tensor(gt_offset), box_min, box_max))
    in_width = dist / width if width > 0 else (0.0 if dist == 0 else math.inf)
    return PlaneMatch(angle, rel, angle < angle_threshold and rel < distance_threshold, width, in_width)


@dataclasses.dataclass(frozen=True)
class PlaneScores(Result):
    """Scores of a set of detections against one ground-truth plane per object.

    Attributes:
        precision, recall, f: at the given thresholds, keeping every detection.
        curve: the precision-recall curve over detection scores, with its max F.
        threshold_curve: the thesis's curve over angle and distance thresholds
            (:func:`plane_threshold_curve`), with its max F.
        angles: ``(M,)`` angle error of each object's detection, degrees.
        distances: ``(M,)`` relative centre distance of each detection.
        correct: ``(M,)`` bool.
    """

    precision: float
    recall: float
    f: float
    curve: PRCurve
    threshold_curve: ThresholdCurve
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
    angles, dists, correct, scores, found, matches = [], [], [], [], [], []
    for det, (gn, gb), (lo, hi) in zip(detections, ground_truth, boxes):
        if det is None:
            angles.append(float("nan"))
            dists.append(float("nan"))
            correct.append(False)
            matches.append(None)
            continue
        n, b, s = det
        m = plane_match(n, b, gn, gb, lo, hi, angle_threshold=angle_threshold, distance_threshold=distance_threshold)
        matches.append(m)
        angles.append(m.angle)
        dists.append(m.distance)
        correct.append(m.correct)
        scores.append(float(s))
        found.append(m.correct)
    tp = sum(found)
    p, r, f = precision_recall(tp, len(found) - tp, len(ground_truth) - tp)
    curve = precision_recall_curve(torch.tensor(scores, dtype=torch.float64), torch.tensor(found, dtype=torch.bool), len(ground_truth))
    thr = plane_threshold_curve(matches, len(ground_truth))
    return PlaneScores(p, r, f, curve, thr, torch.tensor(angles), torch.tensor(dists), torch.tensor(correct))


def plane_pr_curve(scores: Sequence[float], correct: Sequence[bool], n_ground_truth: int) -> PRCurve:
    """The precision-recall curve over detection scores (:func:`precision_recall_curve`)."""
    return precision_recall_curve(as_tensor(list(scores), "scores"), torch.as_tensor(list(correct), dtype=torch.bool), n_ground_truth)


@dataclasses.dataclass(frozen=True)
class ThresholdCurve(Result):
    """Precision and recall as the correctness thresholds loosen together (thesis Sec. 5.2.4).

    Attributes:
        angle_thresholds: ``(K,)`` angle thresholds in degrees, rising from 0.
        distance_thresholds: ``(K,)`` matching distance thresholds, in units of the
            thesis's width w (:attr:`PlaneMatch.distance_in_width`).
        precision, recall, f: ``(K,)`` at each pair of thresholds.
        max_f: the best F on the curve.
        best_angle, best_distance: the thresholds that attain it (the tightest such pair).
    """

    angle_thresholds: torch.Tensor
    distance_thresholds: torch.Tensor
    precision: torch.Tensor
    recall: torch.Tensor
    f: torch.Tensor
    max_f: float
    best_angle: float
    best_distance: float


def plane_threshold_curve(
    matches: Sequence[PlaneMatch | None],
    n_ground_truth: int,
    *,
    max_angle: float = 45.0,
    max_distance: float = 2.0,
    steps: int = 46,
) -> ThresholdCurve:
    """The thesis's precision-recall curve over thresholds (Sec. 5.2.4) and its maximum F.

    Point k of the curve counts a detection as correct when its angle is below
    ``max_angle * k / (steps - 1)`` and its centre distance below
    ``max_distance * k / (steps - 1)`` widths; each object has one ground-truth plane
    and at most one detection, so an incorrect detection is both a false positive and a
    missed plane. Defaults are the thesis's ranges, tau_theta in [0, 45] degrees and
    tau_d in [0, 2] x w. When every object has a detection, precision and recall are
    equal and the maximum sits at the loosest point: the curve shows how fast the
    detections become correct, the maximum is the share within 45 degrees and 2 w
    (objects without a detection lower the recall only).

    Args:
        matches: one :class:`PlaneMatch` per object, or None where nothing was detected.
        n_ground_truth: number of ground-truth planes (normally ``len(matches)``).
        max_angle: loosest angle threshold, degrees.
        max_distance: loosest distance threshold, in widths w.
        steps: number of points on the curve (>= 2).
    """
    steps = check_int(steps, "steps", minimum=2)
    max_angle = check_positive(max_angle, "max_angle")
    max_distance = check_positive(max_distance, "max_distance")
    if n_ground_truth < 0:
        raise InputValueError(f"n_ground_truth: expected >= 0, got {n_ground_truth}")
    found = [m for m in matches if m is not None]
    if len(found) > n_ground_truth:
        raise InputValueError(f"matches: {len(found)} detections exceed n_ground_truth = {n_ground_truth}")
    t = torch.linspace(0.0, 1.0, steps, dtype=torch.float64)
    at, dt = t * max_angle, t * max_distance
    ang = torch.tensor([m.angle for m in found], dtype=torch.float64)
    dist = torch.tensor([m.distance_in_width for m in found], dtype=torch.float64)
    ok = (ang[None, :] < at[:, None]) & (dist[None, :] < dt[:, None])  # (K, M)
    tp = ok.sum(1).double()
    n_det = float(len(found))
    precision = tp / n_det if n_det else torch.ones_like(tp)
    recall = tp / n_ground_truth if n_ground_truth else torch.ones_like(tp)
    f = torch.where(precision + recall > 0, 2 * precision * recall / (precision + recall), torch.zeros_like(tp))
    best = int(f.argmax())
    return ThresholdCurve(at, dt, precision, recall, f, float(f[best]), float(at[best]), float(dt[best]))
