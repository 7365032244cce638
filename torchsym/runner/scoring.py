"""Scoring a run against ground truth with the library's metrics (:mod:`torchsym.metrics`).

The scorer is chosen by the kind of ground truth and the records' result type (the
``"type"`` of each result, registered with :func:`result_scorer`, as pictures are with
:func:`torchsym.viz.artifact_writer`), never by the keys a record happens to hold. Ground
truth is read by :mod:`torchsym.runner.truth`, whose docstring gives each format.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.core.results import Result
from torchsym.errors import InputFileError, InputValueError
from torchsym.runner.store import read_results
from torchsym.runner.truth import GroundTruth, bsds_segmentations, read_object_mask, read_truth
from torchsym.runner.validate import check_record, scored_means

__all__ = ["Evaluation", "evaluate", "format_evaluation", "result_scorer"]


@dataclasses.dataclass(frozen=True)
class Evaluation(Result):
    """Scores of a run against ground truth.

    Attributes:
        kind: the kind of ground truth scored (``"image"``, ``"pointcloud"``, ``"mesh"``,
            ``"superpixels"``, ``"segmentation"``).
        n_records: records in the results file.
        n_scored: records with ground truth, scored.
        n_failed: of those, records with status ``error`` or ``crashed`` (counted as missed).
        n_no_truth: records without ground truth (left out).
        figures: the figures of the data set, by protocol (e.g. ``{"thesis": {"max_f":
            ..., "precision": ..., "recall": ..., "f": ...}, "challenge": {...}}``).
        items: one row per scored input (``input``, ``status`` and its figures).
        truth: the ground-truth file or folder.
    """

    kind: str
    n_records: int
    n_scored: int
    n_failed: int
    n_no_truth: int
    figures: dict[str, dict[str, float]]
    items: list[dict[str, Any]]
    truth: str


def _ok(rec: Mapping[str, Any]) -> bool:
    return rec.get("status") == "ok" and isinstance(rec.get("result"), Mapping)


AxesOf = Callable[[Mapping[str, Any]], tuple[torch.Tensor, torch.Tensor]]


def _axes(r: Mapping[str, Any]) -> tuple[torch.Tensor, torch.Tensor]:
    """``(axes (K, 4), scores (K,))`` of an image-axes result (K >= 0 axes)."""
    return torch.tensor(r["axes"], dtype=torch.float64).reshape(-1, 4), torch.tensor(r["scores"], dtype=torch.float64).reshape(-1)


def _one_axis(r: Mapping[str, Any]) -> tuple[torch.Tensor, torch.Tensor]:
    """``(axes (K, 4), scores (K,))`` of a one-axis result (``segment``, ``score``); K = 0 when it found none."""
    flat = [v for point in r.get("segment") or [] for v in point]
    if len(flat) == 4 and None not in flat:
        return torch.tensor(flat, dtype=torch.float64).reshape(1, 4), torch.tensor([float(r.get("score") or 0.0)], dtype=torch.float64)
    return torch.zeros(0, 4, dtype=torch.float64), torch.zeros(0, dtype=torch.float64)


def _image_size(rec: Mapping[str, Any]) -> tuple[int, int]:
    size = (rec.get("result") or {}).get("image_size")
    if size:
        return int(size[0]), int(size[1])
    import cv2

    img = cv2.imread(str(rec["input"]), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise InputFileError(f"input: cannot read {str(rec['input'])!r} to find its size")
    return int(img.shape[0]), int(img.shape[1])


def _score_images(pairs: Sequence[tuple[Mapping[str, Any], Any]], axes_of: AxesOf) -> tuple[dict[str, dict[str, float]], list[dict[str, Any]]]:
    from torchsym.metrics import AXIS_CRITERIA, evaluate_axes, match_axes

    empty = (torch.zeros(0, 4, dtype=torch.float64), torch.zeros(0, dtype=torch.float64))
    dets = [axes_of(rec["result"]) if _ok(rec) else empty for rec, _ in pairs]
    gts = [gt for _, gt in pairs]
    sizes = [_image_size(rec) if _ok(rec) else (1, 1) for rec, _ in pairs]
    summary, rows = {}, [{"n_detections": int(d[0].shape[0]), "n_truth": int(g.shape[0])} for d, g in zip(dets, gts)]
    for crit in AXIS_CRITERIA:
        ev = evaluate_axes(dets, gts, sizes, criterion=crit)
        summary[crit] = {"max_f": ev.max_f, "precision": ev.precision, "recall": ev.recall, "f": ev.f}
        for row, (axes, scores), gt, size in zip(rows, dets, gts, sizes):
            correct = match_axes(axes, gt, image_size=size, scores=scores, criterion=crit)
            row[f"correct_{crit}"] = int(correct.sum())
            row[f"top_correct_{crit}"] = bool(correct[int(scores.argmax())]) if scores.numel() else False
    return summary, rows


def _box(rec: Mapping[str, Any], gt: Mapping[str, Any]) -> tuple[torch.Tensor, torch.Tensor]:
    if gt["box"] is not None:
        return gt["box"]
    from torchsym.io.read import read_pointcloud

    pts = read_pointcloud(rec["input"], dtype=torch.float64)[:, :3]
    return pts.min(0).values, pts.max(0).values


def _score_clouds(pairs: Sequence[tuple[Mapping[str, Any], Any]]) -> tuple[dict[str, dict[str, float]], list[dict[str, Any]]]:
    from torchsym.metrics import evaluate_planes

    dets, gts, boxes = [], [], []
    for rec, gt in pairs:
        if _ok(rec):
            r = rec["result"]
            score = float(r.get("score") if r.get("score") is not None else 1.0)
            dets.append((torch.tensor(r["normal"], dtype=torch.float64), torch.tensor(float(r["offset"]), dtype=torch.float64), score))
        else:
            dets.append(None)
        gts.append((gt["normal"], gt["offset"]))
        boxes.append(_box(rec, gt))
    sc = evaluate_planes(dets, gts, boxes)
    summary = {
        "plane": {"precision": sc.precision, "recall": sc.recall, "f": sc.f, "max_f": sc.curve.max_f,
                  "threshold_max_f": sc.threshold_curve.max_f},
    }
    rows = [
        {"angle_deg": _finite(a), "distance": _finite(d), "correct": bool(c)}
        for a, d, c in zip(sc.angles.tolist(), sc.distances.tolist(), sc.correct.tolist())
    ]
    return summary, rows


def _score_meshes(pairs: Sequence[tuple[Mapping[str, Any], Any]]) -> tuple[dict[str, dict[str, float]], list[dict[str, Any]]]:
    from torchsym.io.read import read_mesh
    from torchsym.metrics import correspondence_rate, mesh_rate

    rows = []
    for rec, landmarks in pairs:
        if not _ok(rec):
            rows.append({"rate": 0.0, "n_landmarks": int(landmarks.shape[0])})
            continue
        mesh = read_mesh(rec["input"], dtype=torch.float64)
        score = correspondence_rate(mesh, torch.as_tensor(rec["result"]["map"]), landmarks=landmarks)
        rows.append({"rate": _finite(score.rate), "n_landmarks": score.num_evaluated, "threshold": score.threshold})
    rates = [r["rate"] if r["rate"] is not None else 0.0 for r in rows]
    summary = {"mesh": {"mean_rate": float(np.mean(rates)) if rates else math.nan, "mesh_rate": mesh_rate(rates)}}
    return summary, rows


def _result_array(rec: Mapping[str, Any], name: str) -> np.ndarray:
    """``rec["result"][name]`` as an array; ``InputValueError`` when the result has none."""
    value = rec["result"].get(name)
    if value is None or isinstance(value, Mapping):  # absent, or an array whose .npz is missing
        raise InputValueError(
            f"results: the record of {str(rec.get('input'))!r} has no {name!r} array to score "
            f"(a {rec['result'].get('type')!r}; this ground truth needs SymmSLIC's {name})"
        )
    return np.asarray(value)


def _score_superpixels(pairs: Sequence[tuple[Mapping[str, Any], Any]]) -> tuple[dict[str, dict[str, float]], list[dict[str, Any]]]:
    from torchsym.metrics import achievable_segmentation_accuracy, boundary_recall, undersegmentation_error

    rows = []
    for rec, path in pairs:
        truths = bsds_segmentations(path)
        if not _ok(rec):  # missed: the worst value of each measure
            rows.append({"br_mean": 0.0, "br_best": 0.0, "use_mean": 1.0, "use_best": 1.0, "asa_mean": 0.0, "asa_best": 0.0,
                         "n_superpixels": 0})
            continue
        labels = _result_array(rec, "labels")
        br = [boundary_recall(labels, t) for t in truths]
        use = [undersegmentation_error(labels, t) for t in truths]
        asa = [achievable_segmentation_accuracy(labels, t) for t in truths]
        rows.append({"br_mean": float(np.mean(br)), "br_best": float(np.max(br)), "use_mean": float(np.mean(use)),
                     "use_best": float(np.min(use)), "asa_mean": float(np.mean(asa)), "asa_best": float(np.max(asa)),
                     "n_superpixels": int(len(np.unique(labels)))})
    summary = {"superpixels": scored_means(rows, list(rows[0]))}
    return summary, rows


def _ssm_row(rec: Mapping[str, Any], obj: np.ndarray) -> dict[str, float]:
    """SSM scores of a symmetry map record's ``score_map`` (resized to the mask) against ``obj``."""
    import torch.nn.functional as F

    from torchsym.metrics import ssm_scores

    score = torch.zeros(obj.shape)
    if _ok(rec):
        s = torch.as_tensor(_result_array(rec, "score_map"), dtype=torch.float32)
        score = F.interpolate(s[None, None], size=obj.shape, mode="bilinear", align_corners=False)[0, 0].clamp(0, 1)
    sc = ssm_scores(score, torch.from_numpy(obj))
    return {"auc": sc.auc, "precision": sc.precision, "recall": sc.recall, "f_beta_0_09": sc.f_beta_0_09, "f_beta_0_3": sc.f_beta_0_3}


