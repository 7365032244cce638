"""Starts refined on the subsample, best first, until one is accepted (thesis Sec. 5.2.3, extended).

The thesis refines the one best cell of Algorithm 5. Here the cloud's principal axes are
tried first, then Algorithm 5's candidates in rank order; each start is pre-aligned
(:mod:`~torchsym.pointcloud.reflection_plane.prealign`) or run through Algorithm 6 on the
subsample, and the one with the highest support wins. See ``docs/design/reflection_plane.md``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

from torchsym.core.random import random_subset
from torchsym.geometry.reflection import reflect_points, spread_normals
from torchsym.matching.knn import KNNIndex
from torchsym.pointcloud.reflection_plane.alternation import alternate
from torchsym.pointcloud.reflection_plane.candidates import initial_normals, score_normals
from torchsym.pointcloud.reflection_plane.prealign import local_pca, pre_align, support
from torchsym.pointcloud.prepare import Subsample
from torchsym.pointcloud.reflection_plane.settings import ReflectionPlaneSettings, StartsSettings

__all__ = [
    "RefineContext",
    "align_start",
    "StartSearch",
    "candidate_starts",
    "is_dominant",
    "principal_axes",
    "refine_context",
    "same_plane",
    "search_starts",
]

Plane = tuple[torch.Tensor, torch.Tensor]


def principal_axes(centered: torch.Tensor, sample: torch.Tensor, index: KNNIndex, spacing: float) -> list[Plane]:
    """The principal axes of ``centered (K, 3)`` as planes, best first by the narrow kernel
    of Algorithm 5's scoring on ``sample``. For an exactly symmetric set the normal is one."""
    _, axes = torch.linalg.eigh(centered.T @ centered)
    axes = axes.T.to(torch.float64)  # (3, 3) one normal per row
    offs, (cost,) = score_normals(sample, index, axes, (2.0 * spacing,))
    return [(axes[k], offs[k]) for k in cost.argsort().tolist()]


def candidate_starts(sample: torch.Tensor, index: KNNIndex, spacing: float, settings: ReflectionPlaneSettings) -> list[Plane]:
    """Algorithm 5's candidates, best first, up to ``n_starts``, ``starts.min_separation`` apart."""
    cand, b_cand, order = initial_normals(sample, index, settings.init, spacing)
    chosen = spread_normals(cand, order, settings.n_starts, settings.starts.min_separation)
    return [(cand[k], b_cand[k]) for k in chosen]


def same_plane(points: torch.Tensor, a: Plane, b: Plane, tol: float) -> bool:
    """True when the mirror images of ``points (Q, 3)`` about planes ``a`` and ``b`` lie
    within ``tol`` of each other at the median: for the support's kernel the two are
    one plane."""
    return float((reflect_points(points, *a) - reflect_points(points, *b)).norm(dim=1).median()) < tol


def is_dominant(supports: list[float], settings: StartsSettings) -> bool:
    """True when, after at least ``dominance_after`` starts, the best support is
    ``dominance`` times the median and ``dominance_gap`` above it."""
    if len(supports) < settings.dominance_after:
        return False
    best, middle = max(supports), float(np.median(supports))
    return best >= settings.dominance * middle and best - middle >= settings.dominance_gap


@dataclasses.dataclass(frozen=True)
class RefineContext:
    """What every start is refined and judged against.

    Attributes:
        sub: ``(M, 3)`` the subsample; ``index`` over it.
        tol: the inlier tolerance on the subsample (normalised units).
        reference: the support a perfect symmetry would have on the subsample.
        normals: ``(M, 3)`` surface normals of ``sub`` (with pre-alignment), else None.
        eigenvalues: ``(M, 3)`` local PCA eigenvalues of ``sub`` (with pre-alignment), else None.
        queries: ``(Q, 3)`` the points pre-alignment reflects (up to 1,000 of ``sub``).
    """

    sub: torch.Tensor
    index: KNNIndex
    tol: float
    reference: float
    normals: torch.Tensor | None
    eigenvalues: torch.Tensor | None
    queries: torch.Tensor


def refine_context(
    xs: torch.Tensor, subs: Subsample, settings: ReflectionPlaneSettings, generator: torch.Generator
) -> RefineContext:
    """The tolerance, the acceptance reference and the pre-alignment's normals.

    The reference is the soft support, over the same kernel, of the distances from up to
    1,000 points left out of the subsample to it (or, for the whole cloud, from points
    to their nearest other point), at least ``starts.reference_floor``.
    """
    n, sub, index = xs.shape[0], subs.sub, subs.index
    tol = settings.inlier_factor * subs.spacing
    if subs.sub_idx is not None:
        left = torch.ones(n, dtype=torch.bool, device=xs.device)
        left[subs.sub_idx] = False
        left_idx = left.nonzero()[:, 0]
        d_ref, _ = index.query(xs[left_idx[random_subset(left_idx.numel(), 1000, generator)]])
    else:
        d_ref = index.query(sub[random_subset(n, 1000, generator)], k=2)[0][:, 1]
    reference = max(float(torch.exp(-0.5 * (d_ref / tol) ** 2).mean()), settings.starts.reference_floor)
    pca = local_pca(sub, index) if settings.prealign.enabled else None
    queries = sub[random_subset(sub.shape[0], 1000, generator)] if sub.shape[0] > 1000 else sub
    return RefineContext(
        sub, index, tol, reference, None if pca is None else pca[1][:, :, 0], None if pca is None else pca[0], queries
    )


