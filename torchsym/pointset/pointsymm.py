"""PointSymm: reflection symmetry of a point set in R^d (thesis Ch. 7, Algorithm 7)."""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
from typing import Any

import numpy as np
import torch
from scipy.spatial import cKDTree
from torch import nn

from torchsym.core.checks import check_in_range, check_int, check_points, check_positive
from torchsym.core.random import DEFAULT_SEED, make_generator, numpy_rng
from torchsym.core.registry import register_solver
from torchsym.core.results import Result
from torchsym.errors import InputValueError
from torchsym.optim import trust_region
from torchsym.pointset import transform as tf
from torchsym.pointset.assignment import mirror_assignment
from torchsym.pointset.initialization import (
    normal_scan,
    pair_search,
    thesis_pair_search,
)

__all__ = ["PointSymm", "PointSymmResult", "point_symm"]

logger = logging.getLogger(__name__)

_ASSIGNMENTS = ("auto", "exact", "sparse")

# The scan of extra starting planes is skipped when the best start already scores this
# much. The score is 1 for an exact symmetry; for the true plane of the sets of Sec. 7.4.2
# (n = 300, 3-D) it is 0.5 to 0.6 at sigma^2 = 1e-4 and 0.07 to 0.14 at 1e-3.
_SCAN_BELOW_SCORE = 0.5


@dataclasses.dataclass(frozen=True)
class PointSymmResult(Result):
    """The reflection symmetry of a point set found by :func:`point_symm`.

    Attributes:
        normal: ``(D,)`` unit normal of the symmetry hyperplane ``normal . x + offset = 0``,
            the null space of ``I + T E T^T`` (Theorem 7.2.3); largest component positive.
        offset: ``()`` offset of the hyperplane.
        rotations: ``(D-1, D, D)`` the plane rotations ``R_1 .. R_{D-1}`` of Eq. 7.1;
            ``R_u`` turns the coordinate plane ``(u-1, D-1)`` (0-based axes).
        translation: ``(D,)`` the translation ``t`` of Eq. 7.1, a point on the hyperplane.
        permutation: ``(N,)`` int64; ``permutation[i]`` is the index of the mirror of point
            ``i`` (``i`` itself for a point on the plane), -1 where ``i`` is unmatched.
        residuals: ``(N,)`` distance between the reflection of each point and its mirror
            (``inf`` where unmatched).
        score: symmetry score in [0, 1]: the mean over all points of
            ``exp(-(residual / h)^2 / 2)`` with ``h`` a quarter of the median distance between
            nearest neighbours (unmatched points count 0); 1 for a perfect symmetry.
        cost: the symmetry error of Eq. 7.5 over the matched points.
        iterations: alternations between the correspondences and (R, t) that were run.
        converged: True when the correspondences stopped changing before ``max_iter``.
        assignment: ``"exact"`` or ``"sparse"``, the correspondence solver that was used.
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


_INITS = ("search", "thesis")


def _check_settings(
    n_runs: Any,
    eps_theta: Any,
    eps_d: Any,
    max_iter: Any,
    match_fraction: Any,
    assignment: Any,
    n_neighbors: Any,
    exact_max_points: Any,
    n_starts: Any,
    init: Any = "search",
    n_scan: Any = 0,
    n_scan_starts: Any = 1,
) -> None:
    if init not in _INITS:
        raise InputValueError(f"init: expected one of {', '.join(map(repr, _INITS))}, got {init!r}")
    check_int(n_runs, "n_runs", minimum=1)
    check_in_range(eps_theta, "eps_theta", 0.0, 90.0)
    check_in_range(eps_d, "eps_d", 0.0, 1.0)
    check_int(max_iter, "max_iter", minimum=1)
    check_positive(match_fraction, "match_fraction")
    check_in_range(match_fraction, "match_fraction", 0.0, 1.0)
    if assignment not in _ASSIGNMENTS:
        raise InputValueError(f"assignment: expected one of {', '.join(map(repr, _ASSIGNMENTS))}, got {assignment!r}")
    check_int(n_neighbors, "n_neighbors", minimum=1)
    check_int(exact_max_points, "exact_max_points", minimum=2)
    check_int(n_starts, "n_starts", minimum=1)
    check_int(n_scan, "n_scan", minimum=0)
    check_int(n_scan_starts, "n_scan_starts", minimum=1)


def _cost(v, st):
    return tf.reflection_cost(v, st)


def _egrad(v, st):
    return tf.egrad(v, st)


def _ehess(v, u, st):
    return tf.ehess(v, u, st)


def _starts(normal0, point0, normals, points, errors, n_starts):
    """The median plane, then the runs' planes by increasing error, skipping near-duplicates."""
    chosen = [(normal0, point0)]
    for k in np.argsort(errors, kind="stable"):
        if len(chosen) >= n_starts:
            break
        nk, pk = normals[k], points[k]
        if all(abs(float(nk @ nc)) < math.cos(math.radians(5.0)) or abs(float(nk @ (pk - pc))) > 0.05 for nc, pc in chosen):
            chosen.append((nk, pk))
    return chosen