def _segmentation_summary(rows: list[dict[str, Any]], protocol: str) -> dict[str, dict[str, float]]:
    """Means over the rows that could be scored, with ``n_unscored`` (:func:`scored_means`)."""
    return {protocol: scored_means(rows, list(rows[0]))} if rows else {}


def _score_masks(pairs: Sequence[tuple[Mapping[str, Any], Any]]) -> tuple[dict[str, dict[str, float]], list[dict[str, Any]]]:
    """Object masks (SymmSLIC's ``mask``) by the segmentation error over the image and the box."""
    from torchsym.metrics import segmentation_error

    rows = []
    for rec, path in pairs:
        obj, band = read_object_mask(path)
        mask = _result_array(rec, "mask").astype(bool) if _ok(rec) else np.zeros_like(obj)  # missed: nothing found
        if mask.shape != obj.shape:
            raise InputValueError(f"results: the mask of {str(rec.get('input'))!r} is {mask.shape}, its ground truth {obj.shape}")
        rows.append(segmentation_error(mask, obj, ignore=band))
    return _segmentation_summary(rows, "segmentation"), rows


def _score_maps(pairs: Sequence[tuple[Mapping[str, Any], Any]]) -> tuple[dict[str, dict[str, float]], list[dict[str, Any]]]:
    """Symmetry maps (``score_map``) by the SSM scores; a failed input scores an all-zero map."""
    rows = [_ssm_row(rec, read_object_mask(path)[0]) for rec, path in pairs]
    return _segmentation_summary(rows, "ssm"), rows


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


