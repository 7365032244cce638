"""The result of the dense reflection symmetry map (thesis Ch. 3)."""

from __future__ import annotations

import dataclasses
from typing import Any

import torch

from torchsym.core.results import ArraySink, Result, to_jsonable

__all__ = ["StylizedResult", "SymmetryMapResult"]


@dataclasses.dataclass(frozen=True)
class SymmetryMapResult(Result):
    """Reflection symmetry maps of one image, one per symmetry axis (thesis Sec. 3.2).

    Maps are at the working resolution (the input resized so that its longer side is at
    most ``max_side``); ``scale`` converts: input pixel = map pixel x ``scale``.

    Attributes:
        nmrf: ``(K, H, W, 2)`` float: the nearest mirror reflection field ``f_h``, the
            ``(x, y)`` pixel of each pixel's mirror about axis ``h``.
        ssm: ``(K, H, W)`` float in [0, 1]: the symmetry score map ``S_h`` (Eqs. 3.7-3.8).
        lines: ``(K, 3)`` float axis lines ``a x + b y + c = 0`` (unit ``(a, b)``) fitted to
            each cluster's pairs, in map pixels.
        pairs: ``(P, 4)`` float candidate mirror pairs ``x1, y1, x2, y2`` in map pixels.
        pair_cluster: ``(P,)`` int64 index of the cluster each pair belongs to (its first),
            -1 for outliers.
        image: ``(C, H, W)`` float in [0, 1]: the image the maps describe (the input at the
            working resolution), carried for the reconstruction and the stylization.
        scale: input pixels per map pixel (1.0 when the input was not resized).
        scheme: ``"irs"``, ``"mmp"`` or ``"bmp"``.
        iterations: IRS iterations run (0 for MMP and BMP).
        notes: what the solver could not do as asked (no pairs, fewer clusters than ``k``).
        seconds: wall time per stage (``candidates``, ``axes_count``, ``clustering``,
            ``descriptors``, ``patchmatch``, ``score``).
    """

    nmrf: torch.Tensor
    ssm: torch.Tensor
    lines: torch.Tensor
    pairs: torch.Tensor
    pair_cluster: torch.Tensor
    image: torch.Tensor
    scale: float
    scheme: str
    iterations: int
    notes: tuple[str, ...] = ()
    seconds: dict[str, float] = dataclasses.field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.ssm.shape[0])

    @property
    def score_map(self) -> torch.Tensor:
        """``(H, W)`` the highest score over the axes; zeros when there are none."""
        if self.ssm.shape[0] == 0:
            return torch.zeros(self.image.shape[-2:], dtype=self.image.dtype, device=self.image.device)
        return self.ssm.max(0).values

    @property
    def score(self) -> float:
        """The photo's symmetry score in [0, 1]: the mean of :attr:`score_map`, the share of
        the picture explained by a mirror (0 without an axis)."""
        return float(self.score_map.float().mean().clamp(0, 1)) if self.ssm.numel() else 0.0

    def to_dict(self, sink: ArraySink | None = None, name: str = "") -> dict[str, Any]:
        """A JSON summary; with ``sink`` (a dataset run) also ``score_map``, the ``(H, W)``
        highest score over the axes at map resolution, as an array in the sink. The maps
        themselves are written as ``.npy`` by the picture writer."""
        out = {
            "type": type(self).__name__,
            "map_size": list(self.ssm.shape[-2:]) if self.ssm.dim() == 3 else list(self.image.shape[-2:]),
            "n_axes": len(self),
            "score": self.score,
            "lines": to_jsonable(self.lines),
            "scores": [float(s.mean()) for s in self.ssm],
            "n_pairs": int(self.pairs.shape[0]),
            "cluster_sizes": [int((self.pair_cluster == h).sum()) for h in range(len(self))],
            "scale": self.scale,
            "scheme": self.scheme,
            "iterations": self.iterations,
            "notes": list(self.notes),
            "seconds": to_jsonable(self.seconds),
        }
        if sink is not None:
            out["score_map"] = sink.take(f"{name}.score_map" if name else "score_map", self.score_map.detach().float().cpu().numpy())
        return out


@dataclasses.dataclass(frozen=True)
class StylizedResult(Result):
    """A symmetry-preserving stylization (thesis Sec. 3.4).

    Attributes:
        image: ``(C, H, W)`` float in [0, 1]: each region filled with its mean colour.
        labels: ``(H, W)`` int64 region of each pixel after merging (0 .. R - 1).
        region_scores: ``(R,)`` float in [0, 1]: each region's average symmetry score.
        n_superpixels: SLIC superpixels before merging.
        notes: what the solver could not do as asked.
    """

    image: torch.Tensor
    labels: torch.Tensor
    region_scores: torch.Tensor
    n_superpixels: int
    notes: tuple[str, ...] = ()

    @property
    def score(self) -> float:
        """The mean region score over the picture's pixels, in [0, 1] (0 without regions)."""
        if not self.region_scores.numel():
            return 0.0
        weights = torch.bincount(self.labels.flatten(), minlength=self.region_scores.numel()).to(self.region_scores)
        return float((weights * self.region_scores).sum() / weights.sum().clamp_min(1))

    def to_dict(self, sink: ArraySink | None = None, name: str = "") -> dict[str, Any]:
        """A JSON summary (no large arrays, so ``sink`` is unused; the picture is written by
        the picture writer)."""
        return {
            "type": type(self).__name__,
            "image_size": list(self.image.shape[-2:]),
            "n_superpixels": self.n_superpixels,
            "n_regions": int(self.region_scores.numel()),
            "score": self.score,
            "min_region_score": float(self.region_scores.min()) if self.region_scores.numel() else None,
            "mean_region_score": float(self.region_scores.mean()) if self.region_scores.numel() else None,
            "notes": list(self.notes),
        }
