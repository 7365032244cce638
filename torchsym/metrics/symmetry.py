"""Metrics of predicted reflection planes on point clouds: SymmetryNet's dense symmetry
error with its precision-recall curve, and the symmetry distance as a metric."""

from __future__ import annotations

import math

import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.geometry.conventions import check_planes
from torchsym.losses._common import check_points, masked_mean
from torchsym.losses.symmetry_distance import nearest_neighbours, reflect_batch
from torchsym.metrics.pr import PRCurve, precision_recall_curve

__all__ = ["dense_symmetry_error", "symmetry_distance_error", "symmetrynet_pr_curve"]


def dense_symmetry_error(
    points: torch.Tensor,
    normal: torch.Tensor,
    offset: torch.Tensor,
    true_normal: torch.Tensor,
    true_offset: torch.Tensor,
    mask: torch.Tensor | None = None,
) -> torch.Tensor:
    """SymmetryNet's dense symmetry error of every predicted plane against every true one, ``(B, K, G)``.

    ``mean_i |S x_i - S* x_i| / max_i |S* x_i - x_i|`` over the (valid) points ``x_i``: the
    mean disagreement of the two reflections, relative to the longest reflection chord of
    the true plane (``tools/evaluation/eval_ref_shapenet.py`` in
    ``GodZarathustra/SymmetryNet``). Scale-free; 0 for the same plane.

    Args:
        points: ``(B, N, D)``, ``mask (B, N)``.
        normal, offset: ``(B, K, D)``, ``(B, K)`` predicted planes.
        true_normal, true_offset: ``(B, G, D)``, ``(B, G)`` true planes.
    """
    w = check_points(points, mask)
    check_planes(normal, offset, points.shape[-1])
    check_planes(true_normal, true_offset, points.shape[-1])
    pred = reflect_batch(points, normal, offset)  # (B, K, N, D)
    true = reflect_batch(points, true_normal, true_offset)  # (B, G, N, D)
    dense = (pred.unsqueeze(2) - true.unsqueeze(1)).norm(dim=-1)  # (B, K, G, N)
    chord = (true - points.unsqueeze(1)).norm(dim=-1) * w.unsqueeze(1)  # (B, G, N)
    longest = chord.amax(-1).clamp_min(torch.finfo(points.dtype).tiny)  # (B, G)
    return masked_mean(dense, w[:, None, None, :], dim=-1) / longest.unsqueeze(1)


def symmetrynet_pr_curve(
    errors: torch.Tensor,
    scores: torch.Tensor,
    *,
    threshold: float = math.tan(math.radians(15.0)),
    pred_mask: torch.Tensor | None = None,
    true_mask: torch.Tensor | None = None,
) -> PRCurve:
    """SymmetryNet's precision-recall curve from dense errors ``(B, K, G)`` and scores ``(B, K)``.

    As in ``eval_ref_shapenet.py``: a true plane is found (one true positive, carrying the
    score of the first prediction within ``threshold`` of it) when some prediction's error
    is at most ``threshold`` (``tan 15 deg`` there); a prediction within the threshold of no
    true plane is a false positive; the curve sweeps the score. A prediction may find
    several true planes.

    Args:
        errors: ``(B, K, G)`` from :func:`dense_symmetry_error`.
        scores: ``(B, K)`` confidences of the predictions.
        threshold: error at or under which a prediction matches.
        pred_mask, true_mask: ``(B, K)`` and ``(B, G)`` real predictions and true planes.
    """
    if errors.dim() != 3 or scores.shape != errors.shape[:2]:
        raise InputShapeError(f"scores: expected {tuple(errors.shape[:2])} to match errors (B, K, G), got {tuple(scores.shape)}")
    if not threshold >= 0:
        raise InputValueError(f"threshold: expected >= 0, got {threshold}")
    b, k, g = errors.shape
    pm = torch.ones(b, k, dtype=torch.bool) if pred_mask is None else pred_mask.bool().cpu()
    tm = torch.ones(b, g, dtype=torch.bool) if true_mask is None else true_mask.bool().cpu()
    hit = (errors.detach().cpu() <= threshold) & pm[:, :, None] & tm[:, None, :]  # (B, K, G)
    s = scores.detach().cpu().double()
    found = hit.any(1)  # (B, G)
    first = hit.int().argmax(1)  # (B, G): first matching prediction
    tp_scores = torch.gather(s, 1, first)[found]
    fp = pm & ~hit.any(2)  # (B, K)
    all_scores = torch.cat([tp_scores, s[fp]])
    correct = torch.cat([torch.ones_like(tp_scores, dtype=torch.bool), torch.zeros(int(fp.sum()), dtype=torch.bool)])
    return precision_recall_curve(all_scores, correct, int(tm.sum()))


def symmetry_distance_error(
    points: torch.Tensor,
    normal: torch.Tensor,
    offset: torch.Tensor,
    mask: torch.Tensor | None = None,
    *,
    scale: str = "diagonal",
    method: str = "auto",
) -> torch.Tensor:
    """Mean distance from each reflected point to the cloud, per cloud and plane, ``(B, K)`` (no gradient).

    The metric form of :func:`torchsym.losses.symmetry_distance`: distances, not squares,
    divided by the cloud's bounding-box diagonal (``scale="diagonal"``) or not (``"none"``).
    """
    w = check_points(points, mask)
    check_planes(normal, offset, points.shape[-1])
    if scale not in ("diagonal", "none"):
        raise InputValueError(f"scale: expected 'diagonal' or 'none', got {scale!r}")
    with torch.no_grad():
        b, n, d = points.shape
        k = normal.shape[1]
        refl = reflect_batch(points, normal, offset)
        idx = nearest_neighbours(refl.reshape(b, k * n, d), points, mask, method=method)
        target = torch.gather(points, 1, idx.unsqueeze(-1).expand(-1, -1, d)).reshape(b, k, n, d)
        err = masked_mean((refl - target).norm(dim=-1), w.unsqueeze(1), dim=-1)  # (B, K)
        if scale == "diagonal":
            big = torch.finfo(points.dtype).max
            valid = w.unsqueeze(-1) > 0
            hi = points.masked_fill(~valid, -big).amax(1)
            lo = points.masked_fill(~valid, big).amin(1)
            err = err / (hi - lo).norm(dim=-1).clamp_min(torch.finfo(points.dtype).tiny).unsqueeze(-1)
        return err
