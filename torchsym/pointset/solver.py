"""PointSymm: reflection symmetry of a point set in R^d (thesis Ch. 7, Algorithm 7)."""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.core.checks import check_points
from torchsym.core.random import make_generator, numpy_rng
from torchsym.core.registry import register_solver
from torchsym.core.results import Result
from torchsym.core.settings import Solver, resolve_settings
from torchsym.errors import InputShapeError, InputValueError
from torchsym.pointset import transform as tf
from torchsym.pointset.alternation import (
    Alternation, AlternationRun, assign, best_run, mirror_score, reflect_points, start_variables,
)
from torchsym.pointset.hull import hull_basis, lift_result
from torchsym.pointset.initialization import choose_starts, initial_plane, normal_scan, pair_search, thesis_pair_search
from torchsym.pointset.score import symmetry_score
from torchsym.pointset.settings import PointSymmSettings
from torchsym.pointset.soft_refinement import soft_refine_plane

__all__ = ["PointSymm", "PointSymmResult", "point_symm"]

logger = logging.getLogger(__name__)

# The scan of extra starting planes runs when the best start scores below this (1 for an
# exact symmetry; see docs/design/pointsymm.md).
_SCAN_BELOW_SCORE = 0.5


@dataclasses.dataclass(frozen=True)
class PointSymmResult(Result):
    """The reflection symmetry of a point set found by :func:`point_symm`.

    Attributes:
        normal: ``(D,)`` unit normal of the hyperplane ``normal . x + offset = 0``, the null
            space of ``I + T E T^T`` (Theorem 7.2.3); largest component positive.
        offset: ``()`` offset of the hyperplane.
        rotations: ``(D-1, D, D)`` the plane rotations ``R_1 .. R_{D-1}`` of Eq. 7.1;
            ``R_u`` turns the coordinate plane ``(u-1, D-1)`` (0-based axes).
        translation: ``(D,)`` the translation ``t`` of Eq. 7.1, a point on the hyperplane.
        permutation: ``(N,)`` int64, the index of the mirror of each point (itself on the
            plane), -1 where unmatched.
        residuals: ``(N,)`` distance from each reflected point to its mirror (``inf`` where
            unmatched).
        score: in [0, 1], calibrated against chance (:func:`~torchsym.pointset.score.symmetry_score`):
            ``q``, the mean over all points of ``max(0, 1 - residual / min(nn, moved))``
            (``nn`` the distance to the point's nearest other point, ``moved`` how far the
            reflection moves it, unmatched points 0), corrected by its mean ``q_0`` under
            random planes: ``max(0, (q - q_0) / (1 - q_0))``; 1 for an exact symmetry, near 0
            for random sets in any dimension.
        cost: the symmetry error of Eq. 7.5 over the matched points.
        iterations: alternations run from the winning start.
        converged: True when the correspondences stopped changing before ``max_iters``.
        assignment: ``"exact"`` or ``"sparse"``, the correspondence solver used.
    """

    normal: torch.Tensor
    offset: torch.Tensor
    rotations: torch.Tensor
    translation: torch.Tensor
    permutation: torch.Tensor
    residuals: torch.Tensor
    score: float
    cost: float
    iterations: int
    converged: bool
    assignment: str


def _check_size(pts: torch.Tensor, settings: PointSymmSettings) -> None:
    """``points`` within ``max_dim`` and ``max_points`` (typed errors naming the setting)."""
    n, d = pts.shape
    if d > settings.max_dim:
        hint = f"; with N < D it may be transposed: pass points.T, shape ({d}, {n})" if n < d else ""
        raise InputShapeError(
            f"points: expected (N, D) with D <= max_dim = {settings.max_dim}, got ({n}, {d}){hint}"
        )
    if n > settings.max_points:
        raise InputShapeError(
            f"points: expected N <= max_points = {settings.max_points}, got ({n}, {d}); "
            "subsample the set (thesis Sec. 7.4.4 samples about 600 points) or raise max_points"
        )


def _solve_in_hull(
    pts: torch.Tensor, x_raw: np.ndarray, mu: np.ndarray, basis: np.ndarray, settings: PointSymmSettings,
    initial: Any, generator: torch.Generator | None,
) -> PointSymmResult:
    """PointSymm in the coordinates of the set's affine hull, the plane lifted back to ``R^D``."""
    centred = x_raw - mu
    sub_initial = None
    if initial is not None:
        n0, q0 = initial_plane(initial, mu, 1.0, x_raw.shape[1])  # unit normal; q0 + mu lies on the plane
        if float(np.linalg.norm(basis.T @ n0)) < 10.0 * math.sqrt(torch.finfo(pts.dtype).eps):
            raise InputValueError(
                "initial: expected a plane that cuts the set, got one whose normal is perpendicular to the "
                "flat set's affine hull (a plane containing the whole set mirrors every point onto itself)"
            )
        sub_initial = (torch.from_numpy(basis.T @ n0), -float(n0 @ q0))
    sub = point_symm(torch.from_numpy(centred @ basis), settings, initial=sub_initial, generator=generator)
    return lift_result(sub, basis, mu, pts.dtype, pts.device)


