"""Reflection symmetry axes from boundary orientation and dominant cliques (thesis Sec. 2.3)."""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from torchsym.core.checks import check_image
from torchsym.core.random import make_generator, random_subset
from torchsym.core.registry import register_solver
from torchsym.core.results import on_input_device
from torchsym.core.settings import Solver, resolve_settings
from torchsym.image.batching import run_batched
from torchsym.image.boundary import BoundarySegments, boundary_curves, boundary_segments
from torchsym.image.boundary_cliques.cliques import clique_axes
from torchsym.image.boundary_cliques.graph import pair_graph
from torchsym.image.boundary_cliques.pairs import BoundaryPairs
from torchsym.image.boundary_cliques.settings import BoundaryCliquesSettings
from torchsym.image.candidates import mirror_pair_candidates
from torchsym.image.evidence import mirror_correlation
from torchsym.image.results import ReflectionAxesBatch, ReflectionAxesResult, empty_result
from torchsym.image.sift_pairs import mirror_sift_pairs
from torchsym.image.verification import Axis, GradientField, finish_axes, verify_axis

__all__ = ["BoundaryCliqueDetector", "boundary_clique_axes"]

METHOD = "boundary_cliques"


@on_input_device
def boundary_clique_axes(
    image: torch.Tensor,
    settings: BoundaryCliquesSettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> ReflectionAxesResult | ReflectionAxesBatch:
    """Reflection symmetry axes by boundary orientation and dominant cliques (thesis Sec. 2.3).

    Algorithm 2: boundary curves and their segments (Sec. 2.3.1) -> pairs of symmetric
    boundary samples (Eq. 2.9) -> a graph of pairs with one axis -> dominant cliques by
    the LP of Eq. 2.11 -> one axis per clique, scored by its mirrored gradients
    (``score="gradient"``, not in the thesis) -> with ``sift``, the axes of mirrored-SIFT
    pairs (Sec. 2.2.1) as further candidates, checked the same way -> one axis per object.
    Why each step beyond the thesis exists: ``docs/design/axes.md``.

    Args:
        image: ``(C, H, W)`` or ``(B, C, H, W)`` float image in [0, 1], ``C`` in {1, 3},
            sides >= 16.
        settings: :class:`BoundaryCliquesSettings`, a mapping of them, or None (defaults).
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with ``settings.seed``, so the same call gives the same bits.
        **overrides: settings by name (dotted for groups: ``cliques.min_support=4``).

    Returns:
        :class:`~torchsym.image.results.ReflectionAxesResult` (a
        :class:`~torchsym.image.results.ReflectionAxesBatch` for ``B > 1``);
        ``info["stage_seconds"]`` times each stage.

    Example:
        >>> from torchsym.image.synthetic import mirrored_objects_image
        >>> img, gt = mirrored_objects_image(1)
        >>> boundary_clique_axes(img).axes.shape[1]
        4
    """
    settings = resolve_settings(BoundaryCliquesSettings, settings, overrides)
    generator = generator if generator is not None else make_generator(settings.seed)
    return run_batched(_detect, image, settings.max_side, settings.min_side, settings=settings, generator=generator)


def _detect(image: torch.Tensor, settings: BoundaryCliquesSettings, generator: torch.Generator) -> ReflectionAxesResult:
    """:func:`boundary_clique_axes` on one ``(1, C, H, W)`` image."""
    img = check_image(image, "image", min_size=16).detach()  # every stage below is combinatorial
    h, w = int(img.shape[-2]), int(img.shape[-1])
    tol = settings.axis_distance * max(h, w)
    t0 = time.perf_counter()
    stages: dict[str, float] = {}
    segs, n_curves, stride = _boundary_samples(img, settings, stages)
    tic = time.perf_counter()
    pairs = BoundaryPairs.of(segs, theta=settings.theta, min_distance=settings.segments.length, max_shift=stride)
    stages["pairs"] = time.perf_counter() - tic
    nodes = np.arange(len(pairs))
    if len(pairs) > settings.max_boundary_pairs:
        nodes = random_subset(len(pairs), settings.max_boundary_pairs, generator).numpy()
    info: dict[str, Any] = dict(n_curves=n_curves, n_samples=len(segs), n_pairs_found=len(pairs), stage_seconds=stages)
    if nodes.size < settings.cliques.min_support and not settings.use_sift:
        stages.update(graph=0.0, cliques=0.0)
        return empty_result(h, w, METHOD, pairs=torch.from_numpy(pairs.pairs).float(),
                            reason="too few symmetric boundary pairs", **info)
    tic = time.perf_counter()
    adj = pair_graph(pairs, nodes, theta=settings.theta, distance=tol)
    stages["graph"] = time.perf_counter() - tic
    tic = time.perf_counter()
    gray = img[0].float().mean(0).cpu().numpy()
    field = GradientField.of(gray) if settings.score == "gradient" else None
    scorer = functools.partial(_score_axis, pairs=pairs.pairs, gray=gray, field=field, settings=settings)
    found = clique_axes(pairs, nodes, adj, scorer, max_axes=settings.max_axes, min_support=settings.cliques.min_support,
                        solver=settings.cliques.solver, gather_support=settings.cliques.gather_support,
                        theta=settings.theta, distance=tol)
    stages["cliques"] = time.perf_counter() - tic
    axes, all_pairs, distance = found.axes, pairs.pairs, None
    if settings.use_sift:  # score == "gradient" (checked): every axis has an extent
        tic = time.perf_counter()
        sift_pairs = mirror_sift_pairs(img, max_keypoints=settings.sift.max_keypoints, backend=settings.sift.backend)[0].cpu().numpy()  # (P, 4)
        sift_axes = _sift_axes(sift_pairs, field, settings, h, w, offset=len(pairs))
        axes, all_pairs, distance = axes + sift_axes, np.concatenate([all_pairs, sift_pairs]), tol
        info.update(n_sift_pairs=int(sift_pairs.shape[0]), sift_axes=len(sift_axes))
        stages["sift"] = time.perf_counter() - tic
    info.update(clique_fallbacks=found.fallbacks, axes_without_evidence=found.without_evidence,
                seconds=time.perf_counter() - t0)
    if not axes:
        enough = len(pairs) >= settings.cliques.min_support or settings.use_sift
        info["reason"] = "no axis with mirrored gradients" if enough else "too few symmetric boundary pairs"
    return finish_axes(axes, all_pairs, h, w, METHOD, duplicate_distance=distance, converged=found.fallbacks == 0,
                       info=info)


def _boundary_samples(
    img: torch.Tensor, settings: BoundaryCliquesSettings, stages: dict[str, float]
) -> tuple[BoundarySegments, int, float]:
    """Step 1 (Sec. 2.3.1): boundary curves cut into segments every ``segments.stride``
    px of arc, the stride widened so that at most ``max_samples`` remain (the pair search
    is quadratic in them). Returns the segments, the number of curves and the stride used
    (the most a pair's second point slides,
    :func:`~torchsym.image.boundary_cliques.pairs.symmetric_boundary_pairs`)."""
    e, s = settings.edges, settings.segments
    t0 = time.perf_counter()
    curves, tangent = boundary_curves(img.cpu(), edges=e.detector, sigma=e.sigma, low_threshold=e.low_threshold,
                                      high_threshold=e.high_threshold, min_length=int(s.length))
    stages["edges"] = time.perf_counter() - t0
    tangent = tangent if s.tangents == "gradient" else None
    stride = s.stride
    segs = boundary_segments(curves, tangent, smooth=s.smooth, segment_length=s.length, n_samples=s.n_samples,
                             stride=stride)
    if len(segs) > s.max_samples:  # the same arc at a wider stride; each curve keeps its first sample
        stride *= len(segs) / s.max_samples
        segs = boundary_segments(curves, tangent, smooth=s.smooth, segment_length=s.length, n_samples=s.n_samples,
                                 stride=stride)
        if len(segs) > s.max_samples:
            segs = BoundarySegments(segs.points[: s.max_samples], segs.angles[: s.max_samples], segs.curve[: s.max_samples])
    stages["segments"] = time.perf_counter() - t0 - stages["edges"]
    return segs, len(curves), stride


def _score_axis(
    line: np.ndarray, members: np.ndarray, *, pairs: np.ndarray, gray: np.ndarray, field: GradientField | None,
    settings: BoundaryCliquesSettings,
) -> Axis:
    """A clique's axis scored as ``settings.score`` says, in [0, 1] (``support``: the
    fraction of the image's symmetric pairs it holds; ``photometric``: that x mirror
    correlation; ``gradient``: :func:`verify_axis`)."""
    if settings.score == "gradient":
        return verify_axis(field, line, pairs, members, min_half_width=settings.segments.length / 3,
                           grow_threshold=settings.grow_threshold)
    value = members.size / max(len(pairs), 1)
    if settings.score == "photometric":
        value *= max(0.0, mirror_correlation(gray, line, pairs[members].reshape(-1, 2)))
    return Axis(line, members, value)


def _sift_axes(
    sift_pairs: np.ndarray, field: GradientField, settings: BoundaryCliquesSettings, h: int, w: int, *, offset: int
) -> list[Axis]:
    """Axes of mirrored-SIFT pairs (:func:`~torchsym.image.candidates.mirror_pair_candidates`)
    with evidence, scored ``sift.weight`` times; members index past the ``offset`` boundary pairs."""
    out = []
    for line, run in mirror_pair_candidates(sift_pairs, h, w, min_support=settings.sift.min_support):
        axis = verify_axis(field, line, sift_pairs, run, weight=settings.sift.weight,
                           min_half_width=settings.segments.length / 3, grow_threshold=settings.grow_threshold)
        if axis.score > 0:
            out.append(dataclasses.replace(axis, members=axis.members + offset))
    return out


@register_solver("boundary_cliques", kind="image")
class BoundaryCliqueDetector(Solver):
    """Reflection axes by boundary orientation and dominant cliques (thesis Sec. 2.3).

    Module form of :func:`boundary_clique_axes`; settings: :class:`BoundaryCliquesSettings`.
    """

    settings_class = BoundaryCliquesSettings

    def forward(self, data: torch.Tensor, generator: torch.Generator | None = None):
        return boundary_clique_axes(
            data, self.settings, generator=generator if generator is not None else make_generator(self.settings.seed)
        )
