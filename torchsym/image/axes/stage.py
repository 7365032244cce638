"""The axis stage: every image method's reflection axes (thesis Ch. 2), verified by the image.

Steps: candidate axes from symmetric boundary pairs and mirrored-SIFT pairs
(:func:`~torchsym.image.boundary_cliques.boundary_clique_axes`, thesis Secs. 2.2-2.3) ->
each candidate's support compared with its reflection on a band-passed pyramid level
(:func:`~torchsym.image.axes.mirror_ncc.mirror_ncc`, after Cicconet et al. 2017) -> angle
and offset refined to the best correlation (:func:`~torchsym.image.axes.refine.refine_axes`)
-> the calibrated score and the decision (:mod:`~torchsym.image.axes.decision`) -> one axis
per object (:func:`~torchsym.image.suppression.suppress_duplicates`), best first.
Why each step exists: ``docs/design/axes.md``.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from torchsym.core.checks import check_image, check_unit_range
from torchsym.core.random import make_generator
from torchsym.core.registry import register_solver
from torchsym.core.results import on_input_device
from torchsym.core.settings import Solver, resolve_settings
from torchsym.image.axes.border import content_box
from torchsym.image.axes.decision import calibrated_score, turned_ncc
from torchsym.image.axes.extent import grow_extent
from torchsym.image.axes.level import band_level, from_level, to_level
from torchsym.image.axes.global_mirror import MirrorMap, axis_correlation, map_peaks, mirror_map
from torchsym.image.axes.mirror_ncc import AxisParams, mirror_ncc
from torchsym.image.axes.refine import refine_axes
from torchsym.image.axes.settings import AxisStageSettings
from torchsym.image.boundary_cliques import boundary_clique_axes
from torchsym.image.lines import clip_line_to_image
from torchsym.image.results import ReflectionAxesBatch, ReflectionAxesResult, empty_result
from torchsym.image.suppression import suppress_duplicates

__all__ = ["AxisStage", "candidate_features", "image_axes", "registration_axes", "shift_result", "verify_candidates"]

METHOD = "axes"


@on_input_device
def image_axes(
    image: torch.Tensor,
    settings: AxisStageSettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> ReflectionAxesResult | ReflectionAxesBatch:
    """The reflection axes of a photograph, ranked by a calibrated score, with a decision.

    Args:
        image: ``(C, H, W)`` or ``(B, C, H, W)`` float image in [0, 1] (or uint8), ``C`` in
            {1, 3}, sides >= 16.
        settings: :class:`AxisStageSettings`, a mapping of them, or None (defaults).
        generator: the source of randomness of the candidates (``torch.Generator``); None
            uses a fresh generator seeded with ``settings.candidates.seed``.
        **overrides: settings by name (dotted for groups: ``decision.threshold=0.3``).

    Returns:
        :class:`~torchsym.image.results.ReflectionAxesResult` (a batch for ``B > 1``):
        ``axes (K, 4)`` and ``scores (K,)`` (the calibrated probability that the axis is
        right, in [0, 1]) best first, ``accepted (K,)`` those at or above
        ``decision.threshold``; ``info`` holds each axis's ``ncc`` and ``contrast``.

    Example:
        >>> from torchsym.image.synthetic import mirrored_objects_image
        >>> img, gt = mirrored_objects_image(1)
        >>> res = image_axes(img)
        >>> bool(res.accepted[0])
        True
    """
    settings = resolve_settings(AxisStageSettings, settings, overrides)
    generator = generator if generator is not None else make_generator(settings.candidates.seed)
    img = check_image(image, "image", min_size=16)
    if not _integer_image(image):
        img = check_unit_range(img, "image")  # a float photo in 0-255 would saturate: refused, as elsewhere
    found = [_one(img[b : b + 1], settings, generator) for b in range(img.shape[0])]
    return found[0] if len(found) == 1 else ReflectionAxesBatch(tuple(found))


def _one(img: torch.Tensor, settings: AxisStageSettings, generator: torch.Generator) -> ReflectionAxesResult:
    """:func:`image_axes` on one ``(1, C, H, W)`` image: every step on its content box
    (:func:`~torchsym.image.axes.border.content_box`), the axes mapped back."""
    t0 = time.perf_counter()
    bd = settings.border
    y0, y1, x0, x1 = content_box(img[0].detach(), tolerance=bd.tolerance, margin=bd.margin, min_margin=bd.min_band)
    crop = img[..., y0:y1, x0:x1]
    cand = boundary_clique_axes(crop.detach(), settings.candidates, generator=generator)
    info = {"stage_seconds": {"candidates": time.perf_counter() - t0}, "content_box": [y0, y1, x0, x1]}
    found = verify_candidates(crop, cand, settings, info)
    return shift_result(found, x0, y0, (int(img.shape[-2]), int(img.shape[-1])))


def shift_result(result: ReflectionAxesResult, x0: int, y0: int, size: tuple[int, int]) -> ReflectionAxesResult:
    """``result`` found on a crop whose top-left corner is ``(x0, y0)`` in an image of ``size
    (H, W)``, in that image's pixels."""
    if x0 == 0 and y0 == 0 and tuple(result.image_size) == tuple(size):
        return result
    off = torch.tensor([x0, y0, x0, y0], dtype=result.axes.dtype)
    lines = result.lines.clone()
    lines[:, 2] -= lines[:, 0] * x0 + lines[:, 1] * y0
    return dataclasses.replace(result, axes=result.axes + off.to(result.axes.device),
                               pairs=result.pairs + off.to(result.pairs.device, result.pairs.dtype),
                               lines=lines, image_size=tuple(size))


