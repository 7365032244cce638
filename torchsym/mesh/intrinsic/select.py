"""Steps 9-10: choose a hypothesis on the vertex sample by tests of an isometric involution,
and try the vertices' mirror plane when the chosen map is weak on a mesh with holes (extensions)."""

from __future__ import annotations

import dataclasses
import logging
import math
from functools import partial

import numpy as np
import torch

from torchsym.core import parallel
from torchsym.mesh import fmaps
from torchsym.mesh.intrinsic import hypotheses
from torchsym.mesh.intrinsic.hypotheses import first_image
from torchsym.mesh.intrinsic.probe import reflection_score
from torchsym.mesh.intrinsic.workspace import Candidate, Workspace

__all__ = ["choose", "is_weak", "rank_choice", "reflection_choice", "refine_score", "screen", "screen_and_refine", "try_extrinsic"]

logger = logging.getLogger(__name__)



def rank_choice(table: np.ndarray, max_distortion: float = math.inf) -> int:
    """The row of ``table (H, T)`` with the smallest sum of ranks over the columns (ties: the earlier).

    Rows holding ``inf`` rank last (all ``inf``: row 0). A winner other than row 0 must
    also have a last column (the distortion) below ``max_distortion`` and row 0's.
    """
    n = table.shape[0]
    ranks = np.zeros(n)
    for col in table.T:
        order = np.argsort(col, kind="stable")
        ranks[order] += np.arange(n)
    ranks[~np.isfinite(table).all(axis=1)] = np.inf
    if not np.isfinite(ranks).any():
        return 0
    best = int(np.argmin(ranks))
    distortion = table[:, -1]
    return best if best == 0 or distortion[best] < min(max_distortion, distortion[0]) else 0


def is_weak(row: np.ndarray, weak_defect: float) -> bool:
    """Whether the chosen hypothesis's tests ``(width,)`` fail or its defect in ``k`` exceeds ``weak_defect`` (step 10 runs)."""
    return not np.isfinite(row).all() or row[0] > weak_defect


