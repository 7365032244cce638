"""Steps 4-8 and the map of step 10: the hypotheses of the symmetry.

The thesis's (Sec. 6.2.4-6.2.7): sparse pairs of feature points, the signs of the
eigenfunctions from geodesics between them (``C = diag(s)``), the correction ``R`` and the
dense map. Extensions: the pairs on HKS alone, both signs of the least-confident
eigenfunctions, an orientation-reversing functional map fitted to the dense HKS, and the
vertices' mirror plane.
"""

from __future__ import annotations

import time

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.core.parallel import thread_budget
from torchsym.core.random import random_subset
from torchsym.mesh import fmaps
from torchsym.mesh.correction import correct_eigenfunctions
from torchsym.mesh.fmaps import consistency, map_consistency, pointwise_to_functional
from torchsym.mesh.geodesic import geodesic_distances
from torchsym.mesh.intrinsic.sample import sign_sample
from torchsym.mesh.intrinsic.settings import IntrinsicSymmetrySettings
from torchsym.mesh.intrinsic.workspace import Candidate, Workspace
from torchsym.mesh.nearest import Nearest, kdtree
from torchsym.mesh.orientation import orientation_reversing_map
from torchsym.mesh.pairs import eigenfunction_signs, symmetric_pairs
from torchsym.pointcloud.reflection_plane import detect_reflection_plane

__all__ = [
    "HYPOTHESIS_TEXT",
    "extrinsic_candidate",
    "first_image",
    "orientation_candidate",
    "pair_features",
    "pairing_candidates",
    "sign_basis_candidates",
    "sign_basis_image",
    "sign_hypotheses",
]

HYPOTHESIS_TEXT = {
    "pairs": "thesis's pairs",
    "hks_pairs": "pairs on HKS alone (pairs.spectral_weight 0)",
    "orientation": "orientation-reversing functional map",
    "signs": "signs of the first eigenfunctions (hypotheses.sign_basis)",
    "extrinsic": "extrinsic reflection plane of the vertices",
}


def first_image(ws: Workspace, cand: Candidate) -> np.ndarray:
    """The hypothesis's map on step 9's sample, ``(S,)`` vertices."""
    return ws.search.to_vertices(Nearest(ws.search.sample_points(cand.target)).query(cand.query[ws.rows]))


def pair_features(
    graph, features: np.ndarray, desc: np.ndarray, evecs: np.ndarray, weights: tuple[float, ...], settings: IntrinsicSymmetrySettings
) -> tuple[list[np.ndarray], list[list[str]]]:
    """Step 4: sparse pairs ``(P, 2)`` of the feature points ``(d,)`` by Eq. 6.1 (HKS ``desc (d, h)``), one set per spectral weight."""
    feat_dist = geodesic_distances(graph, features)[:, features]  # (d, d)
    pair_sets, pair_notes = [], []
    p = settings.pairs
    for weight in weights:
        pairs, _ = symmetric_pairs(
            features, desc, evecs[features], distances=feat_dist, max_pairs=p.max_feature_pairs, max_cost=p.max_cost,
            penalty=p.penalty, spectral_weight=weight,
        )  # (P, 2)
        pair_sets.append(pairs)
        pair_notes.append(
            ["no pair of feature points passed the affinity test: no symmetry found, the map is the identity"] if pairs.shape[0] == 0 else []
        )
    return pair_sets, pair_notes


