"""Symmetry-preserving stylization (thesis Sec. 3.4).

SLIC superpixels (OpenCV ximgproc's ``createSuperpixelSLIC`` on the Lab image) -> the
region adjacency graph -> repeatedly the region of lowest average score is merged into
its neighbour of lowest score (the "next higher", Fig. 3.10) by edge contraction, the merged
region's score the mean of the two (as the thesis; not weighted by area), until every
region's score is above ``min_score`` (or a region has no neighbour left) -> every region
filled with its mean colour. Detail stays where the symmetry score is high.

The input is the :class:`~torchsym.image.symmetry_map.SymmetryMapResult`, which carries its
image, so a config chains ``symmetry_map -> stylize``; the score of a pixel is its highest
score over the axes (zero everywhere when the map found no axis: everything merges).
"""

from __future__ import annotations

import heapq
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from torchsym.core.random import make_generator
from torchsym.core.registry import register_solver
from torchsym.core.settings import Solver, resolve_settings
from torchsym.errors import InputShapeError, InputValueError
from torchsym.image.symmetry_map.result import StylizedResult, SymmetryMapResult
from torchsym.image.symmetry_map.settings import StylizeSettings

__all__ = ["StylizeSolver", "adjacency", "merge_regions", "slic_labels", "stylize"]


def slic_labels(image: torch.Tensor, region_px: int, ruler: float, n_iters: int) -> np.ndarray:
    """``(H, W)`` int32 SLIC labels of ``image (C, H, W)`` in [0, 1] (OpenCV ximgproc, Lab)."""
    import cv2

    rgb = (image.detach().cpu().clamp(0, 1).permute(1, 2, 0).numpy() * 255).round().astype(np.uint8)
    if rgb.shape[2] == 1:
        rgb = np.repeat(rgb, 3, 2)
    lab = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2LAB)
    slic = cv2.ximgproc.createSuperpixelSLIC(lab, algorithm=cv2.ximgproc.SLIC, region_size=region_px, ruler=ruler)
    slic.iterate(n_iters)
    slic.enforceLabelConnectivity()
    return slic.getLabels()


def adjacency(labels: np.ndarray) -> list[set[int]]:
    """Neighbour sets of the regions of ``labels (H, W)`` (4-connectivity)."""
    n = int(labels.max()) + 1
    pairs = np.concatenate(
        [
            np.stack([labels[:, :-1].ravel(), labels[:, 1:].ravel()], 1),
            np.stack([labels[:-1].ravel(), labels[1:].ravel()], 1),
        ]
    )
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    pairs = np.unique(np.sort(pairs, 1), axis=0)
    nbrs: list[set[int]] = [set() for _ in range(n)]
    for a, b in pairs.tolist():
        nbrs[a].add(b)
        nbrs[b].add(a)
    return nbrs


def merge_regions(scores: list[float], nbrs: list[set[int]], min_score: float) -> np.ndarray:
    """Merge regions by edge contraction (Sec. 3.4); returns ``(R,)`` the surviving region of each input region.

    ``scores`` (one per region) and ``nbrs`` (their neighbour sets) are consumed.
    """
    n = len(scores)
    parent = np.arange(n)
    heap = [(s, i) for i, s in enumerate(scores)]
    heapq.heapify(heap)
    alive = [True] * n
    while heap:
        s, i = heapq.heappop(heap)
        if not alive[i] or s != scores[i]:
            continue  # stale entry
        if s > min_score:
            break
        if not nbrs[i]:
            continue  # an isolated region below the threshold stays as it is
        j = min(nbrs[i], key=lambda k: (scores[k], k))
        # contract edge (i, j) into j: N_w = (N_i \ {j}) | (N_j \ {i})
        for k in nbrs[i]:
            nbrs[k].discard(i)
            if k != j:
                nbrs[k].add(j)
                nbrs[j].add(k)
        nbrs[j].discard(i)
        nbrs[i] = set()
        alive[i] = False
        parent[i] = j
        scores[j] = 0.5 * (scores[i] + scores[j])
        heapq.heappush(heap, (scores[j], j))
    for i in range(n):  # path compression
        r = i
        while parent[r] != r:
            r = parent[r]
        parent[i] = r
    return parent


def stylize(
    result: SymmetryMapResult,
    settings: StylizeSettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> StylizedResult:
    """Stylize the image of a symmetry map, keeping detail where it is symmetric (Sec. 3.4).

    Args:
        result: a :class:`~torchsym.image.symmetry_map.SymmetryMapResult` (it carries the image).
        settings: :class:`StylizeSettings`, a mapping of them, or None for the defaults.
        generator: unused (the stylization draws nothing at random); accepted as by every solver.
        **overrides: settings by name.

    Returns:
        :class:`StylizedResult` on the device of the map.
    """
    if not isinstance(result, SymmetryMapResult):
        raise InputValueError(f"result: expected a SymmetryMapResult (the symmetry_map step's output), got {type(result).__name__}")
    settings = resolve_settings(StylizeSettings, settings, overrides)
    image, score = result.image, result.score_map  # (C, H, W), (H, W)
    if min(image.shape[-2:]) < settings.region_px:  # OpenCV's SLIC crashes the process on a smaller image
        raise InputShapeError(
            f"result.image: expected height and width >= region_px = {settings.region_px}, got {tuple(image.shape)}"
        )
    labels = slic_labels(image, settings.region_px, settings.ruler, settings.n_slic_iters)
    n0 = int(labels.max()) + 1
    lab = torch.from_numpy(labels.astype(np.int64)).reshape(-1)
    count = torch.bincount(lab, minlength=n0).double().clamp_min(1)
    mean_score = torch.bincount(lab, weights=score.detach().cpu().reshape(-1).double(), minlength=n0) / count
    parent = merge_regions(mean_score.tolist(), adjacency(labels), settings.min_score)
    roots, merged = np.unique(parent, return_inverse=True)
    merged_t = torch.from_numpy(merged.astype(np.int64))[lab]  # (H*W,)
    n = roots.size
    img = image.detach().cpu().double().reshape(image.shape[0], -1)  # (C, H*W)
    area = torch.bincount(merged_t, minlength=n).double().clamp_min(1)
    colours = torch.stack([torch.bincount(merged_t, weights=ch, minlength=n) for ch in img]) / area  # (C, R)
    region_scores = torch.bincount(merged_t, weights=score.detach().cpu().reshape(-1).double(), minlength=n) / area
    out = colours[:, merged_t].reshape(image.shape).to(image)
    notes = () if len(result) else ("the map has no axis: every score is zero",)
    return StylizedResult(
        image=out,
        labels=merged_t.reshape(image.shape[-2:]).to(image.device),
        region_scores=region_scores.float().to(image.device),
        n_superpixels=n0,
        notes=notes,
    )


@register_solver("stylize", kind="any")
class StylizeSolver(Solver):
    """Symmetry-preserving stylization of a symmetry map's image: SLIC regions merged by score (thesis Sec. 3.4)."""

    settings_class = StylizeSettings

    def forward(self, data: Any, generator: torch.Generator | None = None) -> StylizedResult:
        return stylize(data, self.settings, generator=generator if generator is not None else make_generator(0))
