"""Starting planes of PointSymm: the randomised pair search (thesis Sec. 7.2.4) and a scan.

:func:`pair_search` tests the thesis's two conditions (angle ``acos(|n_pi . n_qj|) <=
eps_theta``, distance ratio ``>= 1 - eps_d``) on the k-d tree neighbours of the reflected
``x_q`` rather than on random draws, verifies each candidate plane on a random subset by the
robust error ``mean min(r^2, h^2)``, polishes the best by trimmed ICP steps and returns the
robust median of the runs' planes. :func:`thesis_pair_search` is Sec. 7.2.4 word for word.
:func:`normal_scan` (an extension) scores planes through the centroid and needs no pair.
:func:`choose_starts` and :func:`initial_plane` turn these (or a caller's plane) into starts
of the alternation. Design notes: ``docs/design/pointsymm.md``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.core.checks import check_points
from torchsym.errors import InputValueError
from torchsym.geometry.reflection import plane_from_pairs, spread_normals
from torchsym.geometry.sampling import sphere_normals

__all__ = ["choose_starts", "initial_plane", "normal_scan", "pair_search", "scan_normals", "thesis_pair_search"]


def _bisector(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit normals ``(a - b)/|a - b|``, offsets ``n . (a + b)/2`` and midpoints of pairs."""
    diff = a - b
    length = np.linalg.norm(diff, axis=-1, keepdims=True)
    normal = diff / np.maximum(length, 1e-300)
    mid = 0.5 * (a + b)
    return normal, (normal * mid).sum(-1), mid


def _verify(normals: np.ndarray, mids: np.ndarray, sample: np.ndarray, tree: cKDTree, h2: float, approx: float = 0.0) -> np.ndarray:
    """Robust symmetry error ``mean min(r^2, h^2)`` of each candidate plane on ``sample``, ``(K,)``.

    ``approx > 0`` allows nearest neighbours up to ``1 + approx`` times too far (faster).
    """
    signed = sample[None, :, :] @ normals[:, :, None] - (normals * mids).sum(-1)[:, None, None]  # (K, m, 1)
    moved = sample[None] - 2.0 * signed * normals[:, None, :]  # (K, m, D)
    dist, _ = tree.query(moved.reshape(-1, sample.shape[1]), k=1, eps=approx, distance_upper_bound=2.0 * math.sqrt(h2))
    dist = np.minimum(dist, 2.0 * math.sqrt(h2))
    return np.minimum(dist.reshape(len(normals), -1) ** 2, h2).mean(1)


def _polish(normals, offsets, x, sample, tree, h2, steps):
    """A few trimmed ICP steps on ``sample`` for each candidate plane ``(K, D)``, ``(K,)``.

    Each step reflects the sample, takes every reflected point's nearest input point as its
    mirror (pairs farther than ``2h`` apart are dropped) and refits the plane to the pairs in
    closed form (the least-squares reflection of :func:`torchsym.geometry.plane_from_pairs`).
    """
    d = x.shape[1]
    for _ in range(steps):
        signed = sample @ normals.T - offsets  # (m, K)
        moved = sample[None] - 2.0 * signed.T[:, :, None] * normals[:, None, :]  # (K, m, D)
        dist, idx = tree.query(moved.reshape(-1, d), k=1)
        dist, idx = dist.reshape(len(normals), -1), idx.reshape(len(normals), -1)
        w = (dist * dist <= 4.0 * h2).astype(float)  # (K, m)
        y = x[idx]  # (K, m, D)
        wsum = w.sum(1)
        src = torch.from_numpy(np.ascontiguousarray(np.broadcast_to(sample, y.shape)))
        fit_n, fit_b = plane_from_pairs(src, torch.from_numpy(y), torch.from_numpy(w))  # n . x + b = 0
        new, new_off = fit_n.numpy(), -fit_b.numpy()  # here planes are n . x = c
        flip = np.where((new * normals).sum(-1) < 0, -1.0, 1.0)
        good = wsum > d
        normals = np.where(good[:, None], new * flip[:, None], normals)
        offsets = np.where(good, new_off * flip, offsets)
    return normals, offsets


