"""Reflection symmetry axes by k-symmetry clustering of mirror pairs (thesis Sec. 2.2)."""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from torchsym.core.checks import check_image
from torchsym.core.registry import register_solver
from torchsym.core.results import on_input_device
from torchsym.core.settings import Solver, resolve_settings
from torchsym.features.sift import SIFT_MIN_SIDE
from torchsym.image.batching import run_batched
from torchsym.image.candidates import GATHER_ANGLE, GATHER_DISTANCE, RUN_GAP, pixel_inliers, support_runs
from torchsym.image.ksymmetry.clustering import ClusteringRun, cluster_for_each_k, initial_axes, inlier_matrix
from torchsym.image.ksymmetry.settings import KSymmetrySettings
from torchsym.image.lines import fit_axis
from torchsym.image.results import ReflectionAxesBatch, ReflectionAxesResult, empty_result
from torchsym.image.sift_pairs import mirror_sift_pairs
from torchsym.image.verification import Axis, GradientField, finish_axes, verify_axis

__all__ = ["KSymmetryDetector", "ksymmetry_axes"]


@on_input_device
def ksymmetry_axes(
    image: torch.Tensor,
    settings: KSymmetrySettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> ReflectionAxesResult | ReflectionAxesBatch:
    """Reflection symmetry axes by SIFT mirror pairs and k-symmetry clustering (thesis Sec. 2.2).

    SIFT and mirrored SIFT -> mirror pairs by mutual ``k1`` nearest neighbours (Def.
    2.2.1) -> starting axes by inlier counts (Sec. 2.2.3) -> Algorithm 1 for ``k = 1 ..
    max_axes`` -> ``k`` at the elbow of the cost curve (Fig. 2.1e) -> one axis per
    cluster, ranked by its support (``score="support"``) or checked by its mirrored
    gradients (``score="gradient"``, ``docs/design/axes.md``).

    Args:
        image: ``(C, H, W)`` or ``(B, C, H, W)`` float image in [0, 1], ``C`` in {1, 3},
            sides >= 32.
        settings: :class:`KSymmetrySettings`, a mapping of them, or None (defaults).
        generator: unused (the method is deterministic); accepted like every solver's.
        **overrides: settings by name (dotted for groups: ``clustering.max_iters=20``).

    Returns:
        :class:`~torchsym.image.results.ReflectionAxesResult` (a
        :class:`~torchsym.image.results.ReflectionAxesBatch` for ``B > 1``); ``info``
        holds ``k1``, ``k``, ``cost_curve`` and ``n_iter``.

    Example:
        >>> img = torch.zeros(1, 64, 64); img[:, 20:44, 16:48] = torch.rand(1, 24, 16).repeat(1, 1, 2)
        >>> ksymmetry_axes(img).axes.shape[1]
        4
    """
    settings = resolve_settings(KSymmetrySettings, settings, overrides)
    return run_batched(_detect, image, settings.max_side, settings.min_side, settings=settings)


def _detect(image: torch.Tensor, settings: KSymmetrySettings) -> ReflectionAxesResult:
    """:func:`ksymmetry_axes` on one ``(1, C, H, W)`` image."""
    img = check_image(image, "image", min_size=SIFT_MIN_SIDE).detach()  # nothing below is differentiable
    h, w = int(img.shape[-2]), int(img.shape[-1])
    t0 = time.perf_counter()
    sp = settings.pairs
    pairs, k1 = mirror_sift_pairs(img, max_keypoints=sp.max_keypoints, k1=sp.k1, min_pair_distance=sp.min_distance,
                                 backend=sp.backend)  # (P, 4)
    # SIFT ran on the image's device; the clustering and the evidence run on the CPU
    pairs, img = pairs.cpu(), img.cpu()
    if pairs.shape[0] == 0 and k1 == 0:
        return empty_result(h, w, "ksymmetry", k1=None, reason="fewer than 2 keypoints")
    if pairs.shape[0] < settings.min_support:
        return empty_result(h, w, "ksymmetry", pairs=pairs, k1=k1, reason="too few mirror pairs")
    centre = torch.tensor([(w - 1) / 2, (h - 1) / 2], dtype=torch.float64)
    scale = max(h, w) / 2.0
    left = (pairs[:, :2] - centre) / scale  # (P, 2) normalised
    right = (pairs[:, 2:] - centre) / scale
    starts = initial_axes(inlier_matrix(left, right, settings.eps_theta, settings.eps_d), settings.max_axes)
    if not starts:
        return empty_result(h, w, "ksymmetry", pairs=pairs, k1=k1, reason="no candidate axis")
    run = cluster_for_each_k(
        left, right, starts, max_iters=settings.clustering.max_iters, outlier_cost=settings.clustering.outlier_cost
    )
    info: dict[str, Any] = dict(k1=k1, k=run.k, cost_curve=run.cost_curve, n_iter=run.iterations)
    if settings.score == "support":
        axes = _cluster_axes(run, pairs.numpy(), centre, scale, settings.min_support, GATHER_DISTANCE * max(h, w))
        info["seconds"] = time.perf_counter() - t0
        return finish_axes(axes, pairs, h, w, "ksymmetry", converged=run.converged, info=info)
    axes, evidence_free = _verified_runs(run, pairs.numpy(), img, centre, scale, settings)
    info.update(seconds=time.perf_counter() - t0, axes_without_evidence=evidence_free)
    # clusters on one line may give overlapping runs: keep each axis once
    return finish_axes(axes, pairs, h, w, "ksymmetry", duplicate_distance=GATHER_DISTANCE * max(h, w),
                       converged=run.converged, info=info)


def _cluster_lines(run: ClusteringRun, centre: torch.Tensor, scale: float, min_support: int):
    """``(line (3,) in pixels, members (M,))`` of each cluster with ``min_support`` pairs."""
    for i in range(run.axes.shape[0]):
        sup = (run.labels == i).nonzero().flatten()
        if sup.numel() < min_support:
            continue
        a, b, c = run.axes[i]
        line = torch.stack([a, b, c * scale - a * centre[0] - b * centre[1]])  # back to pixels
        yield line / line[:2].norm().clamp_min(1e-12), sup


def _cluster_axes(
    run: ClusteringRun, pairs: np.ndarray, centre: torch.Tensor, scale: float, min_support: int, tol: float
) -> list[Axis]:
    """One axis per cluster, scored by its support (the thesis's ranking) as a fraction in
    [0, 1]: the share of all ``pairs (P, 4)`` that are inliers of its line (chord within
    ``GATHER_ANGLE`` of the normal, midpoint within ``tol`` px). Clustering assigns every
    pair to some axis; counting inliers keeps a cluster of stray pairs low."""
    out = []
    for line, sup in _cluster_lines(run, centre, scale, min_support):
        inliers = int(pixel_inliers(pairs, line.numpy()[None], GATHER_ANGLE, tol)[:, 0].sum())
        out.append(Axis(line.numpy(), sup.numpy(), inliers / pairs.shape[0]))
    return out


def _verified_runs(
    run: ClusteringRun, pairs: np.ndarray, img: torch.Tensor, centre: torch.Tensor, scale: float, settings: KSymmetrySettings
) -> tuple[list[Axis], int]:
    """``score="gradient"``: each cluster's axis gathers the pairs near it, split into runs
    along the line; each run of ``min_support`` pairs is refitted and checked by its mirrored
    gradients. Returns the axes that have evidence and the count of runs without."""
    h, w = int(img.shape[-2]), int(img.shape[-1])
    field = GradientField.of(img[0].float().mean(0).numpy())
    axes, evidence_free = [], 0
    for line, sup in _cluster_lines(run, centre, scale, settings.min_support):
        near = pixel_inliers(pairs, line.numpy()[None], GATHER_ANGLE, GATHER_DISTANCE * max(h, w))[:, 0]
        members = np.union1d(np.flatnonzero(near), sup.numpy())
        for part in support_runs(line.numpy(), pairs, members, RUN_GAP * max(h, w)):
            if part.size < settings.min_support:
                continue
            fit = fit_axis(pairs[part], centre.numpy(), scale)
            axis = verify_axis(field, fit, pairs, part, grow_threshold=settings.grow_threshold)
            if axis.score <= 0:
                evidence_free += 1
                continue
            axes.append(axis)
    return axes, evidence_free


@register_solver("ksymmetry", kind="image")
class KSymmetryDetector(Solver):
    """Reflection axes by SIFT mirror pairs and k-symmetry clustering (thesis Sec. 2.2).

    Module form of :func:`ksymmetry_axes`; settings: :class:`KSymmetrySettings`.
    """

    settings_class = KSymmetrySettings

    def forward(self, data: torch.Tensor, generator: torch.Generator | None = None):
        return ksymmetry_axes(data, self.settings, generator=generator)