def _alternate(var, assign, manifold, x_t, max_iter):
    """Algorithm 7 from ``var``: alternate the assignment and the trust-region (R, t) step."""
    perm, dist2 = assign(var)
    converged, it = False, 0
    for it in range(1, max_iter + 1):
        matched = perm >= 0
        weights = torch.from_numpy(matched.astype(np.float64))
        mirrors = x_t[torch.from_numpy(np.where(matched, perm, 0))]
        st = tf.pair_statistics(x_t, mirrors, weights)
        res = trust_region(
            manifold,
            functools.partial(_cost, st=st),
            var,
            egrad=functools.partial(_egrad, st=st),
            ehess=functools.partial(_ehess, st=st),
            min_grad_norm=1e-10 * max(1.0, float(st.w)),
            max_iter=100,
        )
        var = res.x
        new_perm, dist2 = assign(var)
        logger.debug("PointSymm iteration %d: cost %.6g, %d correspondences changed", it, res.cost, int((new_perm != perm).sum()))
        if np.array_equal(new_perm, perm):
            converged = True
            break
        perm = new_perm
    return var, perm, dist2, it, converged


def _initial_plane(initial: Any, mu: np.ndarray, radius: float, d: int) -> tuple[np.ndarray, np.ndarray]:
    """The caller's ``(normal, offset)`` as a unit normal and a point on the plane, normalised."""
    if not isinstance(initial, (tuple, list)) or len(initial) != 2:
        raise InputValueError(f"initial: expected a (normal, offset) pair, got {type(initial).__name__}")
    normal = check_points(torch.as_tensor(initial[0]).reshape(1, -1), "initial[0]", dim=d, min_points=1)
    normal = normal.detach().to("cpu", torch.float64).numpy()[0]
    offset = torch.as_tensor(initial[1], dtype=torch.float64)
    if offset.numel() != 1 or not bool(torch.isfinite(offset).all()):
        raise InputValueError(f"initial[1]: expected a finite scalar offset, got shape {tuple(offset.shape)}")
    length = float(np.linalg.norm(normal))
    if length == 0.0:
        raise InputValueError("initial[0]: expected a non-zero normal, got the zero vector")
    normal, offset_n = normal / length, float(offset) / length
    point = -offset_n * normal  # on the plane, input coordinates
    return normal, (point - mu) / radius


def _reflect(x_np: np.ndarray, var) -> np.ndarray:
    *rots, t = var
    s = tf.reflection_from_rotations(rots).numpy()
    t = t.numpy()
    return (x_np - t) @ s.T + t


def _hull_basis(raw: np.ndarray, centred: np.ndarray, dtype: torch.dtype) -> np.ndarray | None:
    """``(D, r)`` orthonormal basis of the directions a centred set spans, ``r >= 2``, or None
    when it spans ``R^D`` (or ``D = 2``).

    A direction ``v`` counts when its singular value exceeds what rounding the input's
    coordinates to its dtype can put along it, ``4 eps |(|X| |v|)|`` (each coordinate
    rounded by at most ``eps |x| / 2``, margin 8): a thin but real extent is kept however
    many points there are and wherever the set lies, and a set that is flat up to the
    rounding of its coordinates (float32 data far from the origin) is reduced.
    ``centred`` must be centred twice (the mean's own rounding adds a direction).
    """
    n, d = centred.shape
    if d <= 2:
        return None
    _, sv, vt = np.linalg.svd(centred, full_matrices=False)
    noise = 4.0 * torch.finfo(dtype).eps * np.linalg.norm(np.abs(raw) @ np.abs(vt.T), axis=0)
    r = max(int((sv > noise).sum()), 2)
    return None if r >= d else vt[:r].T.copy()


