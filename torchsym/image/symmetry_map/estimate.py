"""The dense reflection symmetry map of an image (thesis Ch. 3, Algorithm 3), and its solver.

Steps (Sec. 3.2): mirrored-SIFT candidate pairs
(:mod:`~torchsym.image.symmetry_map.candidates`) -> ``k`` clusters by RansaCov
(:mod:`~torchsym.image.symmetry_map.clustering`) when ``k`` is given, else one cluster
about each axis the axis stage accepts (:func:`torchsym.image.axes.image_axes`) -> per cluster: dense descriptors in the
axis frame (:mod:`~torchsym.image.symmetry_map.descriptors`), symmetric PatchMatch
(:mod:`~torchsym.image.symmetry_map.patchmatch`), the score map
(:mod:`~torchsym.image.symmetry_map.scores`). Tensor stages run on the image's device.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import torch
import torch.nn.functional as F

from torchsym.core.checks import check_image, check_unit_range
from torchsym.core.random import make_generator
from torchsym.image.axes.accepted import accepted_axes
from torchsym.core.registry import register_solver
from torchsym.core.settings import Solver, resolve_settings
from torchsym.errors import InputShapeError
from torchsym.image.symmetry_map.candidates import mirror_sift_matches
from torchsym.image.symmetry_map.clustering import PairClusters, ransacov
from torchsym.image.symmetry_map.descriptors import dense_axis_descriptors
from torchsym.image.symmetry_map.patchmatch import (
    best_mirror_pixel,
    expand_field,
    grid_index,
    initial_field,
    mean_mirror_pixel,
    patchmatch_iteration,
    search_radius,
)
from torchsym.image.symmetry_map.result import SymmetryMapResult
from torchsym.image.symmetry_map.scores import distance_to_points, symmetry_scores
from torchsym.image.symmetry_map.settings import SymmetryMapSettings

__all__ = ["SymmetryMapSolver", "cluster_field", "clusters_about_axes", "symmetry_map", "working_image"]


def working_image(image: Any, max_side: int | None) -> tuple[torch.Tensor, float]:
    """``(1, C, H, W)`` float image resized (area) so its longer side is at most ``max_side``, and the scale."""
    img = check_image(image, "image")
    if img.shape[0] != 1:
        raise InputShapeError(f"image: expected one image (C, H, W) or (1, C, H, W), got a batch of shape {tuple(img.shape)}")
    img = check_unit_range(img.float(), "image")
    h, w = img.shape[-2:]
    if max_side is None or max(h, w) <= max_side:
        return img, 1.0
    s = max_side / max(h, w)
    size = (max(1, round(h * s)), max(1, round(w * s)))
    return F.interpolate(img, size=size, mode="area").clamp(0, 1), max(h, w) / max(size)


def clusters_about_axes(
    pairs: torch.Tensor, lines: torch.Tensor, own: list[torch.Tensor], *, max_angle: float, max_distance: float,
    min_support: int,
) -> tuple[torch.Tensor, list[torch.Tensor]]:
    """One cluster of mirror pairs per given axis (the count and axes come from the axis stage).

    A pair ``x1, y1, x2, y2`` of ``pairs (P, 4)`` joins axis ``a`` (``lines (A, 3)``, unit
    normals) when its chord is within ``max_angle`` degrees of the normal and its midpoint
    within ``max_distance`` px of the line. An axis with fewer than ``min_support`` such
    pairs takes its own supporting pairs ``own[a] (M_a, 4)`` as well.

    Returns:
        ``(all_pairs (P', 4), members)``: ``pairs`` with the own pairs appended as needed,
        and one index tensor into them per axis.
    """
    members: list[torch.Tensor] = []
    extra: list[torch.Tensor] = []
    n_all = pairs.shape[0]
    for a in range(lines.shape[0]):
        n, c = lines[a, :2].to(pairs.dtype), lines[a, 2].to(pairs.dtype)
        chord = pairs[:, 2:] - pairs[:, :2]
        cos = (chord @ n).abs() / chord.norm(dim=1).clamp_min(1e-9)
        mid = 0.5 * (pairs[:, :2] + pairs[:, 2:])
        ok = (cos >= math.cos(math.radians(max_angle))) & ((mid @ n + c).abs() <= max_distance)
        idx = ok.nonzero()[:, 0]
        if idx.numel() < min_support and own[a].shape[0]:
            idx = torch.cat([idx, torch.arange(n_all, n_all + own[a].shape[0], device=pairs.device)])
            extra.append(own[a].to(pairs.dtype))
            n_all += own[a].shape[0]
        if idx.numel():
            members.append(idx)
    return (torch.cat([pairs, *extra]) if extra else pairs), members


def _cluster_line(pairs: torch.Tensor) -> torch.Tensor:
    """Least-squares axis ``(3,)`` of a cluster's pairs ``(M, 4)``: mean chord direction, mean midpoint."""
    chord = pairs[:, :2] - pairs[:, 2:]
    chord = chord / chord.norm(dim=1, keepdim=True).clamp_min(1e-6)
    ref = chord[0]
    chord = torch.where(((chord * ref).sum(1, keepdim=True) < 0), -chord, chord)
    n = chord.mean(0)
    n = n / n.norm().clamp_min(1e-6)
    mid = 0.5 * (pairs[:, :2] + pairs[:, 2:])
    return torch.cat([n, -(n * mid.mean(0)).sum()[None]])


def cluster_field(
    image: torch.Tensor,
    cluster_pairs: torch.Tensor,
    settings: SymmetryMapSettings,
    generator: torch.Generator,
    *,
    history: list[torch.Tensor] | None = None,
) -> tuple[torch.Tensor, torch.Tensor, dict[str, float]]:
    """The field and score map of one cluster (Algorithm 3, lines 3-11).

    Args:
        image: ``(1, C, H, W)`` float image.
        cluster_pairs: ``(M, 4)`` the cluster's pairs ``x1, y1, x2, y2`` (``L_h``, ``R_h``).
        settings: the method's settings (``descriptor``, ``patchmatch``, ``score``).
        generator: the source of randomness (``torch.Generator``).
        history: when a list, the field ``(H, W, 2)`` after each IRS iteration is appended to it.

    Returns:
        The field ``nmrf (H, W, 2)``, the scores ``(H, W)`` and the seconds per stage.
    """
    _, _, h, w = image.shape
    pm, seconds = settings.patchmatch, {}
    t = time.perf_counter()
    line = _cluster_line(cluster_pairs)
    normal = line[:2].float()
    desc = dense_axis_descriptors(
        image, normal, cell_px=settings.descriptor.cell_px, n_dims=settings.descriptor.n_dims, stride=pm.stride, generator=generator
    )
    seconds["descriptors"] = time.perf_counter() - t
    t = time.perf_counter()
    left, right = cluster_pairs[:, :2].float(), cluster_pairs[:, 2:].float()
    if pm.scheme == "mmp":
        state = mean_mirror_pixel(desc, left, right, pm.max_bmp_pairs, generator)
    elif pm.scheme == "bmp":
        state = best_mirror_pixel(desc, left, right, pm.max_bmp_pairs, generator)
    else:
        state = initial_field(desc, left, right, generator)
        radius = pm.search_radius if pm.search_radius is not None else search_radius(left, right, h, w, generator)
        left_index = grid_index(desc, left)
        for _ in range(pm.max_iters):
            state = patchmatch_iteration(
                state, desc, left_index, normal, radius, pm.n_samples, generator, neighbours=pm.neighbours, min_gain=pm.min_gain
            )
            if history is not None:
                history.append(expand_field(desc, state, normal)[0])
    nmrf, cost = expand_field(desc, state, normal)
    seconds["patchmatch"] = time.perf_counter() - t
    t = time.perf_counter()
    dist = distance_to_points(h, w, torch.cat([left, right]))
    scores = symmetry_scores(cost, dist, h, w, sigma_feature=settings.score.sigma_feature, sigma_d=settings.score.sigma_d)
    seconds["score"] = time.perf_counter() - t
    return nmrf, scores.view(h, w), seconds


def symmetry_map(
    image: Any,
    settings: SymmetryMapSettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> SymmetryMapResult:
    """The nearest mirror reflection field and the symmetry score map of ``image``, per axis (Algorithm 3).

    Args:
        image: ``(C, H, W)`` or ``(1, C, H, W)`` image in [0, 1] (or uint8), ``C`` in {1, 3}.
        settings: :class:`SymmetryMapSettings`, a mapping of them, or None for the defaults.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.
        **overrides: settings by name (``n_axes=1``, ``patchmatch={"scheme": "bmp"}``).

    Returns:
        :class:`SymmetryMapResult`; with no mirror pairs, no axes (``K = 0``) and a note.

    Example:
        >>> res = symmetry_map(torch.rand(3, 64, 64), n_axes=1)
        >>> res.ssm.shape[-2:]
        torch.Size([64, 64])
    """
    settings = resolve_settings(SymmetryMapSettings, settings, overrides)
    gen = make_generator(generator)
    img, scale = working_image(image, settings.max_side)
    _, c, h, w = img.shape
    seconds: dict[str, float] = {}
    notes: list[str] = []
    t = time.perf_counter()
    cand = settings.candidates
    pairs, _ = mirror_sift_matches(
        img,
        num_features=cand.num_features,
        max_distance=cand.max_distance,
        n_matches=cand.n_matches,
        min_pair_distance=cand.min_pair_distance,
        max_pairs=settings.clustering.max_pairs,
    )
    seconds["candidates"] = time.perf_counter() - t
    k = settings.n_axes
    cl = settings.clustering
    t = time.perf_counter()
    if k is None:  # the axis stage's accepted axes, each with the pairs about it
        lines, own = accepted_axes(img, settings.axes, generator=gen) if min(h, w) >= 32 else (torch.zeros(0, 3), [])
        seconds["axes"] = time.perf_counter() - t
        t = time.perf_counter()
        pairs, members = clusters_about_axes(pairs, lines, own, max_angle=cl.eps_theta,
                                             max_distance=cl.eps_d * max(h, w), min_support=cl.min_support)
        clusters = PairClusters(members, lines, 0)
        k = len(lines)
    else:
        clusters = ransacov(
            pairs, k, eps_d=cl.eps_d, eps_theta=cl.eps_theta, tol_px=cl.tol_px, cover=cl.cover, min_support=cl.min_support
        )
    seconds["clustering"] = time.perf_counter() - t
    if pairs.shape[0] == 0:
        notes.append("no mirror pairs found: no symmetry map")
    elif k == 0:
        notes.append("no axis found by the axis stage: no symmetry map")
    elif len(clusters.members) < k:
        notes.append(f"asked for {k} axes, found {len(clusters.members)} clusters of at least {cl.min_support} pairs")
    pair_cluster = torch.full((pairs.shape[0],), -1, dtype=torch.int64, device=img.device)
    fields, maps, lines = [], [], []
    for hh, members in reversed(list(enumerate(clusters.members))):
        pair_cluster[members] = hh
    for members in clusters.members:
        nmrf, scores, sec = cluster_field(img, pairs[members], settings, gen)
        for key, v in sec.items():
            seconds[key] = seconds.get(key, 0.0) + v
        fields.append(nmrf)
        maps.append(scores)
        lines.append(_cluster_line(pairs[members]))
    device = img.device
    return SymmetryMapResult(
        nmrf=torch.stack(fields) if fields else torch.zeros(0, h, w, 2, device=device),
        ssm=torch.stack(maps) if maps else torch.zeros(0, h, w, device=device),
        lines=torch.stack(lines).float() if lines else torch.zeros(0, 3, device=device),
        pairs=pairs.float(),
        pair_cluster=pair_cluster,
        image=img[0],
        scale=float(scale),
        scheme=settings.patchmatch.scheme,
        iterations=settings.patchmatch.max_iters if settings.patchmatch.scheme == "irs" and fields else 0,
        notes=tuple(notes),
        seconds=seconds,
    )


@register_solver("symmetry_map", kind="image")
class SymmetryMapSolver(Solver):
    """Dense reflection symmetry map (NMRF and SSM per axis) by symmetric PatchMatch (thesis Ch. 3)."""

    settings_class = SymmetryMapSettings

    def forward(self, data: Any, generator: torch.Generator | None = None) -> SymmetryMapResult:
        return symmetry_map(data, self.settings, generator=generator if generator is not None else make_generator(self.settings.seed))
