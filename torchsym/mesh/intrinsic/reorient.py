"""Step 12 (an extension): a reflection reverses the surface's orientation; a map that keeps it
is refined again by ZoomOut with an orientation penalty (Ren et al. 2018)."""

from __future__ import annotations

import dataclasses
import math
import time
from functools import partial

import numpy as np
import scipy.linalg

from torchsym.core import parallel
from torchsym.mesh import fmaps
from torchsym.mesh.intrinsic.refine import MapState
from torchsym.mesh.intrinsic.workspace import Candidate, Workspace
from torchsym.mesh.orientation import anticommutation_penalty, orientation_operators, reduce_descriptors

__all__ = ["oriented_fits", "reorient"]


def oriented_fits(
    big: np.ndarray, area: np.ndarray, rows: np.ndarray, ks: np.ndarray, ops: np.ndarray, weights: tuple[float, ...]
) -> list[dict]:
    """Cholesky factors ``{kk: factor}`` (one dict per weight ``w``) of ZoomOut's fit with the orientation penalty.

    The fit minimises ``|Phi[rows] C - Phi[T(rows)]|_A^2 / a + w sum_p |C O_p + O_p C|^2 / s``
    over ``C (kk, kk)``; in ``vec(C)`` its matrix is ``G kron I + w P`` (``kk^2`` unknowns).
    ``ops``: ``(p, K, K)`` orientation operators, ``K >= max(ks)``.

    Raises:
        numpy.linalg.LinAlgError: a matrix that is numerically not positive definite.
    """
    sample = area[rows] / area[rows].sum()
    out: list[dict] = [{} for _ in weights]
    for kk in np.unique(ks):
        phi = big[rows, :kk]  # (S, kk)
        data = np.kron(phi.T @ (sample[:, None] * phi), np.eye(kk))  # (kk^2, kk^2)
        penalty = anticommutation_penalty(ops[:, :kk, :kk])
        for table, weight in zip(out, weights):
            table[int(kk)] = scipy.linalg.cho_factor(data + weight * penalty)
    return out


def _reoriented(ws: Workspace, bound: float, oriented: dict, schedule: np.ndarray, start: np.ndarray) -> tuple | None:
    """One trial: penalised ZoomOut from ``start (S,)``; its map, ``C``, distortion and reversed share, or None."""
    image, fitted = fmaps.zoomout(ws.big, ws.area, ws.rows, start, schedule, ws.search, ws.settings.refine.involution, oriented)
    distortion = ws.probe.distortion(image) if ws.probe.near_self(image) < ws.settings.refine.reoriented_near_self else math.inf
    if not distortion < bound:
        return None
    trial = ws.search.map_every_vertex(fitted)
    return trial, fitted, distortion, ws.reversed_share(trial)


def _starts(ws: Workspace, chosen: Candidate, candidates: list[Candidate], state: MapState, share: float) -> list:
    """The trials' ``(schedule, start)``: every hypothesis's own map when none passed step 9,
    else (when the map keeps the orientation) the hypothesis's map and the refined map."""
    ks = ws.plan.ks
    if chosen.refined is None:
        # the sign hypotheses are many and blind to the surface: none of them is a start here
        return [(ks, cand.start) for cand in candidates if cand.start is not None and cand.name != "signs"]
    if share < ws.settings.refine.keeps_orientation:
        return [
            (ks, chosen.start),  # the hypothesis's own map, the basis growing as in step 11
            (np.full(ws.plan.refine_iters, ks[-1]), ws.search.nearest(ks[-1], ws.big[ws.rows, : ks[-1]] @ state.full)),
        ]
    return []


def _should_check(ws: Workspace, chosen: Candidate) -> tuple[bool, list[str]]:
    """Whether step 12 runs, and the note saying why not where a reader should know."""
    check = bool(ws.plan.refine_iters) and ws.settings.refine.orientation_weight > 0 and (chosen.refined is not None or chosen.usable)
    max_k = ws.settings.refine.orientation_max_k
    if check and ws.plan.refine_k > max_k:
        return False, [f"orientation check skipped: its dense penalty grows as refine.n_eigen^4, and refine.n_eigen > {max_k}"]
    if check and not ws.wound:
        return False, ["orientation check skipped: the faces are not consistently wound, so the orientation is undefined"]
    return check, []


def reorient(ws: Workspace, chosen: Candidate, candidates: list[Candidate], state: MapState) -> tuple[MapState, list[str], float | None]:
    """Step 12: of the penalised trials that distort geodesics less than the limit (times
    ``refine.rescue_distortion`` when no hypothesis passed step 9), the one that reverses the
    orientation at the most sampled vertices (at least ``refine.reverses_orientation``) replaces ``state``'s map.

    Returns:
        The map state after the step (with its reversed share measured), its notes, and the
        seconds taken (None: skipped).
    """
    check, notes = _should_check(ws, chosen)
    if not check:
        return state, notes, None
    tic = time.perf_counter()
    share = ws.reversed_share(state.vmap)
    state = dataclasses.replace(state, share=share)
    starts = _starts(ws, chosen, candidates, state, share)
    if starts:
        ks, limit = ws.plan.ks, ws.limit
        ops = orientation_operators(ws.v, ws.f, ws.big[:, : ks[-1]], reduce_descriptors(ws.dense_desc, ws.area))  # (r, K, K)
        ref = ws.settings.refine
        best_share, found = ref.reverses_orientation, None
        weight = ref.orientation_weight
        try:
            fits = oriented_fits(ws.big, ws.area, ws.rows, ks, ops, tuple(c * weight for c in ref.orientation_scales))
        except np.linalg.LinAlgError:
            fits = []
            notes.append("orientation check: the penalised fit is numerically singular; the map is kept")
        bound = limit * ref.rescue_distortion if chosen.refined is None else limit
        # independent trials, on threads; chosen in the order of the loops
        trials = parallel.run_branches([partial(_reoriented, ws, bound, o, sc, st) for o in fits for sc, st in starts])
        for trial in trials:
            if trial is not None and trial[3] >= best_share:
                best_share, found, found_distortion = trial[3], trial[:2], trial[2]
        if found is not None:
            state = dataclasses.replace(state, vmap=found[0], full=found[1], share=best_share, rescued=chosen.refined is None)
            notes.append(
                ("no hypothesis passed the tests of an isometric involution; refined" if state.rescued else
                 f"the map kept the surface's orientation at {1 - share:.0%} of the sampled vertices; refined again")
                + f" with the orientation penalty, it reverses it at {best_share:.0%}"
                + (f", but distorts geodesics by {found_distortion:.3f}, above the limit {limit:g}: the map is "
                   "less reliable" if found_distortion >= limit else "")
            )
        elif chosen.refined is not None:
            notes.append(
                f"the map keeps the surface's orientation at {1 - share:.0%} of the sampled vertices (a "
                "reflection reverses it); ZoomOut with the orientation penalty found no map that reverses it "
                f"at {ref.reverses_orientation:.0%}, the map is unreliable"
            )
    return state, notes, time.perf_counter() - tic
