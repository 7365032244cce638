"""Reflection symmetry axes from boundary orientation and dominant cliques (thesis Sec. 2.3).

Pipeline (Algorithm 2):

1. Boundary curves and their segments (:mod:`torchsym.image.boundary`, Sec. 2.3.1).
2. Pairs of reflection-symmetric boundary pixels: ``p_i, p_j`` define the axis ``L_ij``
   (perpendicular bisector); reflecting segment ``b_i`` through ``L_ij`` must give the
   orientations of ``b_j`` (Eq. 2.9). For a chord at angle ``beta`` and tangent angles
   ``alpha`` (mod pi), the reflected tangent is ``2 beta - alpha``, so both terms of
   Eq. 2.9 equal ``mean_t |2 beta - alpha_i(t) - alpha_j(t')|`` (mod pi), with ``t'``
   running along ``b_j`` in the matching direction (both directions are tried). A pair
   is symmetric when the sum is below ``theta`` (thesis: 5 deg; default 8, see
   :func:`boundary_clique_axes`).
3. Graph ``G``: a vertex per pair, an edge when each pair's segments are symmetric about
   the other pair's axis (the same integral, < ``theta``) and, because that test only
   sees the axis *direction*, each pair's midpoint lies within ``axis_distance`` of the
   other's axis (Eq. 2.3).
4. Dominant clique = complement of a minimum vertex cover of the complement graph,
   by the LP relaxation of Eq. 2.11, solved exactly as a bipartite matching (König's
   theorem on the bipartite double cover, see :func:`dominant_clique`) and rounded at
   0.5; remove it and repeat for up to ``max_axes`` axes.
5. Axis of a clique: through the mean midpoint, perpendicular to the mean chord.
6. Score and extent (``score="gradient"``, not in the thesis): a dense check of each axis
   by its mirrored image gradients (:func:`torchsym.image.axes.axis_evidence`).
7. With ``sift_candidates`` (not in the thesis): the axes of mirrored-SIFT pairs (Sec.
   2.2.1) as further candidates, checked the same way; duplicates are kept once.

Candidate pairs and their cost. The thesis's Ch. 4.2.1 samples ``h`` random partners per
boundary pixel; here every pair of the ``N`` boundary samples is screened instead, in
``O(N^2)`` vectorised work on the centre tangents only (chunks of rows, no ``N x N``
matrix kept), and the survivors get the full ``O(S)`` test of Eq. 2.9 (``S`` samples per
segment). Pairs whose chord runs along both tangents (collinear segments, which fix no
axis position) are skipped. Graph construction is ``O(V^2 S)`` for ``V <= max_pairs``
pairs (a seeded random subset when more pass); the LP runs per connected component of
``G`` (isolated vertices, the outlier pairs of Sec. 2.3.2, form no clique) with one
constraint per complement edge.

``info["stage_seconds"]`` times each stage (``edges``, ``segments``, ``pairs`` (the
screening and Eq. 2.9 tests above), ``graph``, ``cliques``); the benchmark reports them.

When the rounded LP leaves no vertex (its optimum can be all one half), the clique is
grown greedily from the vertex of highest degree instead; the result's
``info["clique_fallbacks"]`` counts these and ``converged`` is then False.
"""

from __future__ import annotations

import math
import time

import numpy as np
import torch
from torch import nn

from torchsym.core.checks import check_image, check_in_range, check_int, check_positive
from torchsym.core.random import random_subset
from torchsym.core.registry import register_solver
from torchsym.core.results import on_input_device
from torchsym.errors import InputShapeError, InputValueError, SolverError
from torchsym.image.axes import (
    EDGE_NOISE,
    ReflectionAxesResult,
    axis_evidence,
    build_result,
    check_max_side,
    empty_result,
    gradient_noise,
    mirror_correlation,
    mirror_gradients,
    run_batched,
    suppress_duplicates,
)
from torchsym.image.boundary import BoundarySegments, boundary_curves, boundary_segments
from torchsym.image.ksymmetry import mirror_pair_candidates, mirror_sift_pairs

__all__ = [
    "BoundaryCliqueDetector",
    "boundary_clique_axes",
    "dominant_clique",
    "symmetric_boundary_pairs",
]


def _wrap(x: np.ndarray) -> np.ndarray:
    """Angles mod pi into [-pi/2, pi/2] (keeps float32 input in float32).

    ``x - pi * rint(x / pi)``: the same magnitudes as ``mod(x + pi/2, pi) - pi/2`` (only
    ``+-pi/2`` itself may come out with the other sign; every caller takes ``abs``), and
    ~5x faster than ``np.mod`` on the ``(V, V, S)`` array of the graph test.
    """
    pi = x.dtype.type(np.pi) if isinstance(x, np.ndarray) else np.pi
    return x - pi * np.rint(x / pi)


