"""Step 13 (an extension): ZoomOut on into a larger basis, kept unless it lowers the orientation reversal."""

from __future__ import annotations

import dataclasses
import time

from torchsym.mesh import fmaps
from torchsym.mesh.intrinsic.refine import MapState
from torchsym.mesh.intrinsic.workspace import Workspace

__all__ = ["polish"]


def polish(ws: Workspace, state: MapState) -> tuple[MapState, list[str], float]:
    """Step 13: ``polish.max_iters`` rounds of involutive ZoomOut from ``state``'s map on the
    sample, the basis growing from ``refine.n_eigen`` to ``polish.n_eigen``; the polished map
    replaces ``state``'s unless it reverses the orientation at ``polish.orientation_drop`` fewer
    sampled vertices (not consistently wound: distorts geodesics more) or is a partial identity.

    Returns:
        The map state after the step, its notes and the seconds taken.
    """
    tic = time.perf_counter()
    rows = ws.rows
    image, fitted = fmaps.zoomout(ws.big, ws.area, rows, state.vmap[rows], ws.plan.schedule, ws.search, ws.settings.refine.involution)
    trial = ws.search.map_every_vertex(fitted)
    if ws.wound:
        before = ws.reversed_share(state.vmap) if state.share is None else state.share  # step 12's figure when it ran
        after = ws.reversed_share(trial)
        keep, test = after >= before - ws.settings.polish.orientation_drop, f"orientation reversed at {before:.0%} -> {after:.0%}"
    else:  # orientation undefined: the geodesic test instead
        before, after = ws.probe.distortion(state.vmap[rows]), ws.probe.distortion(image)
        keep, test = after <= before, f"geodesic distortion {before:.3f} -> {after:.3f}"
    notes = []
    if keep and ws.probe.near_self(image) < ws.settings.select.near_self:
        # the kept map's share, for step 14
        state = dataclasses.replace(state, vmap=trial, full=fitted, share=after if ws.wound else None)
    else:
        notes.append(
            f"ZoomOut to polish.n_eigen = {ws.plan.polish_k} eigenfunctions not kept ({test}); the map in {ws.plan.refine_k} is returned"
        )
    return state, notes, time.perf_counter() - tic