def _lift(sub: PointSymmResult, basis: np.ndarray, mu: np.ndarray, dtype: torch.dtype, device: Any) -> PointSymmResult:
    """A result found in the hull coordinates ``y = basis^T (x - mu)`` as a result in ``R^D``."""
    normal = basis @ sub.normal.numpy()
    normal = normal / np.linalg.norm(normal)
    k = int(np.argmax(np.abs(normal)))
    normal = normal * (1.0 if normal[k] >= 0 else -1.0)
    translation = mu + basis @ sub.translation.numpy()
    rots = tf.rotations_from_normal(torch.from_numpy(normal))

    def out(a: Any) -> torch.Tensor:
        return torch.as_tensor(a, dtype=dtype, device=device)

    return dataclasses.replace(
        sub,
        normal=out(normal),
        offset=out(-float(normal @ translation)),
        rotations=out(torch.stack(rots)),
        translation=out(translation),
        permutation=sub.permutation.to(device),
        residuals=out(sub.residuals),
    )


def point_symm(
    points: Any,
    *,
    n_runs: int = 10,
    eps_theta: float = 2.0,
    eps_d: float = 0.05,
    max_iter: int = 50,
    match_fraction: float = 1.0,
    assignment: str = "auto",
    n_neighbors: int = 10,
    exact_max_points: int = 500,
    n_starts: int = 4,
    n_scan: int = 200,
    n_scan_starts: int = 4,
    init: str = "search",
    initial: tuple[Any, Any] | None = None,
    generator: torch.Generator | None = None,
) -> PointSymmResult:
    """Find the reflection symmetry hyperplane of a point set and the mirror of every point.

    Algorithm 7 of the thesis: minimise the symmetry error
    ``|T E T^T (X - t e^T) + t e^T - X P|_F^2`` (Eq. 7.5) over the correspondences ``P`` and the
    reflection ``(R_1, .., R_{D-1}, t)`` by alternating two exact steps until ``P`` stops
    changing:

    1. ``P`` for fixed ``(R, t)``: a linear assignment problem (Sec. 7.2.3, Claim 7.2.4),
       solved exactly by Jonker-Volgenant (:func:`scipy.optimize.linear_sum_assignment`)
       rather than the thesis's relaxed LP with Karmarkar's ``O(n^3.5)`` algorithm and
       rounding, which is slower and guaranteed only half the optimal objective. With ``assignment="auto"`` the dense
       exact solver is used for ``N <= exact_max_points`` and above that a sparse one in
       which each point may match one of the ``n_neighbors`` input points nearest to its
       reflection (:mod:`torchsym.pointset.assignment`), which makes ``N = 10,000`` take
       seconds. ``match_fraction < 1`` adds the cardinality limit ``e^T P e <= 2k``
       (Sec. 7.4.4) with ``2k = round(match_fraction N)``, for shapes with missing parts.
    2. ``(R, t)`` for fixed ``P``: the Riemannian trust-region method
       (:func:`torchsym.optim.trust_region`) on ``SO(2, D)^(D-1) x R^D`` (Sec. 7.2.2) with
       the analytic gradient of Eqs. 7.10-7.11 and its exact derivative as the Hessian
       (:mod:`torchsym.pointset.transform`), warm-started from the previous solution.
       Each evaluation costs ``O(D)`` products of ``D x D`` matrices, whatever ``N``: on
       noisy sets (``N = 300``, ``sigma^2 = 1e-3``, one thread) the whole solve took 0.8 /
       3.3 / 4.1 s at ``D = 10 / 20 / 30`` (1.1 / 12.1 / 32.1 s with the same results when
       each partial product of the rotations was composed afresh, ``O(D^3)`` products per
       Hessian step; scratch run).

    The start is the randomised pair search of Sec. 7.2.4
    (:func:`torchsym.pointset.initialization.pair_search`): ``n_runs`` runs, each finding two
    mirror pairs with the thesis's ``eps_theta`` / ``eps_d`` tests, the pair's plane verified
    and polished on a subset of the points, and the robust median of the runs' planes. Like
    the thesis's method it needs the noise to be small against the spacing of the points:
    on the sets of Sec. 7.4.2 (``n = 300``, 3-D) its start is usually wrong from
    ``sigma^2 = 3e-3`` on (the scan below then finds most of the planes that it misses). With ``n_starts > 1`` the
    alternation also runs from the best-verified planes of single runs that differ from
    the median (by more than 5 degrees or 0.05 in offset) and the run with the least
    symmetry error wins; when every run agrees (as without noise) there is only one start
    and no extra cost. When the best plane found
    so far still leaves most points without an exact mirror (score below 0.5: noise, or a
    wrong plane), ``n_scan`` more planes through the centroid and the principal axes are
    scored, and the alternation also runs from the ``n_scan_starts`` best of them
    (:func:`torchsym.pointset.initialization.normal_scan`, an extension): the pair search
    needs single pairs of points to agree within ``eps_theta``, which noise comparable to
    the point spacing defeats, while the scan needs no pair. The points are centred and
    scaled to unit RMS radius first, so the result moves with the input under rigid
    motions and scaling. The hyperplane is read off by Theorem 7.2.3: its
    normal spans the null space of ``I + T E T^T`` and it passes through ``t``.

    A set that spans only a proper affine subspace of ``R^D`` (``N <= D`` points, or flat
    data; rank at the input dtype's precision, at least 2 kept) is solved inside its affine
    hull, in coordinates of that subspace, and the plane lifted back with its normal in the
    hull (an extension: the thesis's sets fill their space). Any hyperplane that contains
    the whole set is a trivial mirror fixing every point; and in full coordinates the
    trust-region model is singular along the directions the set does not span, so its
    inner solver ran to its limit at every step: ``N = 64`` random points in ``D = 64`` (a
    grayscale image passed as points) took 244 s, 1.8 s in the hull; 50 points in
    ``D = 60`` 22.6 s, 0.2 s (scratch run).

    Args:
        points: ``(N, D)`` points, ``D >= 2``, ``N >= 2``.
        n_runs: runs of the randomised pair search (thesis: 10).
        eps_theta: angle tolerance of the pair search, in degrees. Sec. 7.2.4 names it
            without a value; 2 degrees is the value of Sec. 2.2.
        eps_d: relative distance tolerance of the pair search (0.05, as in Sec. 2.2).
        max_iter: largest number of alternations ("till convergence" in Algorithm 7).
        match_fraction: largest fraction of points that get a mirror (Sec. 7.4.4); 1 matches all.
        assignment: ``"auto"``, ``"exact"`` or ``"sparse"`` (see above).
        n_neighbors: candidate mirrors per point of the sparse assignment.
        exact_max_points: largest ``N`` solved by the exact assignment under ``"auto"``
            (four times as many with ``match_fraction < 1``). 500 (was 2,000): on noisy
            3-D sets of 500 to 2,000 points the sparse solver returned the same planes and
            scores, 2-5x faster at ``N >= 1,000`` (``N = 2,000``, ``sigma^2 = 1e-4``: 12 s
            instead of 64 s; ``N = 1,000``, ``1e-3``: 2.6 s instead of 5.7 s), and no
            slower without noise. With a cardinality limit the sparse solver only
            approximates it (keeping the cheapest matches of a full matching): on 891
            points of a cut set with ``match_fraction = 0.85`` it ended 1-89 deg off
            where the exact one ended 0.1 deg off, hence the larger limit there.
        n_starts: most starting planes (see above). The thesis starts once, from the median
            plane (``n_starts=1``); the default 4 makes the search far less likely to end in
            a wrong plane under noise (at ``sigma^2 = 1e-3``, 2 failures in 15 sets instead
            of 7 on the sets of ``benchmarks/bench_pointset.py``).
        n_scan: directions scanned for extra starts (see above; 0: no scan, the pair
            search alone). On the sets of ``benchmarks/bench_pointset.py`` (``n = 300``, 15
            seeds per level) the median normal error went from 0.39 to 0.30 deg at
            ``sigma^2 = 1e-3`` in 3-D (planes within 1 deg: 13 -> 15 of 15), from 40.0 to
            1.5 deg at ``3e-3`` (within 5 deg: 6 -> 15), from 13.0 to 11.1 deg at
            ``1e-2``; in 6-D from 75.7 to 4.6 deg at ``1e-2``. (In the latest run, on
            a rebuilt environment, the figures with the scan were the same and those
            without it 0.31, 58.6 and 28.3 deg, within 5 deg 14, 5 and 2 of 15: without
            the scan the wrong basins reached depend on rounding.) It costs about 0.1 to 0.3 s
            at ``n = 300`` in 3-D (0.6 to 0.8 s in 6-D), and nothing on exact symmetries.
            Beyond that noise (``sigma^2 >= 0.02``, the benchmark's curves) no start
            reaches the true plane, and more starts find more wrong planes of lower
            symmetry error: in 2-D the share within 5 deg fell from 0.33 to 0.22 at 0.02 (9
            sets).
        n_scan_starts: best-scoring scanned planes, at least 10 deg apart, from which the
            alternation also runs.
        init: ``"search"`` (the search above) or ``"thesis"``: Sec. 7.2.4 word for word
            (:func:`torchsym.pointset.initialization.thesis_pair_search`: the first two
            pairs of each run that pass the tests, the median of the 20 planes, one start;
            ``n_starts`` is then unused; the scan still runs unless ``n_scan = 0``).
        initial: ``(normal (D,), offset ())`` of a hyperplane ``normal . x + offset = 0`` to
            start the alternation from instead of the pair search (a warm start, e.g. from
            a previous frame or a learned predictor); None runs the search.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        :class:`PointSymmResult`, tensors in the input's dtype.

    Raises:
        InputShapeError: ``points`` is not ``(N, D)`` with ``D >= 2`` and ``N >= 2``.
        InputValueError: non-finite coordinates, all points equal, or a bad setting.

    Example:
        >>> x = torch.rand(20, 3, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
        >>> pts = torch.cat([x, x * torch.tensor([-1.0, 1.0, 1.0], dtype=torch.float64)])
        >>> res = point_symm(pts)
        >>> res.normal.abs().round(decimals=6).tolist(), res.score > 0.99
        ([1.0, 0.0, 0.0], True)
    """
    pts = check_points(points, "points", min_dim=2, min_points=2)
    _check_settings(
        n_runs, eps_theta, eps_d, max_iter, match_fraction, assignment, n_neighbors, exact_max_points, n_starts, init, n_scan, n_scan_starts
    )
    out_dtype, device = pts.dtype, pts.device
    x_raw = pts.detach().to("cpu", torch.float64).numpy()
    n, d = x_raw.shape
    mu = x_raw.mean(0)
    centred = x_raw - mu
    radius = math.sqrt(float((centred**2).sum(1).mean()))
    if radius == 0.0:
        raise InputValueError(f"points: expected at least two distinct points, got {n} copies of one point")
    basis = _hull_basis(x_raw, centred - centred.mean(0), pts.dtype)
    if basis is not None:
        # Every reflection of the set maps its affine hull onto itself: solve inside the hull
        # (exactly as any set given in those coordinates) and lift the plane back.
        sub_initial = None
        if initial is not None:
            n0, q0 = _initial_plane(initial, mu, 1.0, d)  # unit normal; q0 + mu lies on the plane
            if float(np.linalg.norm(basis.T @ n0)) < 10.0 * math.sqrt(torch.finfo(pts.dtype).eps):
                raise InputValueError(
                    "initial: expected a plane that cuts the set, got one whose normal is perpendicular to the "
                    "flat set's affine hull (a plane containing the whole set mirrors every point onto itself)"
                )
            sub_initial = (torch.from_numpy(basis.T @ n0), -float(n0 @ q0))
        sub = point_symm(
            torch.from_numpy(centred @ basis), n_runs=n_runs, eps_theta=eps_theta, eps_d=eps_d, max_iter=max_iter,
            match_fraction=match_fraction, assignment=assignment, n_neighbors=n_neighbors,
            exact_max_points=exact_max_points, n_starts=n_starts, n_scan=n_scan, n_scan_starts=n_scan_starts,
            init=init, initial=sub_initial, generator=generator,
        )
        return _lift(sub, basis, mu, out_dtype, device)
    xn = centred / radius  # (N, D) centred, unit RMS radius
    rng = numpy_rng(make_generator(generator))
    tree = cKDTree(xn)
    nn_dist, _ = tree.query(xn, k=2)
    spacing = np.median(nn_dist[:, 1])
    if spacing <= 0:
        positive = nn_dist[:, 1][nn_dist[:, 1] > 0]
        spacing = float(np.median(positive)) if positive.size else 1.0
    h = 0.25 * spacing  # the score's width, in the normalised units

    def score_of(perm: np.ndarray, dist2: np.ndarray) -> float:
        matched = perm >= 0
        return float(np.where(matched, np.exp(-0.5 * np.where(matched, dist2, 0.0) / h**2), 0.0).mean())

    # Initialisation (Sec. 7.2.4), or the caller's plane.
    if initial is None and init == "thesis":
        normal0, t0, _, _, found = thesis_pair_search(xn, rng, n_runs=n_runs, eps_theta=math.radians(eps_theta), eps_d=eps_d)
        logger.debug("thesis pair search: %d of %d runs found two pairs within the tolerances", found, n_runs)
        starts = [(normal0, t0)]
    elif initial is None:
        normal0, t0, run_normals, run_points, run_errors, found = pair_search(
            xn, rng, n_runs=n_runs, eps_theta=math.radians(eps_theta), eps_d=eps_d, tree=tree
        )
        logger.debug("pair search: %d of %d runs found a pair within the tolerances", found, n_runs)
        starts = _starts(normal0, t0, run_normals, run_points, run_errors, n_starts)
    else:
        starts = [_initial_plane(initial, mu, radius, d)]
    n_matches = None if match_fraction >= 1.0 else max(1, round(match_fraction * n))
    # the sparse solver applies the cardinality limit only approximately: exact up to 4x further
    exact_limit = exact_max_points if n_matches is None else 4 * exact_max_points
    method = assignment if assignment != "auto" else ("exact" if n <= exact_limit else "sparse")
    manifold = tf.rotation_manifold(d)
    x_t = torch.from_numpy(xn)

    def assign(v):
        return mirror_assignment(xn, _reflect(xn, v), n_matches=n_matches, method=method, n_neighbors=n_neighbors, tree=tree)

    best = None

    def run(start_normal: np.ndarray, start_point: np.ndarray) -> None:
        nonlocal best
        var = (*tf.rotations_from_normal(torch.from_numpy(start_normal)), torch.from_numpy(start_point).clone())
        var, perm, dist2, it, converged = _alternate(var, assign, manifold, x_t, max_iter)
        total = float(dist2[perm >= 0].sum())
        logger.debug("PointSymm start: cost %.6g after %d alternations", total, it)
        if best is None or total < best[0]:
            best = (total, var, perm, dist2, it, converged)

    for start_normal, start_point in starts:
        run(start_normal, start_point)
    keep = 1.0 if n_matches is None else n_matches / n
    # the score counts unmatched points as 0, so it is compared on the share that may match
    if initial is None and n_scan and score_of(best[2], best[3]) < _SCAN_BELOW_SCORE * keep:
        pair_search_best = best
        for start_normal, start_point in normal_scan(xn, tree, rng, n_normals=n_scan, n_keep=n_scan_starts, keep_fraction=keep):
            run(start_normal, start_point)
        if best is not pair_search_best and np.mean(best[2] == np.arange(n)) > 0.5:
            best = pair_search_best  # a scanned start ended in the trivial mirror of a flat set
    _, var, perm, dist2, it, converged = best

    # Read the plane off the rotations (Theorem 7.2.3) and undo the normalisation.
    *rots, t_n = var
    normal = tf.normal_from_rotations(rots).numpy()
    k = int(np.argmax(np.abs(normal)))
    normal = normal * (1.0 if normal[k] >= 0 else -1.0)
    translation = radius * t_n.numpy() + mu
    offset = -float(normal @ translation)
    matched = perm >= 0
    residuals = np.full(n, np.inf)
    residuals[matched] = np.sqrt(dist2[matched]) * radius
    score = score_of(perm, dist2)
    cost = float(dist2[matched].sum()) * radius * radius

    def out(a: np.ndarray) -> torch.Tensor:
        return torch.as_tensor(a, dtype=out_dtype, device=device)

    return PointSymmResult(
        normal=out(normal),
        offset=out(np.asarray(offset)),
        rotations=out(torch.stack(rots).numpy()),
        translation=out(translation),
        permutation=torch.as_tensor(perm, dtype=torch.int64, device=device),
        residuals=out(residuals),
        score=score,
        cost=cost,
        iterations=it,
        converged=converged,
        assignment=method,
    )