def _score_width(xn: np.ndarray, tree: cKDTree) -> float:
    """``h`` of the scan's trigger: a quarter of the median nearest-neighbour distance."""
    nn_dist, _ = tree.query(xn, k=2)
    spacing = np.median(nn_dist[:, 1])
    if spacing <= 0:
        positive = nn_dist[:, 1][nn_dist[:, 1] > 0]
        spacing = float(np.median(positive)) if positive.size else 1.0
    return 0.25 * spacing


def _starts(xn, tree, rng, settings: PointSymmSettings, initial, mu, radius) -> list[tuple[np.ndarray, np.ndarray]]:
    """Step 1: the starting planes, from the pair search (Sec. 7.2.4) or the caller's plane."""
    init = settings.init
    if initial is not None:
        return [initial_plane(initial, mu, radius, xn.shape[1])]
    if init.method == "thesis":
        normal0, t0, _, _, found = thesis_pair_search(xn, rng, n_runs=init.n_runs, eps_theta=init.eps_theta, eps_d=init.eps_d)
        logger.debug("thesis pair search: %d of %d runs found two pairs within the tolerances", found, init.n_runs)
        return [(normal0, t0)]
    normal0, t0, run_normals, run_points, run_errors, found = pair_search(
        xn, rng, n_runs=init.n_runs, eps_theta=init.eps_theta, eps_d=init.eps_d, tree=tree
    )
    logger.debug("pair search: %d of %d runs found a pair within the tolerances", found, init.n_runs)
    return choose_starts(normal0, t0, run_normals, run_points, run_errors, init.n_starts)


def _problem(xn: np.ndarray, tree: cKDTree, settings: PointSymmSettings) -> Alternation:
    """The alternation's fixed data; ``"auto"`` picks the exact assignment up to
    ``max_exact_points`` (4x that with a cardinality limit, which the sparse one only approximates)."""
    n, d = xn.shape
    a = settings.assignment
    n_matches = None if settings.match_fraction >= 1.0 else max(1, round(settings.match_fraction * n))
    exact_limit = a.max_exact_points if n_matches is None else 4 * a.max_exact_points
    method = a.method if a.method != "auto" else ("exact" if n <= exact_limit else "sparse")
    return Alternation(
        points=xn, points_t=torch.from_numpy(xn), tree=tree, manifold=tf.rotation_manifold(d), method=method,
        n_matches=n_matches, n_neighbors=a.n_neighbors, max_iters=settings.max_iters,
        closed_form=d > settings.max_trust_region_dim,
    )


def _rescan(problem: Alternation, best: AlternationRun, rng, settings: PointSymmSettings, h: float) -> AlternationRun:
    """Extra starts from :func:`normal_scan` when the best plane still leaves most points
    without an exact mirror (an extension of Sec. 7.2.4)."""
    n = problem.points.shape[0]
    keep = 1.0 if problem.n_matches is None else problem.n_matches / n
    # the score counts unmatched points as 0, so it is compared on the share that may match
    if mirror_score(best.perm, best.dist2, h) >= _SCAN_BELOW_SCORE * keep:
        return best
    scan = settings.scan
    starts = normal_scan(problem.points, problem.tree, rng, n_normals=scan.n_normals, n_keep=scan.n_starts, keep_fraction=keep)
    scanned = best_run(problem, starts, best)
    if scanned is not best and np.mean(scanned.perm == np.arange(n)) > 0.5:
        return best  # a scanned start ended in the trivial mirror of a flat set
    return scanned


def _soften(problem: Alternation, best: AlternationRun, settings: PointSymmSettings) -> AlternationRun:
    """The winning plane refined on soft correspondences (:func:`soft_refine_plane`), and the
    hard correspondences of the refined plane."""
    soft = settings.soft
    matched = best.perm >= 0
    if not soft.enabled or problem.n_matches is not None or not matched.any():
        return best
    d = problem.points.shape[1]
    s2 = float(best.dist2[matched].mean()) / d
    *rots, t = best.var
    normal = tf.normal_from_rotations(rots).numpy()
    refined = soft_refine_plane(
        problem.points, normal, -float(normal @ t.numpy()), s2, tree=problem.tree,
        n_neighbors=soft.n_neighbors, max_iters=soft.max_iters, tol_se=soft.tol_se,
    )
    if refined.iterations == 0:
        return best
    var = start_variables(refined.normal, -refined.offset * refined.normal)
    perm, dist2 = assign(problem, var)
    return AlternationRun(float(dist2[perm >= 0].sum()), var, perm, dist2, best.iterations, best.converged)