def sign_hypotheses(
    emb: np.ndarray,
    signs: np.ndarray,
    confidence: np.ndarray,
    n_flip: int,
    margin: float,
    rng: np.random.Generator | tuple[np.ndarray, np.ndarray | None],
    accept: float = 0.1,
    points: np.ndarray | None = None,
    max_points: int = 6000,
) -> tuple[np.ndarray, float, float]:
    """Step 7's extension: both signs of the ``n_flip`` least-confident eigenfunctions; the most consistent kept.

    ``emb``: ``(V, k)`` the corrected embedding; ``signs``, ``confidence``: ``(k,)``. The
    thesis's signs stay when their :func:`~torchsym.mesh.fmaps.map_consistency` is below
    ``accept`` or no trial beats ``margin`` times it. ``rng``: the generator of the 800-vertex
    sample, or the sample (:func:`~torchsym.mesh.intrinsic.sample.sign_sample`); with
    ``points`` (``(V, 3)``) on more than ``max_points`` vertices, images are sought among an even subset.

    Returns:
        The chosen signs ``(k,)``, the thesis's consistency and the chosen one's.
    """
    use = np.nonzero(signs != 0)[0]
    use = use[use != 0]  # the constant eigenfunction is always even
    flip = use[np.argsort(np.abs(confidence[use]), kind="stable")[:n_flip]]
    cols = signs != 0
    sub_emb = emb[:, cols]
    rows, keep = sign_sample(emb.shape[0], rng, points, max_points) if isinstance(rng, np.random.Generator) else rng
    if keep is not None:  # the images among an even subset that holds the rows
        sub_emb, rows = sub_emb[keep], np.searchsorted(keep, rows)
    tree = cKDTree(sub_emb)  # default leaves: its searches are approximate (eps), so the leaf size would change them
    base = consistency(sub_emb, signs[cols], rows, Nearest(sub_emb, tree=tree).query(sub_emb[rows] * signs[cols]))
    if base < accept:
        return signs, base, base
    base = map_consistency(tree, sub_emb, signs[cols], rows, approx=1.0)  # compared like with like
    best, best_q = signs, base
    for mask in range(1, 2 ** flip.size):
        trial = signs.copy()
        chosen = flip[[(mask >> b) & 1 == 1 for b in range(flip.size)]]
        trial[chosen] *= -1.0
        q = map_consistency(tree, sub_emb, trial[cols], rows, approx=1.0)
        if q < best_q:
            best, best_q = trial, q
    if best_q >= margin * base:
        return signs, base, base
    return best, base, best_q


def _pairing_candidate(ws: Workspace, pairs: np.ndarray, cand_notes: list[str], sign_draw, weight: float) -> tuple[Candidate, dict[str, float]]:
    """Steps 5-7 for one pairing: signs, correction, and the map's rows; and the seconds of each."""
    s, evecs, evals = ws.settings, ws.evecs, ws.evals
    seconds = {}
    cand_notes = list(cand_notes)
    tic = time.perf_counter()
    signs, confidence = eigenfunction_signs(
        evecs, ws.v, ws.graph, pairs, cross_pairs=s.signs.cross_pairs, min_confidence=s.signs.min_confidence
    )  # (k,)
    signs[0] = 1.0  # the constant eigenfunction is even
    if not pairs.shape[0]:
        signs[:] = 1.0  # no evidence: C = I, whose map is the identity
    seconds["signs"], tic = time.perf_counter() - tic, time.perf_counter()

    rotation = np.eye(ws.plan.n_eigen)
    converged = True
    fb_sparse = np.concatenate([evecs[pairs[:, 0]], evecs[pairs[:, 1]]], axis=0).T  # (k, 2P)
    gb_sparse = np.concatenate([evecs[pairs[:, 1]], evecs[pairs[:, 0]]], axis=0).T  # (k, 2P)
    if s.correction.enabled and not pairs.shape[0]:
        cand_notes.append("eigenfunction correction skipped: it needs at least one pair")
    if s.correction.enabled and pairs.shape[0]:
        res = correct_eigenfunctions(evals / evals[-1], fb_sparse, gb_sparse, signs, mu=s.correction.mu, max_iter=s.correction.max_iters)
        rotation, converged = res.rotation.numpy(), converged and res.converged
    seconds["correction"], tic = time.perf_counter() - tic, time.perf_counter()

    emb = evecs @ rotation  # (V', k)
    if sign_draw is not None:
        signs, q_thesis, q_chosen = sign_hypotheses(
            emb, signs, confidence, s.signs.n_uncertain, 0.6, sign_draw, points=ws.v, max_points=s.select.max_search_vertices
        )
        if q_chosen < q_thesis:
            cand_notes.append(f"signs of C changed from the thesis's rule: map consistency {q_thesis:.3f} -> {q_chosen:.3f}")
    use = signs != 0
    # a map without an odd eigenfunction is the identity, which every test scores as perfect
    usable = bool(pairs.shape[0]) and bool((signs < 0).any())
    name = "pairs" if weight == s.pairs.spectral_weight else "hks_pairs"
    cand = Candidate(name, pairs, np.diag(signs), rotation, converged, emb[:, use] * signs[use], emb[:, use], usable, tuple(cand_notes))
    seconds["map"] = time.perf_counter() - tic
    return cand, seconds