Scorer = Callable[[Sequence[tuple[Mapping[str, Any], Any]]], tuple[dict[str, dict[str, float]], list[dict[str, Any]]]]

#: scorers by (kind of ground truth, result type): ``(records, truths) -> (summary, rows)``
_SCORERS: dict[tuple[str, str], Scorer] = {}


def result_scorer(truth: str, *result_types: str) -> Callable[[Scorer], Scorer]:
    """Decorator: register ``fn(pairs) -> (summary, rows)`` as the scorer of records whose
    result has one of ``result_types`` (the ``"type"`` a result's ``to_dict()`` writes:
    its class name) against ground truth of kind ``truth``, as :func:`torchsym.viz.artifact_writer`
    registers pictures per result type. The first scorer of a kind also scores a run whose
    every record failed."""

    def deco(fn: Scorer) -> Scorer:
        for name in result_types:
            _SCORERS[(truth, name)] = fn
        return fn

    return deco


result_scorer("image", "ReflectionAxesResult", "ReflectionAxesBatch")(functools.partial(_score_images, axes_of=_axes))
result_scorer("image", "ImageAxisResult")(functools.partial(_score_images, axes_of=_one_axis))
result_scorer("pointcloud", "ReflectionPlaneResult", "PointSymmResult")(_score_clouds)
result_scorer("mesh", "IntrinsicSymmetryResult")(_score_meshes)
result_scorer("superpixels", "SymmSlicResult")(_score_superpixels)
result_scorer("segmentation", "SymmSlicResult")(_score_masks)
result_scorer("segmentation", "SymmetryMapResult", "StylizedResult")(_score_maps)