@register_solver("pointsymm", kind="points", default=True)
class PointSymm(nn.Module):
    """Reflection symmetry of a d-dimensional point set (thesis Ch. 7); module form of :func:`point_symm`.

    Settings are those of :func:`point_symm` with the thesis's defaults (Sec. 7.2.4: ten
    runs of the pair search; Algorithm 7 run until the correspondences stop changing) except
    ``n_starts`` and the scan ``n_scan`` / ``n_scan_starts`` (see :func:`point_symm`);
    ``seed`` seeds the generator used when ``forward`` is called without one. ``forward``
    takes ``points (N, D)`` (and optionally ``initial``, a starting plane) and returns a
    :class:`PointSymmResult`.
    """

    def __init__(
        self,
        *,
        n_runs: int = 10,
        eps_theta: float = 2.0,
        eps_d: float = 0.05,
        max_iter: int = 50,
        match_fraction: float = 1.0,
        assignment: str = "auto",
        n_neighbors: int = 10,
        exact_max_points: int = 500,
        n_starts: int = 4,
        n_scan: int = 200,
        n_scan_starts: int = 4,
        init: str = "search",
        seed: int = DEFAULT_SEED,
    ) -> None:
        super().__init__()
        _check_settings(
            n_runs, eps_theta, eps_d, max_iter, match_fraction, assignment, n_neighbors, exact_max_points, n_starts, init,
            n_scan, n_scan_starts,
        )
        self.init, self.n_scan, self.n_scan_starts = init, n_scan, n_scan_starts
        self.n_runs, self.eps_theta, self.eps_d, self.max_iter = n_runs, eps_theta, eps_d, max_iter
        self.match_fraction, self.assignment = match_fraction, assignment
        self.n_neighbors, self.exact_max_points, self.n_starts = n_neighbors, exact_max_points, n_starts
        self.seed = check_int(seed, "seed")

    def settings(self) -> dict[str, Any]:
        """The keyword settings passed to :func:`point_symm`."""
        return {
            "n_runs": self.n_runs,
            "eps_theta": self.eps_theta,
            "eps_d": self.eps_d,
            "max_iter": self.max_iter,
            "match_fraction": self.match_fraction,
            "assignment": self.assignment,
            "n_neighbors": self.n_neighbors,
            "exact_max_points": self.exact_max_points,
            "n_starts": self.n_starts,
            "n_scan": self.n_scan,
            "n_scan_starts": self.n_scan_starts,
            "init": self.init,
        }

    def forward(
        self, points: Any, generator: torch.Generator | None = None, initial: tuple[Any, Any] | None = None
    ) -> PointSymmResult:
        gen = make_generator(self.seed) if generator is None else generator
        return point_symm(points, generator=gen, initial=initial, **self.settings())

    def extra_repr(self) -> str:
        return ", ".join(f"{k}={v!r}" for k, v in {**self.settings(), "seed": self.seed}.items())