def _one_run(x, p, q, tree, eps_theta, eps_d, n_look, sample, h2, max_candidates, rng, n_polish, polish_steps, polish_sample, n_screen=16, n_shortlist=128):
    """One run of the search from ``x_p, x_q``: ``(error, normal, point, passed)`` or None."""
    n = x.shape[0]
    others = np.setdiff1d(np.arange(n), [p, q])
    if others.size == 0:
        return None
    n_pi, c_pi, mid_pi = _bisector(x[p][None], x[others])  # (M, D), (M,), (M, D)
    s_q = (n_pi * x[q]).sum(-1) - c_pi  # signed distance of x_q to each plane pi_pi
    q_star = x[q] - 2.0 * s_q[:, None] * n_pi  # reflection of x_q through pi_pi
    k = min(n_look, n)
    gaps, js = tree.query(q_star, k=k)
    js, gaps = js.reshape(len(others), k), gaps.reshape(len(others), k)
    rows, cols, passed, miss = [], [], [], []
    for col in range(k):
        j = js[:, col]
        valid = np.nonzero((j != p) & (j != q))[0]
        n_qj, _, _ = _bisector(x[q][None], x[j[valid]])
        angle = np.arccos(np.clip(np.abs((n_pi[valid] * n_qj).sum(-1)), 0.0, 1.0))
        d_q = np.abs(s_q[valid])
        d_j = np.abs((n_pi[valid] * x[j[valid]]).sum(-1) - c_pi[valid])
        ratio = np.minimum(d_q, d_j) / np.maximum(np.maximum(d_q, d_j), 1e-300)
        rows.append(valid)
        cols.append(j[valid])
        miss.append(gaps[valid, col])
        passed.append((angle <= eps_theta) & (ratio >= 1.0 - eps_d))
    rows_a, js_a, ok = np.concatenate(rows), np.concatenate(cols), np.concatenate(passed)
    if rows_a.size > max_candidates:
        # half: the pairs whose x_j lies closest to the reflection of x_q; half: drawn at
        # random from the rest; and every pair that passed the tests
        near = np.argsort(np.concatenate(miss), kind="stable")
        rest = near[max_candidates // 2 :]
        keep = np.concatenate([near[: max_candidates // 2], rng.choice(rest, size=min(rest.size, max_candidates // 2), replace=False)])
        keep = np.union1d(keep, np.nonzero(ok)[0])
        rows_a, js_a, ok = rows_a[keep], js_a[keep], ok[keep]
    n_qj, _, mid_qj = _bisector(x[q][None], x[js_a])
    sign = np.where((n_pi[rows_a] * n_qj).sum(-1) < 0, -1.0, 1.0)[:, None]
    both = n_pi[rows_a] + sign * n_qj
    both = both / np.maximum(np.linalg.norm(both, axis=-1, keepdims=True), 1e-300)
    mids = 0.5 * (mid_pi[rows_a] + mid_qj)
    # Two-stage verification: every candidate on the first points of the subset, the best
    # ones (and those that passed the tests) on all of it.
    score = _verify(both, mids, sample[:n_screen], tree, h2, approx=0.5)
    if both.shape[0] > n_shortlist:
        short = np.union1d(np.argsort(score, kind="stable")[:n_shortlist], np.nonzero(ok)[0])
        score = np.full_like(score, np.inf)
        score[short] = _verify(both[short], mids[short], sample, tree, h2)
    else:
        score = _verify(both, mids, sample, tree, h2)
    order = np.argsort(score, kind="stable")[:n_polish]
    if ok.any():
        order = np.union1d(order, np.nonzero(ok)[0][np.argsort(score[ok], kind="stable")[:1]])
    normals, offsets = _polish(both[order], (both[order] * mids[order]).sum(-1), x, polish_sample, tree, h2, polish_steps)
    polished = _verify(normals, offsets[:, None] * normals, polish_sample, tree, h2)
    a = int(np.argmin(polished))
    if ok.any():
        # Prefer the pair that passed the thesis's tests unless another verifies far better.
        b = int(np.argmin(np.where(ok[order], polished, np.inf)))
        if polished[b] <= 2.0 * polished[a]:
            a = b
    return float(polished[a]), normals[a], offsets[a] * normals[a], bool(ok.any())


def pair_search(
    x: np.ndarray,
    rng: np.random.Generator,
    *,
    n_runs: int = 10,
    eps_theta: float = 2.0,
    eps_d: float = 0.05,
    n_look: int = 3,
    n_verify: int = 64,
    max_candidates: int = 1024,
    n_polish: int = 8,
    polish_steps: int = 4,
    tree: cKDTree | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """Initial plane for PointSymm from ``n_runs`` randomised pair searches (Sec. 7.2.4).

    Args:
        x: ``(N, D)`` points.
        rng: NumPy generator that draws ``x_p, x_q``.
        n_runs: runs (each finds two candidate mirror pairs and gives one plane).
        eps_theta: angle tolerance in degrees.
        eps_d: relative distance tolerance.
        n_look: points near each reflected ``x_q`` that are tested.
        n_verify: size of the random subset that verifies and polishes candidate planes.
        max_candidates: most candidate pairs verified per run: half those whose ``x_j`` is
            nearest to the reflection of ``x_q``, half drawn at random from the others (plus
            every pair that passed the tests).
        n_polish: best-verified candidates of each run that are polished by ICP steps.
        polish_steps: ICP steps of the polish.
        tree: a :class:`cKDTree` of ``x`` to reuse.

    Returns:
        ``normal (D,)`` unit and ``point (D,)`` on the plane: the robust median of the runs'
        planes (the start of the alternation); ``normals (K, D)`` and ``points (K, D)`` the
        runs' own planes; ``errors (K,)`` their robust symmetry errors on the verification
        subset; and ``found``, the number of runs in which some pair passed the thesis's two
        tests.
    """
    eps_theta = math.radians(eps_theta)
    n = x.shape[0]
    tree = cKDTree(x) if tree is None else tree
    nn_dist, _ = tree.query(x, k=min(2, n))
    spacing = float(np.median(nn_dist[:, -1])) if n > 1 else 1.0
    h2 = max(spacing, 1e-12) ** 2
    sample = x[np.sort(rng.choice(n, size=min(n, n_verify), replace=False))]
    normals: list[np.ndarray] = []
    mids: list[np.ndarray] = []
    errors: list[float] = []
    found = 0
    for _ in range(n_runs):
        p, q = (int(v) for v in rng.choice(n, size=2, replace=False))
        got = _one_run(x, p, q, tree, eps_theta, eps_d, n_look, sample, h2, max_candidates, rng, n_polish, polish_steps, sample)
        if got is None:  # only two points: the bisector of the pair
            nrm_pq, _, mid_pq = _bisector(x[p][None], x[q][None])
            normals.append(nrm_pq[0])
            mids.append(mid_pq[0])
            errors.append(0.0)
            continue
        errors.append(got[0])
        normals.append(got[1])
        mids.append(got[2])
        found += int(got[3])
    nrm = np.stack(normals)  # (K, D)
    mid = np.stack(mids)  # (K, D)
    # Median plane: the robust medoid normal (least total angle to the others, each angle
    # capped at ``tol``, signs ignored), then the componentwise medians of the normals and
    # midpoints that agree with it. A plain componentwise median is pulled away by the runs
    # whose x_p has no mirror.
    tol = max(2.0 * eps_theta, math.radians(5.0))
    cross = np.clip(np.linalg.norm(nrm[:, None, :] - (nrm @ nrm.T)[:, :, None] * nrm[None], axis=-1), 0.0, 1.0)
    angles = np.arcsin(cross)  # (K, K) accurate near 0, where arccos is not
    medoid = nrm[int(np.argmin(np.minimum(angles, tol).sum(1)))]
    agree = np.arcsin(np.clip(np.linalg.norm(nrm - (nrm @ medoid)[:, None] * medoid, axis=-1), 0.0, 1.0)) <= tol
    nrm = nrm * np.where(nrm @ medoid < 0, -1.0, 1.0)[:, None]
    normal = np.median(nrm[agree], axis=0)
    norm = np.linalg.norm(normal)
    normal = medoid if norm < 1e-12 else normal / norm
    point = np.median(mid[agree], axis=0)
    # The componentwise median of points on a plane need not lie on it: move it onto the
    # plane whose offset is the median of the midpoints' offsets.
    point = point - (point @ normal - np.median(mid[agree] @ normal)) * normal
    return normal, point, nrm, mid, np.asarray(errors), found


def thesis_pair_search(
    x: np.ndarray,
    rng: np.random.Generator,
    *,
    n_runs: int = 10,
    eps_theta: float = 2.0,
    eps_d: float = 0.05,
    chunk: int = 64,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    """The randomised pair search of Sec. 7.2.4 as the thesis states it.

    Each run draws ``x_p, x_q``; for each ``x_i`` (in random order) it draws ``x_j`` at random
    without replacement until the bisecting planes of ``(x_p, x_i)`` and ``(x_q, x_j)`` pass the
    two tests (angle ``<= eps_theta``, distance ratio ``>= 1 - eps_d``), and keeps the first
    such two pairs. Drawing ``j`` without replacement until a pass is the same as taking the
    first passing ``j`` of a random permutation, which is how it is computed here, ``chunk``
    values of ``i`` at a time. The angle test is the thesis's, on the signed normals
    ``(x_p - x_i) / |x_p - x_i|`` and ``(x_q - x_j) / |x_q - x_j|``: it passes true pairs
    only when ``x_p`` and ``x_q`` lie on the same side of the plane (our
    :func:`pair_search` compares ``|cos|``). The 2 pairs of each of the ``n_runs`` runs give 20 candidate
    planes (the bisectors of the pairs); the start is their median plane: the componentwise
    median of the normals, signs aligned with the normal nearest to the others, and the
    median of the pairs' midpoints as the point ``t``.

    Returns:
        ``normal (D,)``, ``point (D,)``, the candidate ``normals (K, D)`` and midpoints
        ``(K, D)`` (``K = 2 x`` the runs that found a pair), and the number of such runs.
        When no run finds a pair, the bisectors of the runs' ``(x_p, x_q)`` are used.
    """
    eps_theta = math.radians(eps_theta)
    n = x.shape[0]
    normals: list[np.ndarray] = []
    mids: list[np.ndarray] = []
    fallback: list[tuple[np.ndarray, np.ndarray]] = []
    found = 0
    for _ in range(n_runs):
        p, q = (int(v) for v in rng.choice(n, size=2, replace=False))
        nrm_pq, _, mid_pq = _bisector(x[p][None], x[q][None])
        fallback.append((nrm_pq[0], mid_pq[0]))
        others = np.setdiff1d(np.arange(n), [p, q])
        order_i = rng.permutation(others)
        order_j = rng.permutation(others)
        if others.size == 0:
            continue
        n_qj, _, mid_qj = _bisector(x[q][None], x[order_j])  # (M, D) in draw order
        hit = None
        for start in range(0, order_i.size, chunk):
            ii = order_i[start : start + chunk]
            n_pi, c_pi, mid_pi = _bisector(x[p][None], x[ii])  # (m, D)
            cos = n_pi @ n_qj.T  # (m, M), signed as in the thesis: cos^-1(n_pi^T n_qj) <= eps_theta
            d_q = np.abs(n_pi @ x[q] - c_pi)[:, None]  # (m, 1)
            d_j = np.abs(n_pi @ x[order_j].T - c_pi[:, None])  # (m, M)
            ratio = np.minimum(d_q, d_j) / np.maximum(np.maximum(d_q, d_j), 1e-300)
            ok = (np.arccos(np.clip(cos, -1.0, 1.0)) <= eps_theta) & (ratio >= 1.0 - eps_d)
            rows = np.nonzero(ok.any(1))[0]
            if rows.size:
                r = int(rows[0])
                c = int(np.argmax(ok[r]))
                hit = (n_pi[r], mid_pi[r], n_qj[c], mid_qj[c])
                break
        if hit is None:
            continue
        found += 1
        normals += [hit[0], hit[2]]
        mids += [hit[1], hit[3]]
    if not normals:
        normals = [f[0] for f in fallback]
        mids = [f[1] for f in fallback]
    nrm, mid = np.stack(normals), np.stack(mids)
    medoid = nrm[int(np.argmax(np.abs(nrm @ nrm.T).sum(1)))]
    nrm = nrm * np.where(nrm @ medoid < 0, -1.0, 1.0)[:, None]
    normal = np.median(nrm, axis=0)
    norm = np.linalg.norm(normal)
    normal = medoid if norm < 1e-12 else normal / norm
    return normal, np.median(mid, axis=0), nrm, mid, found


def scan_normals(d: int, count: int, rng: np.random.Generator) -> np.ndarray:
    """``(count, d)`` unit normals spread over the directions of hyperplanes in ``R^d``.

    ``d = 2``: ``count`` angles evenly in ``[0, pi)``; ``d = 3``: the Fibonacci lattice on
    the half sphere (:func:`torchsym.geometry.sphere_normals`); ``d >= 4``:
    Gaussian directions drawn from ``rng`` (no lattice covers high-dimensional spheres
    evenly at this count).
    """
    if d == 2:
        angle = np.pi * (np.arange(count) + 0.5) / count
        return np.stack([np.cos(angle), np.sin(angle)], axis=1)
    if d == 3:
        return sphere_normals(count).numpy()
    out = rng.standard_normal((count, d))
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def normal_scan(
    x: np.ndarray,
    tree: cKDTree,
    rng: np.random.Generator,
    *,
    n_normals: int = 200,
    n_keep: int = 4,
    keep_fraction: float = 1.0,
    n_sample: int = 1000,
    min_separation: float = 10.0,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Starting planes from a scan of hyperplanes through the centroid (an extension of Sec. 7.2.4).

    The candidates are the principal axes of ``x`` (the normal of a mirror-symmetric set is
    an eigenvector of its covariance) and ``n_normals`` directions of :func:`scan_normals`.
    Each is scored on ``n_sample`` points by the mean squared distance from a reflected
    point to its nearest input point over the ``keep_fraction`` share of smallest distances;
    planes that send most sampled points nearest to themselves (the trivial mirror of a set
    flat across them) are left out. The ``n_keep`` best, at least ``min_separation`` degrees
    apart, are returned.

    Args:
        x: ``(N, D)`` points.
        tree: :class:`cKDTree` of ``x``.
        rng: draws the scored sample (and the directions when ``D >= 4``).
        n_normals: directions scanned besides the ``D`` principal axes.
        n_keep: most planes returned.
        keep_fraction: share of the sample whose distances are averaged, in (0, 1].
        n_sample: points scored (all when fewer).
        min_separation: smallest angle between two returned normals, in degrees.

    Returns:
        ``(normal (D,), point (D,))`` pairs, best first.
    """
    n, d = x.shape
    centre = x.mean(axis=0)  # (D,)
    centred = x - centre
    _, axes = np.linalg.eigh(centred.T @ centred)  # (D, D) columns
    normals = np.concatenate([axes.T, scan_normals(d, n_normals, rng)])  # (K, D)
    rows = np.sort(rng.choice(n, size=min(n, n_sample), replace=False))  # (m,)
    sample = centred[rows]  # (m, D)
    moved = sample[None] - 2.0 * (sample @ normals.T).T[:, :, None] * normals[:, None, :]  # (K, m, D)
    dist, nearest = tree.query(moved.reshape(-1, d) + centre, k=1)
    to_self = (nearest.reshape(normals.shape[0], -1) == rows[None]).mean(axis=1)  # (K,)
    dist = np.sort(dist.reshape(normals.shape[0], -1) ** 2, axis=1)  # (K, m)
    cost = dist[:, : max(1, round(keep_fraction * dist.shape[1]))].mean(axis=1)  # (K,)
    cost[to_self > 0.5] = np.inf  # the trivial mirror of a flat set
    order = np.argsort(cost, kind="stable")
    order = order[np.isfinite(cost[order])]
    chosen = spread_normals(torch.from_numpy(normals), torch.from_numpy(order), n_keep, min_separation)
    return [(normals[k], centre.copy()) for k in chosen]


def choose_starts(
    normal0: np.ndarray, point0: np.ndarray, normals: np.ndarray, points: np.ndarray, errors: np.ndarray, n_starts: int
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The median plane, then the runs' planes by increasing error, skipping near-duplicates
    (within 5 degrees and 0.05 in offset); at most ``n_starts`` ``(normal (D,), point (D,))``."""
    chosen = [(normal0, point0)]
    for k in np.argsort(errors, kind="stable"):
        if len(chosen) >= n_starts:
            break
        nk, pk = normals[k], points[k]
        if all(abs(float(nk @ nc)) < math.cos(math.radians(5.0)) or abs(float(nk @ (pk - pc))) > 0.05 for nc, pc in chosen):
            chosen.append((nk, pk))
    return chosen


def initial_plane(initial: Any, mu: np.ndarray, radius: float, d: int) -> tuple[np.ndarray, np.ndarray]:
    """A caller's ``(normal (D,), offset ())`` as a unit normal and a point on the plane in the
    coordinates ``(x - mu) / radius``.

    Raises:
        InputShapeError, InputValueError: ``initial`` is not a finite plane of ``R^d``.
    """
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