@dataclasses.dataclass
class StartSearch:
    """The starts refined so far, updated in place by :func:`search_starts`.

    Attributes:
        best: ``(normal, offset, support, median residual)`` of the best start, or None.
        iterations: alignment steps of the best start.
        tried: starts refined.
        aligned: ``(support, normal, offset, steps)`` of every start refined.
        stop: why the list of starts ended: ``"accepted"`` (a start reached the acceptance
            level), ``"dominant"`` (one start clearly above the others), ``"confirmed"`` (a
            start aligned onto the best plane found from an earlier one) or ``"exhausted"``.
    """

    best: tuple[torch.Tensor, torch.Tensor, float, float] | None = None
    iterations: int = 0
    tried: int = 0
    stop: str = "exhausted"
    aligned: list[tuple[float, torch.Tensor, torch.Tensor, int]] = dataclasses.field(default_factory=list)

    def ranked(self, count: int) -> list[Plane]:
        """The ``count`` best-supported starts refined."""
        return [(nk, bk) for _, nk, bk, _ in sorted(self.aligned, key=lambda a: -a[0])[:count]]


def align_start(nk, bk, ctx: RefineContext, settings: ReflectionPlaneSettings):
    """One start ``(normal (3,), offset ())`` aligned on the subsample (pre-alignment, or
    Algorithm 6 without it): ``(normal, offset, support, median residual, steps)``."""
    if settings.prealign.enabled:
        raw = (nk, bk, *support(ctx.sub, ctx.index, nk, bk, ctx.tol))
        nk, bk, steps = pre_align(
            ctx.queries, ctx.sub, ctx.index, ctx.normals, nk, bk,
            max_iters=settings.prealign.max_iters, tol_angle=settings.prealign.tol_angle, tol_se=settings.tol_se,
        )
        frac, med = support(ctx.sub, ctx.index, nk, bk, ctx.tol)
        if (raw[2], -raw[3]) > (frac, -med):
            # the steps made it worse (an exact principal axis jittered on a subsample)
            nk, bk, frac, med = raw
    else:
        nk, bk, steps = alternate(ctx.sub, ctx.index, nk, bk, settings.alternation, tol_se=settings.tol_se)[:3]
        frac, med = support(ctx.sub, ctx.index, nk, bk, ctx.tol)
    return nk, bk, frac, med, steps


def _try_starts(starts: list[Plane], search: StartSearch, ctx: RefineContext, settings: ReflectionPlaneSettings) -> bool:
    """Refine ``starts`` in order into ``search``; True once one is accepted or dominates,
    or (``starts.confirm``) once a start aligns onto the best plane so far
    (:func:`same_plane` at the inlier tolerance)."""
    for nk, bk in starts:
        nk, bk, frac, med, steps = align_start(nk, bk, ctx, settings)
        search.aligned.append((frac, nk, bk, steps))
        confirmed = settings.starts.confirm and search.best is not None and same_plane(
            ctx.queries, (nk, bk), search.best[:2], ctx.tol
        )
        if search.best is None or (frac, -med) > (search.best[2], -search.best[3]):
            search.best = (nk, bk, frac, med)
            search.iterations = steps
        search.tried += 1
        if frac >= settings.starts.accept * ctx.reference:
            search.stop = "accepted"
            return True
        if is_dominant([a[0] for a in search.aligned], settings.starts):
            search.stop = "dominant"
            return True
        if confirmed:
            search.stop = "confirmed"
            return True
    return False


def _fallback(search: StartSearch, ctx: RefineContext, settings: ReflectionPlaneSettings) -> None:
    """Algorithm 6 on the subsample from each pre-aligned start, best supported first, for
    ``refine.fallback_max_iters`` steps, until one is accepted, dominates, or
    ``refine.fallback_patience`` starts in a row raised the best support by less than 0.005."""
    alt = settings.alternation
    since = 0
    refined: list[float] = []
    for _, nk, bk, it_k in sorted(search.aligned, key=lambda a: -a[0]):
        nk, bk, it_a = alternate(
            ctx.sub, ctx.index, nk, bk, alt,
            max_iters=settings.refine.fallback_max_iters, tol_angle=max(alt.tol_angle, settings.prealign.tol_angle),
            tol_se=settings.tol_se,
        )[:3]
        frac, med = support(ctx.sub, ctx.index, nk, bk, ctx.tol)
        refined.append(frac)
        since = 0 if frac > search.best[2] + 0.005 else since + 1
        if (frac, -med) > (search.best[2], -search.best[3]):
            search.best = (nk, bk, frac, med)
            search.iterations = it_k + it_a
        accepted = frac >= settings.starts.accept * ctx.reference
        if accepted or since >= settings.refine.fallback_patience or is_dominant(refined, settings.starts):
            break


def search_starts(
    axes: list[Plane], subs: Subsample, ctx: RefineContext, settings: ReflectionPlaneSettings
) -> StartSearch:
    """Refine the principal ``axes``, then (when none is accepted) Algorithm 5's candidates;
    when the pre-aligned starts left the choice open (none accepted, none dominant), run
    the Algorithm 6 fallback."""
    search = StartSearch()
    if not _try_starts(axes, search, ctx, settings):
        _try_starts(candidate_starts(subs.sample, subs.index, subs.spacing, settings), search, ctx, settings)
    if settings.prealign.enabled and search.stop == "exhausted":
        _fallback(search, ctx, settings)
    return search
