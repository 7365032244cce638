"""The result of the multi-view plane detector."""

from __future__ import annotations

import dataclasses
from typing import Any

import torch

from torchsym.core.results import ArraySink, Result

__all__ = ["Cameras", "MultiviewPlaneResult"]


@dataclasses.dataclass(frozen=True)
class Cameras(Result):
    """The registered photos' cameras (pinhole, COLMAP's camera-from-world convention).

    Attributes:
        image_names: the photos' names, in camera order.
        intrinsics: ``(C, 3, 3)`` calibration matrices (pixels).
        rotations: ``(C, 3, 3)`` camera-from-world rotations.
        translations: ``(C, 3)`` camera-from-world translations.
        sizes: ``(C, 2)`` photo width and height in pixels.
    """

    image_names: list[str]
    intrinsics: torch.Tensor
    rotations: torch.Tensor
    translations: torch.Tensor
    sizes: torch.Tensor


@dataclasses.dataclass(frozen=True)
class MultiviewPlaneResult(Result):
    """The hidden reflection plane of a scene seen in several photos (thesis Sec. 5.3).

    Attributes:
        normal: ``(3,)`` unit normal of the plane in the reconstruction's frame (largest
            component positive); zeros when no symmetry was found.
        offset: ``()`` the plane is ``normal . x + offset = 0``.
        found: whether the scene shows a reflection symmetry: at least ``min_inliers``
            inlier pairs and a ``confidence`` of at least ``min_margin``.
        confidence: the winning plane's inlier pairs over those of the best plane at least
            ``margin_angle`` degrees away (the runner-up counted as at least 1).
        score: ``1 - 1 / confidence`` in [0, 1]: 0 when another plane explains as many
            pairs, near 1 when none comes close.
        points: ``(M, 3)`` float64 reconstructed 3D points.
        colors: ``(M, 3)`` uint8 their colours.
        pairs: ``(S, 2)`` int64 mirror symmetric point pairs (indices into ``points``).
        inliers: ``(S,)`` bool, the pairs that support the plane.
        cameras: the registered photos' :class:`Cameras`.
        n_photos: photos given (``len(cameras.image_names)`` of them were registered).
        notes: what the caller should know (e.g. why no symmetry was reported).
        timings: seconds per stage (``features``, ``matching``, ``mapping``,
            ``descriptors``, ``pairs``, ``plane``, ``total``).
        reconstruction: the ``pycolmap.Reconstruction`` (not in ``to_dict``; written in
            COLMAP's format by :func:`torchsym.viz.write_artifacts`).
    """

    normal: torch.Tensor
    offset: torch.Tensor
    found: bool
    confidence: float
    score: float
    points: torch.Tensor
    colors: torch.Tensor
    pairs: torch.Tensor
    inliers: torch.Tensor
    cameras: Cameras
    n_photos: int
    notes: list[str]
    timings: dict[str, float]
    reconstruction: Any = dataclasses.field(default=None, repr=False, compare=False)

    def to_dict(self, sink: ArraySink | None = None, name: str = "") -> dict[str, Any]:
        out = super().to_dict(sink, name)
        out.pop("reconstruction")
        return out