def _result(problem: Alternation, best: AlternationRun, mu, radius, rng, dtype: torch.dtype, device) -> PointSymmResult:
    """Step 4's output: the plane read off the rotations (Theorem 7.2.3), in input coordinates."""
    *rots, t_n = best.var
    normal = tf.normal_from_rotations(rots).numpy()
    k = int(np.argmax(np.abs(normal)))
    normal = normal * (1.0 if normal[k] >= 0 else -1.0)
    translation = radius * t_n.numpy() + mu
    offset = -float(normal @ translation)
    perm, dist2 = best.perm, best.dist2
    matched = perm >= 0
    residuals = np.full(perm.shape[0], np.inf)
    residuals[matched] = np.sqrt(dist2[matched]) * radius

    def out(a: np.ndarray) -> torch.Tensor:
        return torch.as_tensor(a, dtype=dtype, device=device)

    return PointSymmResult(
        normal=out(normal),
        offset=out(np.asarray(offset)),
        rotations=out(torch.stack(rots).numpy()),
        translation=out(translation),
        permutation=torch.as_tensor(perm, dtype=torch.int64, device=device),
        residuals=out(residuals),
        score=symmetry_score(problem.points, reflect_points(problem.points, best.var), perm, rng, tree=problem.tree),
        cost=float(dist2[matched].sum()) * radius * radius,
        iterations=best.iterations,
        converged=best.converged,
        assignment=problem.method,
    )


def point_symm(
    points: Any,
    settings: PointSymmSettings | Mapping[str, Any] | None = None,
    *,
    initial: tuple[Any, Any] | None = None,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> PointSymmResult:
    """The reflection symmetry hyperplane of a point set and the mirror of every point.

    Algorithm 7 (thesis Sec. 7.2) on the points centred and scaled to unit RMS radius:
    1. starting planes from the randomised pair search (Sec. 7.2.4), or ``initial``;
    2. the correspondences ``P`` for a fixed reflection, an exact linear assignment (Sec. 7.2.3);
    3. ``(R, t)`` for fixed ``P`` by the Riemannian trust region on ``SO(2, D)^(D-1) x R^D``
       (Sec. 7.2.2);
    4. steps 2-3 until ``P`` stops changing; the plane by Theorem 7.2.3.
    Extensions (``docs/design/pointsymm.md``): several starts, a scan of planes through the
    centroid when the best plane scores below 0.5, the plane refined on soft correspondences
    (EM, ``soft``), and flat sets solved in their affine hull.

    Args:
        points: ``(N, D)`` points, ``2 <= D <= max_dim``, ``2 <= N <= max_points``.
        settings: :class:`~torchsym.pointset.PointSymmSettings`, a mapping, or None for the
            defaults; ``**overrides`` replace single settings (``max_iters=20``,
            ``scan={"enabled": False}``).
        initial: ``(normal (D,), offset ())`` of a plane ``normal . x + offset = 0`` to start
            from instead of the pair search (a warm start); None runs the search.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        :class:`PointSymmResult`, tensors in the input's dtype and on its device.

    Raises:
        InputShapeError: ``points`` is not ``(N, D)`` within those bounds.
        InputValueError: non-finite coordinates, all points equal, or a bad ``initial``.
        ConfigError: a bad setting.

    Example:
        >>> x = torch.rand(20, 3, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
        >>> pts = torch.cat([x, x * torch.tensor([-1.0, 1.0, 1.0], dtype=torch.float64)])
        >>> res = point_symm(pts)
        >>> res.normal.abs().round(decimals=6).tolist(), res.score > 0.99
        ([1.0, 0.0, 0.0], True)
    """
    pts = check_points(points, "points", min_dim=2, min_points=2)
    settings = resolve_settings(PointSymmSettings, settings, overrides)
    _check_size(pts, settings)
    x_raw = pts.detach().to("cpu", torch.float64).numpy()
    n = x_raw.shape[0]
    mu = x_raw.mean(0)
    centred = x_raw - mu
    radius = math.sqrt(float((centred**2).sum(1).mean()))
    if radius == 0.0:
        raise InputValueError(f"points: expected at least two distinct points, got {n} copies of one point")
    basis = hull_basis(x_raw, centred - centred.mean(0), pts.dtype)
    if basis is not None:
        return _solve_in_hull(pts, x_raw, mu, basis, settings, initial, generator)
    xn = centred / radius  # (N, D) centred, unit RMS radius
    rng = numpy_rng(make_generator(generator))
    tree = cKDTree(xn)
    h = _score_width(xn, tree)
    starts = _starts(xn, tree, rng, settings, initial, mu, radius)  # step 1
    problem = _problem(xn, tree, settings)
    best = best_run(problem, starts)  # steps 2-4 from each start
    if initial is None and settings.scan.enabled:
        best = _rescan(problem, best, rng, settings, h)
    best = _soften(problem, best, settings)
    return _result(problem, best, mu, radius, rng, pts.dtype, pts.device)


@register_solver("pointsymm", kind="points", default=True)
class PointSymm(Solver):
    """Reflection symmetry of a d-dimensional point set (thesis Ch. 7); module form of :func:`point_symm`.

    ``forward(points (N, D), generator=None, *, initial=None)`` returns a :class:`PointSymmResult`.
    """

    settings_class = PointSymmSettings

    def forward(
        self, points: Any, generator: torch.Generator | None = None, *, initial: tuple[Any, Any] | None = None
    ) -> PointSymmResult:
        gen = generator if generator is not None else make_generator(self.settings.seed)
        return point_symm(points, self.settings, initial=initial, generator=gen)