def symmetric_boundary_pairs(
    segments: BoundarySegments,
    *,
    theta: float = 5.0,
    min_distance: float = 24.0,
    max_shift: float = 3.0,
    collinear_angle: float = 15.0,
    chunk: int = 256,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pairs of reflection-symmetric boundary samples (Eq. 2.9 below ``theta`` degrees).

    Boundary samples lie every ``stride`` pixels, so the exact mirror of ``p_i`` usually
    falls between two samples of the other curve, and the chord angle ``beta`` enters
    Eq. 2.9 twice. Each candidate's second point is therefore slid along its curve's
    tangent by at most ``max_shift`` pixels to where the chord is perpendicular to the
    axis that the two centre tangents imply (``2 beta = alpha_i + alpha_j`` mod pi),
    and Eq. 2.9 is evaluated for that pixel pair.

    Args:
        segments: boundary samples and their segment orientations.
        theta: threshold in degrees on the sum of the two integrals of Eq. 2.9.
        min_distance: the least chord length in pixels.
        max_shift: the most a second point moves along its curve (the sample stride).
        collinear_angle: pairs whose chord is within this angle (degrees) of both centre
            tangents are skipped.
        chunk: rows screened at once.

    Returns:
        ``index (M, 2)`` int64 sample indices, ``second (M, 2)`` the refined second
        points, ``cost (M,)`` the Eq. 2.9 value in radians, ``sums (M, S)`` the matched
        tangent sums ``alpha_i(t) + alpha_j(t')``.
    """
    p, a = segments.points, segments.angles  # (N, 2), (N, S)
    n, s = a.shape
    th = math.radians(theta)
    a0 = a[:, s // 2]
    sin_col = math.sin(math.radians(collinear_angle))
    # screening without atan2 or mod: |wrap_pi(2 beta - a_i - a_j)| < slack  <=>
    # cos(4 beta - 2 (a_i + a_j)) > cos(2 slack), with 4 beta from the chord by double-angle formulas
    pf = p.astype(np.float32)
    c2, s2 = np.cos(2 * a0).astype(np.float32), np.sin(2 * a0).astype(np.float32)  # (N,)
    ct, st = np.cos(a0).astype(np.float32), np.sin(a0).astype(np.float32)
    found_i, found_j = [], []
    for i0 in range(0, n, chunk):
        i1 = min(n, i0 + chunk)
        cols = slice(i0 + 1, n)
        dx = pf[None, cols, 0] - pf[i0:i1, None, 0]  # (c, N - i0 - 1)
        dy = pf[None, cols, 1] - pf[i0:i1, None, 1]
        len2 = dx * dx + dy * dy
        ok = len2 >= min_distance**2
        ok &= np.triu(np.ones((i1 - i0, n - i0 - 1), dtype=bool))  # j > i
        inv = 1.0 / np.maximum(len2, 1e-12)
        c2b, s2b = (dx * dx - dy * dy) * inv, 2 * dx * dy * inv  # cos, sin of 2 beta
        c4b, s4b = c2b * c2b - s2b * s2b, 2 * c2b * s2b  # of 4 beta
        cs = c2[i0:i1, None] * c2[None, cols] - s2[i0:i1, None] * s2[None, cols]  # cos 2(a_i + a_j)
        ss = s2[i0:i1, None] * c2[None, cols] + c2[i0:i1, None] * s2[None, cols]
        slack = np.minimum(th + 2 * max_shift * np.sqrt(inv), np.pi / 2)  # atan(x) <= x: never too strict
        ok &= c4b * cs + s4b * ss > np.cos(2 * slack)
        lim = sin_col * np.sqrt(len2)
        ok &= (np.abs(dx * st[i0:i1, None] - dy * ct[i0:i1, None]) > lim) | (
            np.abs(dx * st[None, cols] - dy * ct[None, cols]) > lim
        )
        ii, jj = np.nonzero(ok)
        found_i.append(ii + i0)
        found_j.append(jj + i0 + 1)
    ii = np.concatenate(found_i) if found_i else np.zeros(0, dtype=np.int64)
    jj = np.concatenate(found_j) if found_j else np.zeros(0, dtype=np.int64)
    empty = (np.zeros((0, 2), dtype=np.int64), np.zeros((0, 2)), np.zeros(0), np.zeros((0, s)))
    if ii.size == 0:
        return empty
    d = p[jj] - p[ii]  # (M, 2)
    beta0 = np.arctan2(d[:, 1], d[:, 0])
    # the chord direction the centre tangents ask for, nearest the current chord
    half = 0.5 * (a0[ii] + a0[jj])
    target = half + np.pi / 2 * np.round((beta0 - half) / (np.pi / 2))
    u = np.stack([np.cos(target), np.sin(target)], 1)
    tau = np.stack([np.cos(a0[jj]), np.sin(a0[jj])], 1)
    cross_du = d[:, 0] * u[:, 1] - d[:, 1] * u[:, 0]
    cross_tu = tau[:, 0] * u[:, 1] - tau[:, 1] * u[:, 0]
    shift = -cross_du / np.where(np.abs(cross_tu) < 1e-9, np.inf, cross_tu)
    movable = np.abs(shift) <= max_shift
    second = p[jj] + np.where(movable, shift, 0.0)[:, None] * tau
    d = second - p[ii]
    length = np.hypot(d[:, 0], d[:, 1])
    beta = np.arctan2(d[:, 1], d[:, 0])[:, None]  # (M, 1)
    fwd = a[ii] + a[jj]  # (M, S)
    rev = a[ii] + a[jj][:, ::-1]
    e_f = 2 * np.abs(_wrap(2 * beta - fwd)).mean(1)  # both terms of Eq. 2.9 are equal
    e_r = 2 * np.abs(_wrap(2 * beta - rev)).mean(1)
    use_rev = e_r < e_f
    cost = np.where(use_rev, e_r, e_f)
    sums = np.where(use_rev[:, None], rev, fwd)
    keep = (cost < th) & (length >= min_distance)
    return np.stack([ii[keep], jj[keep]], 1).astype(np.int64), second[keep], cost[keep], sums[keep]


CLIQUE_SOLVERS = ("matching", "highs")
SCORES = ("gradient", "photometric", "support")


def _greedy_clique(adj: np.ndarray) -> np.ndarray:
    deg = adj.sum(1)
    order = np.argsort(-deg, kind="stable")
    clique = [int(order[0])]
    cand = adj[order[0]].copy()
    for v in order[1:]:
        if cand[v]:
            clique.append(int(v))
            cand &= adj[v]
    return np.asarray(sorted(clique), dtype=np.int64)


def _vertex_cover_lp_zeros(n: int, cu: np.ndarray, cv: np.ndarray) -> np.ndarray:
    """Vertices at 0 in a half-integral optimum of the vertex-cover LP of the graph ``(n, edges cu-cv)``.

    Nemhauser & Trotter (1975): with the bipartite double cover (left copy ``u_L``, right
    copy ``v_R``, an edge ``u_L - v_R`` and ``v_L - u_R`` per edge ``u - v``) and a minimum
    vertex cover ``C`` of it, ``x_v = |C & {v_L, v_R}| / 2`` is an optimal LP solution.
    ``C`` comes from a maximum matching by König's construction (left vertices not
    reachable by alternating paths from the free left vertices, right vertices reachable).
    """
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import breadth_first_order, maximum_bipartite_matching

    r, c = np.concatenate([cu, cv]), np.concatenate([cv, cu])
    b = csr_matrix((np.ones(r.size, dtype=np.int8), (r, c)), shape=(n, n))
    match = maximum_bipartite_matching(b, perm_type="column")  # right partner of each left vertex, -1: free
    matched, free = np.nonzero(match >= 0)[0], np.nonzero(match < 0)[0]
    # alternating paths: source 2n -> free left; left u -> right n + v (edges); right -> its matched left
    rows = np.concatenate([r, n + match[matched], np.full(free.size, 2 * n)])
    cols = np.concatenate([n + c, matched, free])
    g = csr_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(2 * n + 1, 2 * n + 1))
    reach = np.zeros(2 * n + 1, dtype=bool)
    reach[breadth_first_order(g, 2 * n, directed=True, return_predecessors=False)] = True
    return reach[:n] & ~reach[n : 2 * n]  # v_L and v_R both outside the cover: x_v = 0


def _vertex_cover_highs_zeros(n: int, cu: np.ndarray, cv: np.ndarray) -> np.ndarray:
    """Vertices below 0.5 in HiGHS's optimum of the vertex-cover LP (Eq. 2.11) of ``(n, edges cu-cv)``."""
    from scipy.optimize import linprog
    from scipy.sparse import coo_matrix

    m = cu.size
    rows = np.concatenate([np.arange(m), np.arange(m)])
    a_ub = coo_matrix((-np.ones(2 * m), (rows, np.concatenate([cu, cv]))), shape=(m, n)).tocsr()
    res = linprog(np.ones(n), A_ub=a_ub, b_ub=-np.ones(m), bounds=(0.0, 1.0), method="highs")
    if res.status != 0:
        raise SolverError(f"adj: HiGHS could not solve the vertex-cover LP of {n} vertices and {m} edges ({res.message})")
    return res.x < 0.5


def dominant_clique(adj: np.ndarray, solver: str = "matching") -> tuple[np.ndarray, bool]:
    """The dominant clique of a graph by the LP relaxation of minimum vertex cover (Eq. 2.11).

    ``min 1^T x`` s.t. ``x_u + x_v >= 1`` for every edge ``(u, v)`` of the complement
    graph, ``0 <= x <= 1``; vertices with ``x < 0.5`` form an independent set of the
    complement, i.e. a clique of the graph. Each connected component of the graph is
    solved on its own and the largest clique is returned.

    The LP is solved exactly through its half-integral optimum from a maximum bipartite
    matching (:func:`_vertex_cover_lp_zeros`) rather than with HiGHS
    (``scipy.optimize.linprog``), which this used before: on dense complement graphs
    (up to ~3e5 constraints for ``V = 800``) HiGHS took up to 3 s of a 640-px photograph's
    budget, the matching takes milliseconds. Both reach the same optimal value
    (``tests/image/test_boundary_cliques.py`` checks it against HiGHS), but the LP often
    has several optima and the two may round different ones: on the 32 dev photographs
    the first clique was the same size on 24 and smaller here on 8 (HiGHS returns a
    vertex of the polytope, which tends to have fewer halves); max F and the synthetic
    axes found were unchanged (``benchmarks/results/axes.md``).

    Args:
        adj: ``(V, V)`` bool symmetric adjacency, no self loops.
        solver: ``"matching"`` (the exact half-integral optimum above, default) or
            ``"highs"`` (the LP of Eq. 2.11 by ``scipy.optimize.linprog`` with HiGHS, as
            the thesis solves it with an LP solver).

    Returns:
        ``(clique indices, used_lp)``; ``used_lp`` is False when a component's rounded LP
        was empty (all one half) and the greedy clique was used.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if solver not in CLIQUE_SOLVERS:
        raise InputValueError(f"solver: expected one of {', '.join(map(repr, CLIQUE_SOLVERS))}, got {solver!r}")
    zeros = _vertex_cover_lp_zeros if solver == "matching" else _vertex_cover_highs_zeros
    v = adj.shape[0]
    if v == 0 or not adj.any():
        return np.zeros(0, dtype=np.int64), True
    n_comp, labels = connected_components(coo_matrix(adj), directed=False)
    best, used_lp = np.zeros(0, dtype=np.int64), True
    sizes = np.bincount(labels, minlength=n_comp)
    for comp in np.argsort(-sizes, kind="stable"):
        nodes = np.nonzero(labels == comp)[0]
        if nodes.size <= max(1, best.size):
            break  # no larger clique can come from a smaller component
        sub = adj[np.ix_(nodes, nodes)]
        cu, cv = np.nonzero(np.triu(~sub, k=1))  # complement edges
        if cu.size == 0:
            clique, lp_ok = np.arange(nodes.size), True
        else:
            clique = np.nonzero(zeros(nodes.size, cu, cv))[0]
            lp_ok = clique.size > 0
            if not lp_ok:
                clique = _greedy_clique(sub)
        if clique.size > best.size:
            best, used_lp = nodes[clique], lp_ok
    return best, used_lp


def _axis_of(pairs: np.ndarray) -> np.ndarray:
    """Line ``(a, b, c)`` through the mean midpoint, perpendicular to the mean chord."""
    chord = pairs[:, :2] - pairs[:, 2:]
    _, vecs = np.linalg.eigh(chord.T @ chord)
    sign = np.sign(chord @ vecs[:, -1])
    sign[sign == 0] = 1
    mean_chord = (chord * sign[:, None]).sum(0)
    normal = mean_chord / max(np.linalg.norm(mean_chord), 1e-12)
    mid = 0.5 * (pairs[:, :2] + pairs[:, 2:]).mean(0)
    return np.array([normal[0], normal[1], -normal @ mid])


def _check_settings(*, edges, sigma, low_threshold, high_threshold, segment_length, n_samples, stride, tangents,
                    smooth, max_samples, theta, axis_distance, max_pairs, max_axes, min_support,
                    clique_solver="matching", score="gradient", grow_threshold=0.3, sift_candidates=None,
                    sift_weight=0.5, num_features=1000, **_) -> None:
    """Raise :class:`InputValueError` naming the first bad setting of :func:`boundary_clique_axes`."""
    if edges not in ("canny", "edge_drawing"):
        raise InputValueError(f"edges: expected 'canny' or 'edge_drawing', got {edges!r}")
    if clique_solver not in CLIQUE_SOLVERS:
        raise InputValueError(f"clique_solver: expected one of {', '.join(map(repr, CLIQUE_SOLVERS))}, got {clique_solver!r}")
    if score not in SCORES:
        raise InputValueError(f"score: expected one of {', '.join(map(repr, SCORES))}, got {score!r}")
    if grow_threshold is not None:
        check_in_range(grow_threshold, "grow_threshold", -1.0, 1.0)
    if tangents not in ("gradient", "chain"):
        raise InputValueError(f"tangents: expected 'gradient' or 'chain', got {tangents!r}")
    for name, val in (("sigma", sigma), ("low_threshold", low_threshold), ("high_threshold", high_threshold),
                      ("segment_length", segment_length), ("stride", stride), ("theta", theta),
                      ("axis_distance", axis_distance), ("smooth", smooth)):
        check_positive(val, name)
    n_samples = check_int(n_samples, "n_samples", minimum=2)
    max_samples = check_int(max_samples, "max_samples", minimum=2)
    max_pairs = check_int(max_pairs, "max_pairs", minimum=2)
    max_axes = check_int(max_axes, "max_axes", minimum=1)
    min_support = check_int(min_support, "min_support", minimum=2)
    if sift_candidates is not None and not isinstance(sift_candidates, (bool, np.bool_)):
        raise InputValueError(f"sift_candidates: expected True, False or None, got {sift_candidates!r}")
    if sift_candidates is not None and bool(sift_candidates) and score != "gradient":
        raise InputValueError(f"sift_candidates: needs score='gradient' (its axes are ranked by their evidence), got score={score!r}")
    check_positive(sift_weight, "sift_weight")
    check_int(num_features, "num_features", minimum=1)


@on_input_device
def boundary_clique_axes(
    image: torch.Tensor,
    *,
    edges: str = "edge_drawing",
    sigma: float = 2.0,
    low_threshold: float = 0.015,
    high_threshold: float = 0.04,
    segment_length: float = 24.0,
    n_samples: int = 9,
    stride: float = 1.5,
    tangents: str = "gradient",
    smooth: float = 2.0,
    max_samples: int = 3000,
    theta: float = 8.0,
    axis_distance: float = 0.02,
    max_pairs: int = 800,
    max_axes: int = 5,
    min_support: int = 3,
    gather_support: bool = True,
    score: str = "gradient",
    grow_threshold: float | None = 0.3,
    clique_solver: str = "matching",
    sift_candidates: bool | None = None,
    sift_weight: float = 0.5,
    num_features: int = 1000,
    generator: torch.Generator | None = None,
) -> ReflectionAxesResult:
    """Reflection symmetry axes of one image by boundary orientation and dominant cliques (Sec. 2.3).

    Args:
        image: ``(C, H, W)`` or ``(1, C, H, W)`` float image in [0, 1], ``C`` in {1, 3}.
        edges: ``"edge_drawing"`` (OpenCV contrib Edge Drawing chains, default: it scored
            higher on the benchmark and links in milliseconds) or ``"canny"`` (kornia Canny,
            junction removal of Sec. 2.3.1, own linking); see :mod:`torchsym.image.boundary`.
        sigma: Gaussian smoothing of the edge detector and of the gradient that gives the
            boundary tangents, pixels (the ``"gradient"`` score smooths by its own 1.5,
            :func:`~torchsym.image.axes.mirror_gradients`).
        low_threshold: Canny's low gradient threshold (``edges="canny"``).
        high_threshold: Canny's high gradient threshold (``edges="canny"``).
        segment_length: ``q``, pixels of boundary around each boundary pixel.
        n_samples: orientation samples per segment.
        stride: arc length between boundary samples.
        tangents: ``"gradient"`` (boundary normals from the smoothed image gradient) or
            ``"chain"`` (differentiating the smoothed pixel chain).
        smooth: Gaussian smoothing of the pixel chain, pixels.
        max_samples: the most boundary samples (every k-th kept beyond).
        theta: threshold of Eq. 2.9 in degrees. The thesis uses 5 on UCM boundaries; on
            Edge Drawing chains with gradient normals true pairs are noisier, and at 5
            only 6 of 20 planted axes of the synthetic 2-3 object images were found
            against 16 of 20 at 8, the default.
        axis_distance: midpoint-to-axis tolerance for a graph edge, as a fraction of the
            image's longer side.
        max_pairs: the most pairs in the graph (a seeded random subset beyond).
        max_axes: ``k``, the most dominant cliques extracted.
        min_support: cliques with fewer pairs end the search.
        gather_support: after fitting a clique's axis, every symmetric pair (also those
            outside the sampled graph) whose segments are symmetric about it and whose
            midpoint is within ``axis_distance`` joins its support (extent and score).
        score: how axes are ranked.

            - ``"gradient"`` (default): ``symmetry * sqrt(area) * log(1 + n)`` from
              :func:`~torchsym.image.axes.axis_evidence`: how exactly the image gradients
              in the band around the axis are mirrored, times the size of that band (as a
              fraction of the image) and the log of the support ``n``. Axes through
              textured clutter collect many pairs but few mirrored gradients; small
              symmetric details are exact but cover little of the image. On the 32 dev
              photographs this and ``grow_threshold`` raised max F from 0.326 / 0.514
              (``"photometric"``, no growth) to 0.426 / 0.667 (thesis / challenge
              criterion, ``benchmarks/bench_axes.py``); on this small set one image moves
              max F by about 0.03, and small changes of the pipeline moved it by up to 0.05.
            - ``"photometric"``: the support times the normalised correlation of the
              image with its reflection over the support's bounding box.
            - ``"support"``: the number of supporting pairs, as the thesis ranks.

            With ``"gradient"`` or ``"photometric"``, a clique whose axis scores 0 (no
            mirrored gradients, or no positive correlation) is not reported; its pairs
            stay used, and ``info["axes_without_evidence"]`` counts these. On the 32 dev
            photographs 35 of 153 axes were such, and dropping them changed neither max F
            nor the synthetic axes found.
        grow_threshold: with ``score="gradient"``, each axis's segment (the extent of its
            supporting pairs) grows along the line while the mirrored-gradient symmetry
            stays above this on balance (:func:`~torchsym.image.axes.axis_evidence`);
            None keeps the supporting pairs' extent, as the thesis does. Four guards
            keep segments on their object (``axis_evidence``): gradients up to
            ``EDGE_NOISE`` (3) times the image's median gradient magnitude never count
            for the growth; pairs whose chord lies along the axis (points where an
            outline crosses the line, which Eq. 2.9 accepts) stretch the extent only in
            steps of at most ``0.1 max(H, W)``; a support is cut where the band crosses
            more than 4 empty bins (two objects on one line); and the SIFT candidates'
            segments are trimmed to the outermost edges that cross the line. Before
            them, 4 of 75 planted axes of the 30 synthetic benchmark images were missed
            with the right line and a segment up to 190 px too long; with them none (on
            fresh images: seeds 3000-3029, 75 of 75 against 69; seeds 2000-2019, 49 of
            50 against 46, the miss an object whose end barely differs from the
            background; seeds 4000-4029, 75 of 75 either way), and max F on the dev
            photographs stayed 0.426 / 0.704.
        clique_solver: how the LP of Eq. 2.11 is solved (:func:`dominant_clique`):
            ``"matching"`` (exact, milliseconds) or ``"highs"``.
        sift_candidates: add the axes of mirrored-SIFT pairs (Sec. 2.2.1, shared with
            :func:`~torchsym.image.ksymmetry.ksymmetry_axes`) as a second source of
            candidates (not in the thesis): candidates by greedy inlier counting
            (:func:`~torchsym.image.ksymmetry.mirror_pair_candidates` with its defaults: at
            least 4 pairs within 3 deg and ``0.01 max(H, W)``, runs split at gaps over
            ``0.1 max(H, W)``; ``k1`` chosen automatically, keypoints at least 5 px
            apart; ``min_support`` does not apply to them), checked by the same dense
            evidence as the cliques' axes and scored ``sift_weight`` times as much; an axis found by both sources is kept
            once (:func:`~torchsym.image.axes.suppress_duplicates`, 10 deg and
            ``axis_distance``). Boundary pairs need both sides of an object's outline
            found and mirrored over a ``segment_length`` arc; on textured objects against
            clutter Edge Drawing often traces texture contours instead, and small or flat
            objects then get no pair at all, while a handful of mirrored SIFT pairs still
            mark them. On the first 10 synthetic 2-3 object images of
            ``benchmarks/bench_axes.py`` this found 25 of 25 planted axes against 19 (on
            all 30: 71 of 75, 66 among the k best detections, k = objects, before the
            extent guards of ``grow_threshold``; 75 of 75, 70 among the k best, with
            them), and it raised
            max F on the 32 dev photographs from 0.426 / 0.667 to 0.426 / 0.704 (thesis /
            challenge criterion); the best axis was correct on 24 photographs instead
            of 19.
            Costs one SIFT pass (about 0.3 s of the 0.5 s it adds at 640 px). None (the
            default) uses them with ``score="gradient"`` only; True needs that score.
        sift_weight: factor on the score of axes from SIFT pairs. Descriptor matches
            include repeated texture that Eq. 2.9 never pairs; at 1 the dev max F fell
            to 0.375 / 0.667 (thesis / challenge criterion), at 0.3, 0.5 and 0.7 it was
            0.426 / 0.680, 0.704 and 0.706.
        num_features: the most SIFT keypoints (``sift_candidates``).
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        :class:`~torchsym.image.axes.ReflectionAxesResult`; scores as ``score`` says.

    Example:
        >>> from torchsym.image.synthetic import mirrored_objects_image
        >>> img, gt = mirrored_objects_image(1)
        >>> boundary_clique_axes(img).axes.shape[1]
        4
    """
    img = check_image(image, "image", min_size=16)
    if img.shape[0] != 1:
        raise InputShapeError(f"image: expected one image (C, H, W) or (1, C, H, W), got {tuple(img.shape)}")
    _check_settings(edges=edges, sigma=sigma, low_threshold=low_threshold, high_threshold=high_threshold,
                    segment_length=segment_length, n_samples=n_samples, stride=stride, tangents=tangents,
                    smooth=smooth, max_samples=max_samples, theta=theta, axis_distance=axis_distance,
                    max_pairs=max_pairs, max_axes=max_axes, min_support=min_support, clique_solver=clique_solver,
                    score=score, grow_threshold=grow_threshold, sift_candidates=sift_candidates,
                    sift_weight=sift_weight, num_features=num_features)
    sift_candidates = score == "gradient" if sift_candidates is None else bool(sift_candidates)
    h, w = int(img.shape[-2]), int(img.shape[-1])
    t0 = time.perf_counter()
    stages: dict[str, float] = {}
    curves, tangent = boundary_curves(img.cpu(), edges=edges, sigma=sigma, low_threshold=low_threshold,
                             high_threshold=high_threshold, min_length=int(segment_length))
    stages["edges"] = time.perf_counter() - t0
    segs = boundary_segments(curves, tangent if tangents == "gradient" else None, smooth=smooth, segment_length=segment_length, n_samples=n_samples, stride=stride)
    if len(segs) > max_samples:
        keep = np.arange(0, len(segs), int(math.ceil(len(segs) / max_samples)))
        segs = BoundarySegments(segs.points[keep], segs.angles[keep], segs.curve[keep])
    stages["segments"] = time.perf_counter() - t0 - stages["edges"]
    tic = time.perf_counter()
    index, second, _cost, full_sums = symmetric_boundary_pairs(segs, theta=theta, min_distance=segment_length, max_shift=stride)
    stages["pairs"] = time.perf_counter() - tic
    sums = full_sums
    n_found = int(index.shape[0])
    all_pairs = np.concatenate([segs.points[index[:, 0]], second], 1)  # (M, 4) every symmetric pair
    all_chord = all_pairs[:, 2:] - all_pairs[:, :2]
    all_beta = np.arctan2(all_chord[:, 1], all_chord[:, 0])
    all_mid = 0.5 * (all_pairs[:, :2] + all_pairs[:, 2:])
    graph = np.arange(n_found)
    if n_found > max_pairs:
        graph = random_subset(n_found, max_pairs, generator).numpy()
    info = dict(n_curves=len(curves), n_samples=len(segs), n_pairs_found=n_found, stage_seconds=stages)
    if graph.size < min_support and not sift_candidates:
        stages.update(graph=0.0, cliques=0.0)
        return empty_result(h, w, "boundary_cliques", pairs=torch.from_numpy(all_pairs).float(),
                            reason="too few symmetric boundary pairs", **info)
    tic = time.perf_counter()
    sums, beta, mid = sums[graph], all_beta[graph], all_mid[graph]  # (V, ...)
    normal = np.stack([np.cos(beta), np.sin(beta)], 1)
    off = -(normal * mid).sum(1)
    # T[i, j]: Eq. 2.9 integral of pair j's segments reflected through pair i's axis
    tcost = np.abs(_wrap(2 * beta.astype(np.float32)[:, None, None] - sums.astype(np.float32)[None, :, :])).mean(2)  # (V, V)
    dist = np.abs(mid @ normal.T + off[None, :]).T  # (V, V): |n_i . m_j + c_i|
    tol = axis_distance * max(h, w)
    th = math.radians(theta)
    adj = (tcost + tcost.T < th) & (dist < tol) & (dist.T < tol)
    np.fill_diagonal(adj, False)
    stages["graph"] = time.perf_counter() - tic
    tic = time.perf_counter()
    gray = img[0].float().mean(0).cpu().numpy()
    grads = mirror_gradients(gray) if score == "gradient" else None
    noise = EDGE_NOISE * gradient_noise(*grads) if grads is not None else 0.0
    full_sums32 = full_sums.astype(np.float32)
    free = np.ones(n_found, dtype=bool)  # pairs not yet supporting an axis
    lines, supports, scores, extents, fallbacks, evidence_free = [], [], [], [], 0, 0
    for _ in range(max_axes if graph.size >= min_support else 0):
        remaining = graph[free[graph]]
        pos = np.nonzero(free[graph])[0]
        clique, used_lp = dominant_clique(adj[np.ix_(pos, pos)], clique_solver)
        if clique.size < min_support:
            break
        fallbacks += int(not used_lp)
        line = _axis_of(all_pairs[remaining[clique]])
        # support: every free pair whose segments are symmetric about the fitted axis
        beta_axis = math.atan2(line[1], line[0])
        t_axis = np.abs(_wrap(np.float32(2 * beta_axis) - full_sums32)).mean(1)  # (M,)
        near = np.abs(all_mid @ line[:2] + line[2]) < tol
        members = remaining[clique]
        if gather_support:
            members = np.union1d(np.nonzero(free & near & (2 * t_axis < th))[0], members)
        free[members] = False
        extent = None
        if score == "gradient":
            ev = axis_evidence(*grads, line, all_pairs[members], min_half_width=segment_length / 3,
                               grow_threshold=grow_threshold, noise_level=noise)
            if ev.kept is not None:  # cut at empty background: the rest may support another axis
                kept = members[list(ev.kept)]
                free[np.setdiff1d(members, kept)] = True
                members = kept
            value = ev.score(members.size)
            extent = ev.extent
        elif score == "photometric":
            pts = all_pairs[members].reshape(-1, 2)
            value = float(members.size) * max(0.0, mirror_correlation(gray, line, pts))
        else:
            value = float(members.size)
        if value <= 0:  # the image is not mirrored about this clique's axis at all
            evidence_free += 1
            continue
        lines.append(torch.from_numpy(line))
        supports.append(torch.from_numpy(members))
        scores.append(value)
        if extent is not None:
            extents.append(extent)
    stages["cliques"] = time.perf_counter() - tic
    if sift_candidates:  # score == "gradient" (checked): every axis has an extent
        tic = time.perf_counter()
        sift_pairs = mirror_sift_pairs(img, num_features=num_features)[0].cpu().numpy()  # (P, 4)
        n_sift = 0
        for line, run in mirror_pair_candidates(sift_pairs, h, w):
            ev = axis_evidence(*grads, line, sift_pairs[run], min_half_width=segment_length / 3,
                               grow_threshold=grow_threshold, noise_level=noise, crossings=True)
            if ev.kept is not None:
                run = run[list(ev.kept)]
            value = sift_weight * ev.score(run.size)
            if value > 0:
                lines.append(torch.from_numpy(line))
                supports.append(torch.from_numpy(run + all_pairs.shape[0]))
                scores.append(value)
                extents.append(ev.extent)
                n_sift += 1
        all_pairs = np.concatenate([all_pairs, sift_pairs])
        keep = suppress_duplicates([ln.numpy() for ln in lines], extents, scores, distance=tol)  # best first
        info.update(n_sift_pairs=int(sift_pairs.shape[0]), sift_axes=n_sift, duplicates_dropped=len(lines) - len(keep))
        lines, supports, scores, extents = ([seq[k] for k in keep] for seq in (lines, supports, scores, extents))
        stages["sift"] = time.perf_counter() - tic
    info.update(clique_fallbacks=fallbacks, axes_without_evidence=evidence_free, seconds=time.perf_counter() - t0)
    if not lines:
        info["reason"] = "no axis with mirrored gradients" if n_found >= min_support or sift_candidates else "too few symmetric boundary pairs"
    return build_result(lines, supports, scores, torch.from_numpy(all_pairs), h, w, "boundary_cliques",
                        converged=fallbacks == 0, extents=extents or None, **info)


@register_solver("boundary_cliques", kind="image", default=True)
class BoundaryCliqueDetector(nn.Module):
    """Reflection axes by boundary orientation and dominant cliques (thesis Sec. 2.3).

    Module form of :func:`boundary_clique_axes`; see it for every setting. ``forward(image)``
    takes ``(C, H, W)`` or ``(B, C, H, W)`` float in [0, 1] and returns a
    :class:`~torchsym.image.axes.ReflectionAxesResult` (``B = 1``) or a
    :class:`~torchsym.image.axes.ReflectionAxesBatch`.

    ``max_side`` (default 640, None: off): the longest side the image is detected at
    (:func:`~torchsym.image.axes.run_batched`).
    """

    def __init__(
        self,
        *,
        edges: str = "edge_drawing",
        sigma: float = 2.0,
        low_threshold: float = 0.015,
        high_threshold: float = 0.04,
        segment_length: float = 24.0,
        n_samples: int = 9,
        stride: float = 1.5,
        tangents: str = "gradient",
        smooth: float = 2.0,
        max_samples: int = 3000,
        theta: float = 8.0,
        axis_distance: float = 0.02,
        max_pairs: int = 800,
        max_axes: int = 5,
        min_support: int = 3,
        gather_support: bool = True,
        score: str = "gradient",
        grow_threshold: float | None = 0.3,
        clique_solver: str = "matching",
        sift_candidates: bool | None = None,
        sift_weight: float = 0.5,
        num_features: int = 1000,
        max_side: int | None = 640,
        seed: int = 0,
    ) -> None:
        super().__init__()
        self.settings = dict(
            edges=edges, sigma=sigma, low_threshold=low_threshold, high_threshold=high_threshold,
            segment_length=segment_length, n_samples=n_samples, stride=stride, tangents=tangents, smooth=smooth,
            max_samples=max_samples, theta=theta, axis_distance=axis_distance, max_pairs=max_pairs,
            max_axes=max_axes, min_support=min_support, gather_support=bool(gather_support),
            score=score, grow_threshold=grow_threshold, clique_solver=clique_solver,
            sift_candidates=sift_candidates, sift_weight=sift_weight, num_features=num_features,
        )
        _check_settings(**self.settings)
        self.max_side = check_max_side(max_side)
        self.seed = check_int(seed, "seed", minimum=0)

    def extra_repr(self) -> str:
        return ", ".join(f"{k}={v}" for k, v in self.settings.items()) + f", max_side={self.max_side}, seed={self.seed}"

    def forward(self, image: torch.Tensor):
        g = torch.Generator().manual_seed(self.seed)
        return run_batched(boundary_clique_axes, image, {**self.settings, "generator": g}, max_side=self.max_side)