def verify_candidates(
    img: torch.Tensor, cand: ReflectionAxesResult, settings: AxisStageSettings, info: dict[str, Any] | None = None
) -> ReflectionAxesResult:
    """Steps 2-5 on the candidate axes ``cand`` of the ``(1, C, H, W)`` image ``img``: the
    photometric test, refinement, the registration's axes, the calibrated score and the decision."""
    h, w = int(img.shape[-2]), int(img.shape[-1])
    info = dict(info or {}, n_candidates=len(cand))
    segments, features = candidate_features(img, cand, settings, info)
    f = features
    score = calibrated_score(f["contrast"], f["length"], f["evidence"], f["registration"], f["from_map"],
                             settings.decision)
    return _ranked(segments, score, features, cand, settings, info, h, w)


def candidate_features(
    img: torch.Tensor, cand: ReflectionAxesResult, settings: AxisStageSettings, info: dict[str, Any]
) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
    """Every axis to score on ``img (1, C, H, W)``: the candidates ``cand`` (refined as
    set) and the registration's best axes, as segments ``(N, 4)`` in ``img``'s pixels, with
    their features ``(N,)`` each (``ncc``, ``contrast``, ``evidence``, ``registration``,
    ``from_map``, ``length``); timings into ``info``."""
    h, w = int(img.shape[-2]), int(img.shape[-1])
    stages = info.setdefault("stage_seconds", {})
    tic = time.perf_counter()
    ph, rf = settings.photometric, settings.refine
    level, scale = band_level(img.detach(), ph.side, ph.band_sigma)
    axes = to_level(cand.axes.to(level.device), scale, ph.width)
    for _ in range(rf.passes):
        axes, ncc, _ = refine_axes(level, axes, angle_step=rf.angle_step, offset_step=rf.offset_step,
                                   rounds=rf.rounds, k=rf.steps, n_along=ph.n_along, n_across=ph.n_across)
        if rf.extent_threshold is not None:
            axes = grow_extent(level, axes, threshold=rf.extent_threshold, width=ph.width)
    stages["photometric"] = time.perf_counter() - tic
    tic = time.perf_counter()
    n_map = 0
    registration = torch.zeros(axes.angle.shape[0])
    if settings.registration.count > 0 or settings.decision.w_registration != 0:
        mmap, gscale, found = registration_axes(img, level, scale, settings)
        axes = AxisParams(*(torch.cat([a, b]) for a, b in zip(
            (axes.centre, axes.angle, axes.half_length, axes.half_width),
            (found.centre, found.angle, found.half_length, found.half_width))))
        n_map = found.angle.shape[0]
        on_map = AxisParams(_rescale(axes.centre, scale, gscale), axes.angle, axes.half_length, axes.half_width)
        registration = axis_correlation(mmap, on_map).cpu()
    from_map = torch.cat([torch.zeros(len(cand)), torch.ones(n_map)])
    evidence = torch.cat([cand.scores.float().cpu(), torch.zeros(n_map)])
    stages["registration"] = time.perf_counter() - tic
    tic = time.perf_counter()
    ncc = mirror_ncc(level, axes, n_along=ph.n_along, n_across=ph.n_across)[0]
    contrast = ncc - turned_ncc(level, axes, n_along=ph.n_along, n_across=ph.n_across).mean(1)
    segments = from_level(axes, scale).cpu().double()
    length = (segments[:, 2:] - segments[:, :2]).norm(dim=1).float() / max(h, w)
    stages["photometric"] += time.perf_counter() - tic
    info["n_registration"] = n_map
    return segments, {"ncc": ncc.cpu(), "contrast": contrast.cpu(), "evidence": evidence,
                      "registration": registration, "from_map": from_map, "length": length}


def _rescale(xy: torch.Tensor, scale: tuple[float, float], to: tuple[float, float]) -> torch.Tensor:
    """Points ``xy (N, 2)`` on a level of ``scale`` moved to the level of scale ``to`` (:func:`band_level`)."""
    s = torch.tensor(scale, device=xy.device, dtype=xy.dtype)
    t = torch.tensor(to, device=xy.device, dtype=xy.dtype)
    return (xy + 0.5) / s * t - 0.5