def screen(ws: Workspace, seen: list[np.ndarray], cand: Candidate, image: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """The hypothesis's map on the sample ``(S,)``; that map as its start (None: unusable, or a
    duplicate of a map in ``seen``); and that map again when worth refining (None: no start,
    or a partial identity)."""
    image = first_image(ws, cand) if image is None else image
    duplicate = any(np.array_equal(image, other) for other in seen)
    start = None if duplicate or not cand.usable else image
    if start is None or ws.probe.near_self(image) >= ws.settings.select.near_self:
        return image, start, None
    return image, start, image


def refine_score(ws: Workspace, image: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None, tuple[str, ...]]:
    """A hypothesis's map on the sample ``image (S,)`` (None: not refined) refined by ZoomOut, and
    its tests ``(width,)``: functional defects in ``k`` and ``refine.n_eigen`` eigenfunctions and
    the geodesic distortion (``inf``: failed); the last ``C`` (None: failed) and the notes."""
    plan = ws.plan
    if image is None:
        return np.full(plan.width, np.inf), None, ()
    rows, area = ws.rows, ws.area
    refined, fitted = fmaps.zoomout(ws.big, area, rows, image, plan.ks, ws.search, ws.settings.refine.involution)
    if ws.probe.near_self(refined) >= ws.settings.select.near_self:
        # ZoomOut drifted to the identity, which every test scores as perfect
        return np.full(plan.width, np.inf), None, ("ZoomOut refinement drifted towards the identity map; the unrefined map is kept",)
    c_k = fmaps.fit_functional(ws.evecs[rows], ws.evecs[refined], area[rows])
    defects = [fmaps.involution_defect(c_k)]
    if plan.refine_k > plan.n_eigen:  # else the same defect twice
        k_r = plan.refine_k
        defects.append(fmaps.involution_defect(fmaps.fit_functional(ws.big[rows, :k_r], ws.big[refined, :k_r], area[rows])))
    return np.array([*defects, ws.probe.distortion(refined)]), fitted, ()


def reflection_choice(ws: Workspace, candidates: list[Candidate], table: np.ndarray) -> tuple[int | None, float]:
    """The refined hypothesis of least geodesic distortion (last column of ``table (H, width)``)
    below the limit whose map reverses the orientation at at least ``select.reflects`` of the
    sampled vertices (not tested when the faces are not consistently wound: share 1); None if
    none. And the share of sampled vertices where its map reverses the orientation."""
    distortion = np.where(np.isfinite(table).all(axis=1), table[:, -1], np.inf)
    read = None
    for row in np.argsort(distortion, kind="stable"):
        if not distortion[row] < ws.limit or candidates[row].refined is None:
            return None, 0.0
        if ws.orient is None:
            return int(row), 1.0
        if read is None:
            read = np.union1d(ws.rows, ws.two_ring[ws.rows].indices)  # the orientation test reads the 2-rings
        vmap = np.full(ws.n, -1, dtype=np.int64)
        vmap[read] = ws.search.map_every_vertex(candidates[row].refined, read)
        share = ws.reversed_share(vmap)
        if share >= ws.settings.select.reflects:
            return int(row), share
    return None, 0.0


def screen_and_refine(
    ws: Workspace, candidates: list[Candidate], images: list[np.ndarray], seen: list[np.ndarray]
) -> tuple[list[Candidate], np.ndarray, list[np.ndarray]]:
    """Step 9's tests: every hypothesis screened (in order: a duplicate of a map in ``seen`` or of an
    earlier one is skipped) and refined on threads.

    Returns:
        The hypotheses with their start and ZoomOut ``C`` (:class:`Candidate`), their tests
        ``(H, width)``, and ``seen`` with their maps on the sample added.
    """
    seen, screened = list(seen), []
    for cand, image in zip(candidates, images):
        image, start, todo = screen(ws, seen, cand, image)
        seen.append(image)
        screened.append((start, todo))
    found = parallel.run_branches([partial(refine_score, ws, todo) for _, todo in screened])
    tested = [
        dataclasses.replace(cand, start=start, refined=fitted, notes=cand.notes + notes)
        for cand, (start, _), (_, fitted, notes) in zip(candidates, screened, found)
    ]
    return tested, np.stack([tests for tests, _, _ in found]), seen  # (H, 3), or (H, 2) without refinement


def choose(ws: Workspace, candidates: list[Candidate], table: np.ndarray) -> tuple[int, float | None]:
    """Step 9's choice among the tested hypotheses (``table (H, width)``): :func:`reflection_choice`, else
    :func:`rank_choice`. And the chosen map's score as a reflection (:func:`~torchsym.mesh.intrinsic.probe.reflection_score`;
    None: no reflection passed)."""
    best, share = reflection_choice(ws, candidates, table)
    if best is None:
        return rank_choice(table, ws.limit), None
    return best, reflection_score(float(table[best, -1]), share, ws.settings.select.score_distortion)


def try_extrinsic(
    ws: Workspace, candidates: list[Candidate], table: np.ndarray, best: int, seen: list[np.ndarray],
    patch_share: float, gen: torch.Generator,
) -> tuple[list[Candidate], np.ndarray, int, bool, str]:
    """Step 10 (run on meshes with holes): the mirror plane's map (:func:`~torchsym.mesh.intrinsic.hypotheses.extrinsic_candidate`),
    refined and tested as in step 9, replaces the weak chosen map when it passes the tests and
    the plane scores at least ``extrinsic.min_score`` (times one less ``patch_share``) or each
    test is at most ``extrinsic.clearly`` times the weak map's.

    Returns:
        The hypotheses and their tests (the plane's added when taken), the chosen row, whether
        the plane's map was taken, and the note saying so or why not.
    """
    ext = ws.settings.extrinsic
    seed = (gen.initial_seed() + 1) % 2**64  # a seed of its own (initial_seed may be 2^64 - 1)
    cand, plane_score = hypotheses.extrinsic_candidate(ws.v, ws.evecs, ws.area, candidates[0].pairs, ext.max_points, seed)
    _, start, todo = screen(ws, seen, cand)
    row, fitted, cand_notes = refine_score(ws, todo)
    cand = dataclasses.replace(cand, start=start, refined=fitted, notes=cand.notes + cand_notes)
    logger.debug("extrinsic plane: score %.3f, defects %s", plane_score, np.round(row, 4))
    weak_row = np.array2string(table[best], precision=3)
    # a vertex whose mirror falls in a covered hole has no partner: the limit drops by the patches' share
    score_limit = ext.min_score * (1.0 - patch_share)
    passes = bool(np.isfinite(row).all() and row[-1] < ws.limit)
    clearly = bool(np.isfinite(table[best]).all() and (row <= ext.clearly * table[best]).all())
    if passes and (plane_score >= score_limit or clearly):
        why = "" if plane_score >= score_limit else (
            f", under {score_limit:.2f}, but each test of its refined map ({np.array2string(row, precision=3)}) is "
            f"at most {ext.clearly:g} times the intrinsic map's"
        )
        note = (
            f"map from the extrinsic reflection plane of the vertices (symmetry score {plane_score:.2f}{why}): "
            f"the intrinsic map was weak (defects {weak_row})"
        )
        return [*candidates, cand], np.vstack([table, row]), len(candidates), True, note
    note = (
        f"the intrinsic map is weak (defects {weak_row}), and the extrinsic reflection plane of the "
        f"vertices did not replace it (symmetry score {plane_score:.2f}, defects "
        f"{np.array2string(row, precision=3)})"
    )
    return candidates, table, best, False, note