def pairing_candidates(
    ws: Workspace, pair_sets: list, pair_notes: list, sign_draws: list
) -> tuple[list[Candidate], list[np.ndarray], dict[str, float]]:
    """Steps 5-7 for each pairing, each map on step 9's sample ``(S,)``, and the seconds of steps 5-7 and of the maps."""
    seconds = {"signs": 0.0, "correction": 0.0, "map": 0.0}
    candidates = []
    for pairs, cand_notes, sign_draw, weight in zip(pair_sets, pair_notes, sign_draws, ws.plan.weights):
        cand, spent = _pairing_candidate(ws, pairs, cand_notes, sign_draw, weight)
        candidates.append(cand)
        for key, value in spent.items():
            seconds[key] += value
    tic = time.perf_counter()
    images = [first_image(ws, cand) for cand in candidates]
    seconds["select"] = time.perf_counter() - tic
    return candidates, images, seconds


def orientation_candidate(ws: Workspace) -> tuple[Candidate, float]:
    """Step 8: the orientation-reversing functional map fitted to the dense HKS
    (:func:`~torchsym.mesh.orientation.orientation_reversing_map`), and the seconds taken.
    It has no pairs of its own (the solver gives it the thesis's once those are known)."""
    tic = time.perf_counter()
    fmap = orientation_reversing_map(ws.v, ws.f, ws.evals, ws.evecs, ws.area, ws.dense_desc)  # (k, k)
    seconds = time.perf_counter() - tic
    cand = Candidate("orientation", np.zeros((0, 2), np.int64), fmap, np.eye(ws.plan.n_eigen), True, ws.evecs @ fmap.T, ws.evecs, True)
    return cand, seconds


def sign_basis_candidates(ws: Workspace, m: int, pairs: np.ndarray) -> list[Candidate]:
    """Step 8's second extension: ``C = diag(1, s)`` in the first ``m`` eigenfunctions, one
    hypothesis per sign vector ``s`` in ``{-1, 1}^(m - 1)`` but all ``+1``.

    A reflection maps each eigenfunction of a simple eigenvalue to plus or minus itself, so
    among the ``2^(m-1) - 1`` hypotheses is the symmetry's ``C`` in the smallest basis
    whenever the first ``m`` eigenvalues are simple; it needs no feature point, which is
    what the thesis's pairs miss on meshes whose HKS maxima are few or ambiguous. Each
    ``fmap`` is ``(k, k)`` with ``+1`` past the first ``m``; ``pairs (P, 2)``: the thesis's, for the result.
    """
    k = ws.plan.n_eigen
    m = min(m, k)
    query = ws.evecs[:, :m]  # (V, m)
    out = []
    for code in range(1, 2 ** (m - 1)):
        signs = np.ones(k)
        signs[1:m] = [-1.0 if (code >> b) & 1 else 1.0 for b in range(m - 1)]
        out.append(Candidate("signs", pairs, np.diag(signs), np.eye(k), True, query * signs[:m], query, True))
    return out


def sign_basis_image(ws: Workspace, cand: Candidate) -> np.ndarray:
    """A sign hypothesis's map on step 9's sample ``(S,)``: its map in its ``m`` eigenfunctions,
    then five rounds of ZoomOut up to ``refine.n_eigen`` (in ``m`` dimensions most vertices' nearest
    image is themselves, which step 9 would take for a partial identity)."""
    m, k = cand.query.shape[1], ws.plan.refine_k
    image = first_image(ws, cand)
    ks = np.unique(np.linspace(m, k, 6).round().astype(int))[1:]
    return fmaps.zoomout(ws.big, ws.area, ws.rows, image, ks, ws.search, ws.settings.refine.involution)[0] if ks.size else image


def extrinsic_candidate(
    v: np.ndarray, evecs: np.ndarray, area: np.ndarray, pairs: np.ndarray, n_samples: int, seed: int
) -> tuple[Candidate, float]:
    """Step 10's hypothesis: each vertex of ``v (V, 3)`` to the vertex nearest its mirror image
    in the best plane of at most ``n_samples`` vertices (seeded by ``seed``), and the plane's score."""
    gen = torch.Generator().manual_seed(seed)
    pts = torch.from_numpy(v)
    if v.shape[0] > n_samples:
        pts = pts[random_subset(v.shape[0], n_samples, gen)]
    plane = detect_reflection_plane(pts, kernel={"enabled": False}, generator=gen)
    nrm, off = plane.normal.numpy(), float(plane.offset)
    mirrored = v - 2.0 * (v @ nrm + off)[:, None] * nrm  # (V, 3)
    vmap = kdtree(v).query(mirrored, k=1, workers=thread_budget())[1].astype(np.int64)
    cand = Candidate(
        "extrinsic", pairs, pointwise_to_functional(evecs, area, vmap), np.eye(evecs.shape[1]), True, v, mirrored, True
    )
    return cand, float(plane.score)