def registration_axes(
    img: torch.Tensor, level: torch.Tensor, scale: tuple[float, float], settings: AxisStageSettings
) -> tuple[MirrorMap, tuple[float, float], AxisParams]:
    """The registration of ``img (1, C, H, W)`` with its mirror (:func:`mirror_map` on a grey
    band-passed level) and its ``count`` best axes on the photometric ``level`` (of
    ``scale``), each with its extent from the local mirror correlation: ``(map, the map's
    level scale, axes)``."""
    rg, ph = settings.registration, settings.photometric
    grey, gscale = band_level(img.detach(), rg.side, rg.band_sigma)
    mmap = mirror_map(grey.mean(0, keepdim=True), n_angles=rg.n_angles, min_overlap=rg.min_overlap)
    angle, centre, _ = map_peaks(mmap, rg.count)
    centre = _rescale(centre, gscale, scale)
    whole = torch.full_like(angle, float(max(level.shape[-2:])))
    found = AxisParams(centre, angle, whole, ph.width * whole)
    if angle.numel():
        found = grow_extent(level, found, threshold=rg.extent_threshold, width=ph.width)
    return mmap, gscale, found


def _ranked(
    segments: torch.Tensor, score: torch.Tensor, features: dict[str, torch.Tensor], cand: ReflectionAxesResult,
    settings: AxisStageSettings, info: dict[str, Any], h: int, w: int,
) -> ReflectionAxesResult:
    """The result: segments ``(N, 4)`` clipped to the image, duplicates of better axes
    dropped, at most ``max_axes``, best first; pairs keep the axis their candidate became;
    ``info`` holds each kept axis's ``features (N,)``."""
    lines, extents, segs, keep_idx = [], [], [], []
    for k, seg in enumerate(segments.numpy()):
        d = seg[2:] - seg[:2]
        length = float(np.hypot(*d))
        if length <= 1e-6:
            continue
        u = d / length
        line = np.array([-u[1], u[0], u[1] * seg[0] - u[0] * seg[1]])  # a x + b y + c = 0, unit (a, b)
        foot, along = -line[2] * line[:2], np.array([-line[1], line[0]])  # as clip_line_to_image
        t = sorted(float((p - foot) @ along) for p in (seg[:2], seg[2:]))
        clipped = clip_line_to_image(line, t[0], t[1], w, h)
        if clipped is None:
            continue
        lines.append(line)
        extents.append((t[0], t[1]))
        segs.append(clipped)
        keep_idx.append(k)
    dec = settings.decision
    order = suppress_duplicates(lines, extents, [float(score[k]) for k in keep_idx], angle=dec.duplicate_angle,
                                distance=dec.duplicate_distance * max(h, w))[: settings.max_axes]
    info["duplicates_dropped"] = len(keep_idx) - len(order)
    if not order:
        return empty_result(h, w, METHOD, pairs=cand.pairs, reason="no candidate axis inside the image", **info)
    pick = [keep_idx[i] for i in order]
    new_index = torch.full((segments.shape[0] + 1,), -1, dtype=torch.int64)
    new_index[torch.tensor(pick)] = torch.arange(len(pick))
    pair_axis = new_index[cand.pair_axis]  # -1 stays -1 (the last slot)
    info.update({name: [float(v[k]) for k in pick] for name, v in features.items()}, candidate_rank=pick)
    scores = score[pick].float()
    return ReflectionAxesResult(
        axes=torch.tensor([segs[i] for i in order], dtype=torch.float32),
        scores=scores,
        lines=torch.tensor(np.stack([lines[i] for i in order]), dtype=torch.float32),
        pairs=cand.pairs.float(),
        pair_axis=pair_axis,
        image_size=(h, w),
        method=METHOD,
        converged=cand.converged,
        info=info,
        accepted=accept(scores, dec.threshold, dec.second_threshold),
    )


def accept(scores: torch.Tensor, threshold: float, second: float) -> torch.Tensor:
    """``(K,)`` bool: the axes of ``scores (K,)`` (best first) at or above ``threshold``, those
    after the best also at or above ``second``."""
    keep = scores >= threshold
    keep[1:] &= scores[1:] >= second
    return keep


@register_solver("axes", kind="image", default=True)
class AxisStage(Solver):
    """Reflection axes of a photograph, verified and refined by the image, with a decision.

    Module form of :func:`image_axes`; settings: :class:`AxisStageSettings`.
    """

    settings_class = AxisStageSettings

    def forward(self, data: torch.Tensor, generator: torch.Generator | None = None):
        return image_axes(data, self.settings, generator=generator)


def _integer_image(image: object) -> bool:
    """Whether ``image`` holds integers (scaled to [0, 1] by :func:`check_image`)."""
    dtype = getattr(image, "dtype", None)
    return dtype is not None and not (dtype.is_floating_point if isinstance(dtype, torch.dtype) else dtype.kind == "f")