def _scorer(kind: str, records: Sequence[Mapping[str, Any]], source: str) -> Scorer:
    """The scorer of ``records``' result type against ground truth of ``kind``."""
    types = sorted({str(rec["result"].get("type")) for rec in records if _ok(rec)})
    if len(types) > 1:
        raise InputValueError(f"results: records of several result types ({', '.join(types)}); score one run at a time")
    known = [name for k, name in _SCORERS if k == kind]
    if not types:  # every record failed: each counts as missed, whatever its type
        return _SCORERS[(kind, known[0])]
    if (kind, types[0]) not in _SCORERS:
        raise InputValueError(
            f"truth: {source!r} is {kind} ground truth, which scores {', '.join(known)}; the run's results are {types[0]}"
        )
    return _SCORERS[(kind, types[0])]


def evaluate(results: str | Path | Sequence[Mapping[str, Any]], truth: str | Path | GroundTruth) -> Evaluation:
    """Score a run's records against ground truth.

    Args:
        results: a results file of ``torchsym run`` (its latest record per input), a
            folder of ``torchsym detect``'s ``<stem>.json`` records, or the records.
        truth: a ground-truth file or folder (formats in the module docstring), or a
            :class:`GroundTruth`.

    Returns:
        :class:`Evaluation`: the data set's figures and one row per input.

    Raises:
        InputFileError: unreadable results or ground truth.
        InputValueError: no record has ground truth (names do not match).
    """
    if isinstance(results, (str, Path)) and Path(results).is_dir():
        records = _detect_records(Path(results))
    else:
        records = read_results(results) if isinstance(results, (str, Path)) else list(results)
    gt = truth if isinstance(truth, GroundTruth) else read_truth(truth)
    records = [check_record(rec, f"results[{i}]", gt.kind) for i, rec in enumerate(records)]
    pairs = [(rec, gt.find(str(rec.get("input")))) for rec in records]
    scored = [(rec, g) for rec, g in pairs if g is not None]
    if not scored:
        names = ", ".join(sorted(gt.items)[:3])
        raise InputValueError(
            f"truth: no record of the run has ground truth in {gt.source!r} (records like "
            f"{Path(str(records[0].get('input'))).name if records else 'none'!r}, truth names like {names})"
        )
    summary, rows = _scorer(gt.kind, [rec for rec, _ in scored], gt.source)(scored)
    items = [{"input": rec.get("input"), "status": rec.get("status"), **row} for (rec, _), row in zip(scored, rows)]
    n_failed = sum(1 for rec, _ in scored if not _ok(rec))
    return Evaluation(gt.kind, len(records), len(scored), n_failed, len(records) - len(scored), summary, items, gt.source)


def _detect_records(folder: Path) -> list[dict[str, Any]]:
    """The records ``torchsym detect`` wrote into ``folder`` (``<stem>.json``; other JSON
    files, which hold no record, are left out)."""
    records = []
    for path in sorted(folder.glob("*.json")):
        try:
            rec = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise InputFileError(f"results: cannot read {str(path)!r} as JSON ({exc})") from None
        if isinstance(rec, dict) and "input" in rec and "status" in rec:
            records.append(rec)
    if not records:
        raise InputFileError(f"results: no torchsym detect record (<stem>.json) in the folder {str(folder)!r}")
    return records


def format_evaluation(ev: Evaluation) -> str:
    """The evaluation as a short text table (one row per protocol)."""
    lines = [
        f"{ev.kind}: {ev.n_scored} inputs scored against {ev.truth} ({ev.n_failed} failed, "
        f"{ev.n_no_truth} without ground truth)",
    ]
    keys = sorted({k for figs in ev.figures.values() for k in figs})
    lines.append("| protocol | " + " | ".join(keys) + " |")
    lines.append("|---" * (len(keys) + 1) + "|")
    for name, figs in ev.figures.items():
        lines.append(f"| {name} | " + " | ".join(f"{figs[k]:.3f}" if k in figs else "" for k in keys) + " |")
    return "\n".join(lines)
