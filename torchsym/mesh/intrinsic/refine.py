"""Step 7's dense map (Sec. 6.2.7) and step 11: the chosen hypothesis's ZoomOut map of every vertex."""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from torchsym.core.parallel import thread_budget
from torchsym.mesh.intrinsic.workspace import Candidate, Workspace
from torchsym.mesh.nearest import kdtree

__all__ = ["MapState", "finish_map", "refined_map", "thesis_map"]


@dataclasses.dataclass(frozen=True)
class MapState:
    """The current map, handed from step 11 to 14 (each step returns a new one).

    Attributes:
        vmap: ``(V,)`` the map (step 11's: read only where steps 12-14 need it, -1 elsewhere).
        full: ``(k_r, k_r)`` its functional map (``(0, 0)`` without refinement).
        share: share of the sampled vertices where it reverses the orientation (None: not measured).
        rescued: step 12 found a map where no hypothesis passed step 9.
        coarse: ``(V,)`` the thesis's map where no ZoomOut map replaced it, else None.
        step11: step 11's map array (``vmap`` is it until a later step replaces it), or None.
        step11_fmap: its functional map. rest: ``(R,)`` vertices step 11 left unread.
    """

    vmap: np.ndarray
    full: np.ndarray
    share: float | None = None
    rescued: bool = False
    step11: np.ndarray | None = None
    step11_fmap: np.ndarray | None = None
    rest: np.ndarray | None = None
    coarse: np.ndarray | None = None


def thesis_map(chosen: Candidate, eps: float) -> tuple[np.ndarray, float]:
    """The hypothesis's dense map ``(V,)``: each row of ``query`` to the nearest row of ``target``
    (approximate with ``eps > 0``), and the seconds taken."""
    tic = time.perf_counter()
    dense_tree = kdtree(chosen.target, balanced=False)
    return dense_tree.query(chosen.query, k=1, eps=eps, workers=thread_budget())[1].astype(np.int64), time.perf_counter() - tic  # (V',)


def refined_map(ws: Workspace, chosen: Candidate) -> tuple[MapState, dict[str, float]]:
    """Step 11: the map of the chosen hypothesis's last ZoomOut ``C`` on the sample and its
    2-rings (the rest when no later step replaces it, :func:`finish_map`); or, unrefined, the
    thesis's map. And the seconds taken, as ``"refine"`` (with refinement on) or ``"map"``."""
    tic = time.perf_counter()
    seconds = {"refine": 0.0} if ws.plan.refine_iters else {}
    if ws.plan.refine_iters and chosen.refined is not None:
        full = chosen.refined  # (k_r, k_r), fitted on the sample
        read = np.union1d(ws.rows, ws.two_ring[ws.rows].indices)  # (U,)
        rest = np.setdiff1d(np.arange(ws.n), read)
        vmap = np.full(ws.n, -1, dtype=np.int64)
        vmap[read] = ws.search.map_every_vertex(full, read)
        seconds["refine"] = time.perf_counter() - tic
        return MapState(vmap, full, step11=vmap, step11_fmap=full, rest=rest), seconds
    coarse_map, seconds["map"] = thesis_map(chosen, 0.0)
    return MapState(coarse_map, np.zeros((0, 0)), coarse=coarse_map), seconds


def finish_map(ws: Workspace, state: MapState) -> tuple[np.ndarray, float]:
    """The map ``(V,)`` of every vertex: step 11's completed on the vertices it left unread when
    no later step replaced it; and the seconds that took."""
    if state.step11 is None or state.vmap is not state.step11:
        return state.vmap, 0.0
    tic = time.perf_counter()
    vmap = state.vmap.copy()
    vmap[state.rest] = ws.search.map_every_vertex(state.step11_fmap, state.rest)
    return vmap, time.perf_counter() - tic
