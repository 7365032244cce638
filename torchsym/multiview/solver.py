"""Hidden 3D reflection symmetry from several photos (thesis Sec. 5.3).

Steps, as in the thesis:

1. sparse reconstruction of the scene by COLMAP (5.3.1);
2. one SIFT descriptor per 3D point, the mean over its observations (5.3.2);
3. mirror symmetric point pairs as best buddies of mirrored descriptors (5.3.2);
4. the plane of each pair, the outlier loop over all of them and the consensus plane
   (5.3.3-5.3.4), with a confidence the thesis does not give.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import torch

from torchsym.core.random import draw_seed, make_generator
from torchsym.core.registry import register_solver
from torchsym.core.settings import Solver, resolve_settings
from torchsym.multiview.pairs import best_buddy_pairs
from torchsym.multiview.plane import consensus_plane
from torchsym.multiview.reconstruct import SparseModel, reconstruct
from torchsym.multiview.result import MultiviewPlaneResult
from torchsym.multiview.settings import MultiviewPlaneSettings
from torchsym.multiview.views import as_views

__all__ = ["MultiviewPlaneDetector", "detect_multiview_plane", "plane_of_model"]


def plane_of_model(model: SparseModel, settings: MultiviewPlaneSettings) -> MultiviewPlaneResult:
    """Steps 3-4 on a sparse model: pairs, the outlier loop, the consensus plane."""
    timings = dict(model.timings)
    notes: list[str] = []
    pts = model.points
    t0 = time.perf_counter()
    extent = float((pts.quantile(0.95, 0) - pts.quantile(0.05, 0)).norm()) if len(pts) > 1 else 0.0
    pairs = best_buddy_pairs(pts, model.descriptors, layout="opencv", min_chord=settings.pairs.min_chord * extent)
    timings["pairs"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    c = settings.consensus
    normal, offset = torch.zeros(3, dtype=pts.dtype), torch.zeros((), dtype=pts.dtype)
    inliers = torch.zeros(len(pairs), dtype=torch.bool)
    confidence, n_in = 0.0, 0
    if len(pairs) >= 2:
        res = consensus_plane(
            pts[pairs[:, 0]], pts[pairs[:, 1]], eps_d=c.eps_d, eps_theta=c.eps_theta, margin_angle=c.margin_angle, lam=c.lam
        )
        n_in = int(res.inliers.sum())
        confidence = n_in / max(res.runner_up, 1)
        normal, offset, inliers = res.normal, res.offset, res.inliers
    timings["plane"] = time.perf_counter() - t0
    found = n_in >= c.min_inliers and confidence >= c.min_margin
    if len(pairs) < 2:
        notes.append(f"no symmetry found: {len(pairs)} mirror pair(s) among {len(pts)} points")
    elif not found:
        notes.append(
            f"no symmetry found: the best plane has {n_in} inlier pairs, {confidence:.2f} times the best plane "
            f"{c.margin_angle:g} deg away (needs {c.min_inliers} pairs and {c.min_margin:g} times)"
        )
    if not found:
        normal, offset = torch.zeros_like(normal), torch.zeros_like(offset)
    return MultiviewPlaneResult(
        normal=normal,
        offset=offset,
        found=found,
        confidence=confidence,
        score=max(0.0, 1.0 - 1.0 / confidence) if confidence > 0 else 0.0,
        points=pts,
        colors=model.colors,
        pairs=pairs,
        inliers=inliers,
        cameras=model.cameras,
        n_photos=model.n_photos,
        notes=notes,
        timings=timings,
        reconstruction=model.reconstruction,
    )


def detect_multiview_plane(
    images: Any,
    settings: MultiviewPlaneSettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> MultiviewPlaneResult:
    """The 3D reflection plane of a scene from photos taken from several viewpoints
    (thesis Sec. 5.3).

    Args:
        images: a folder of photos, a list of photo paths, a list of ``(C, H, W)`` float
            tensors in [0, 1], or a ``(V, C, H, W)`` tensor; at least 2 photos.
        settings: :class:`MultiviewPlaneSettings` (or a mapping of them); defaults: the
            thesis's ``eps_d = 0.04`` and ``eps_theta = 1`` degree, photos at 1600 px.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits. COLMAP's
            seed is drawn from it.
        **overrides: settings by name (``consensus={"eps_theta": 2.0}`` or
            ``**{"consensus.eps_theta": 2.0}``).

    Returns:
        :class:`MultiviewPlaneResult`, with ``found=False`` and a note when the scene shows
        no symmetry.

    Raises:
        InputFileError: a photo cannot be read.
        InputShapeError, InputValueError: fewer than 2 photos, tensors of a wrong shape.
        SolverError: COLMAP registered no two photos.
    """
    views = as_views(images)
    settings = resolve_settings(MultiviewPlaneSettings, settings, overrides)
    seed = draw_seed(make_generator(generator)) % (2**31 - 1)
    t0 = time.perf_counter()
    model = reconstruct(views, settings.reconstruction, seed)
    result = plane_of_model(model, settings)
    result.timings["total"] = time.perf_counter() - t0
    return result


@register_solver("multiview_plane", kind="multiview", default=True)
class MultiviewPlaneDetector(Solver):
    """Hidden 3D reflection plane of a scene from several photos (thesis Sec. 5.3); see
    :func:`detect_multiview_plane`."""

    settings_class = MultiviewPlaneSettings

    def forward(self, images: Any, generator: torch.Generator | None = None) -> MultiviewPlaneResult:
        gen = generator if generator is not None else make_generator(self.settings.seed)
        return detect_multiview_plane(images, self.settings, generator=gen)
