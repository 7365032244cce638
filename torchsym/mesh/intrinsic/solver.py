"""The intrinsic-symmetry method (thesis Ch. 6) as one function of its steps, and its Module."""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping
from functools import partial
from typing import Any

import numpy as np
import torch
from threadpoolctl import threadpool_limits

from torchsym.core import parallel
from torchsym.core.random import draw_seed, make_generator
from torchsym.core.registry import register_solver
from torchsym.core.results import on_input_device
from torchsym.core.settings import Solver, resolve_settings
from torchsym.geometry.mesh import Mesh
from torchsym.mesh.intrinsic.coarsen import carry_map, coarse_copy
from torchsym.mesh.intrinsic.hypotheses import (
    HYPOTHESIS_TEXT,
    first_image,
    orientation_candidate,
    pair_features,
    pairing_candidates,
    sign_basis_candidates,
    sign_basis_image,
)
from torchsym.mesh.intrinsic.polish import polish
from torchsym.mesh.intrinsic.probe import GeodesicProbe, map_score
from torchsym.mesh.intrinsic.realign import realign
from torchsym.mesh.intrinsic.refine import finish_map, refined_map, thesis_map
from torchsym.mesh.intrinsic.reorient import reorient
from torchsym.mesh.intrinsic.result import Deferred, IntrinsicSymmetryResult
from torchsym.mesh.intrinsic.sample import draw_sample, sign_sample
from torchsym.mesh.intrinsic.select import choose, is_weak, screen_and_refine, try_extrinsic
from torchsym.mesh.intrinsic.settings import IntrinsicSymmetrySettings
from torchsym.mesh.intrinsic.spectrum import Spectrum, compute_spectrum, feature_points
from torchsym.mesh.intrinsic.workspace import (
    Candidate,
    Plan,
    Stopwatch,
    Surface,
    Workspace,
    plan_bases,
    prepare_surface,
    sample_notes,
)
from torchsym.mesh.nearest import SampledSearch
from torchsym.mesh.operators import edge_face_counts
from torchsym.mesh.validate import validate_mesh

__all__ = ["IntrinsicSymmetry", "intrinsic_symmetry"]

logger = logging.getLogger(__name__)


@on_input_device
@threadpool_limits.wrap(limits=1, user_api="blas")  # the searches run on every core instead
def intrinsic_symmetry(
    mesh: Mesh,
    settings: IntrinsicSymmetrySettings | Mapping[str, Any] | None = None,
    *,
    generator: torch.Generator | None = None,
    **overrides: Any,
) -> IntrinsicSymmetryResult:
    """The intrinsically symmetric vertex of every vertex of ``mesh`` (thesis Sec. 6.2).

    1. Validate, keep the largest component, cover holes, scale to unit area.
    2. The smallest eigenpairs of the cotangent Laplacian (Sec. 6.2.3).
    3. HKS feature points (Sec. 6.2.4).
    4. Sparse symmetric pairs of them by Eq. 6.1 (also on HKS alone: ``hypotheses.hks_pairs``).
    5. Signs of the eigenfunctions from geodesics between pairs, ``C = diag(s)`` (Sec. 6.2.5).
    6. The correction ``R`` on SO(k) of Eq. 6.4 (Sec. 6.2.6).
    7. The dense map (Sec. 6.2.7), trying both signs of the least-confident eigenfunctions.
    8. The orientation-reversing functional map of the dense HKS (``hypotheses.orientation``).
    9. Choice by ZoomOut on a vertex sample: the least-distorting hypothesis that reverses the
       orientation (a reflection), else the tests of an isometric involution. Where no reflection
       scores ``hypotheses.sign_basis_below``, step 8 adds ``C = diag(1, s)`` in the first
       eigenfunctions for every sign vector ``s`` (``hypotheses.sign_basis``) and step 9 chooses again.
    10. The vertices' mirror plane when the chosen map is weak and the mesh has holes (``extrinsic``).
    11. ZoomOut refinement to ``refine.n_eigen`` eigenfunctions (``refine``).
    12. Orientation check, ZoomOut with an orientation penalty (``refine.orientation_weight``).
    13. ZoomOut on to ``polish.n_eigen`` eigenfunctions (``polish``).
    14. Realignment by distances to anchors (``realign``).
    15. The map's score in [0, 1] (``result.score``), with a note when under ``select.weak_score``.

    Steps 4 and 8-14 go beyond the thesis (``docs/design/intrinsic.md``); the thesis's method
    alone is described in :class:`IntrinsicSymmetrySettings`.

    Args:
        mesh: the input :class:`~torchsym.geometry.mesh.Mesh` (any pose, may have holes).
        settings: :class:`IntrinsicSymmetrySettings`, a mapping as in YAML, or None (defaults).
        generator: the source of randomness; None seeds one with ``settings.seed``.
        **overrides: settings to change, dotted for groups (``**{"refine.n_eigen": 30}``) or
            groups as mappings (``refine={"n_eigen": 30}``).

    Returns:
        An :class:`IntrinsicSymmetryResult`; the same seed gives the same bits.

    Raises:
        ConfigError: a bad setting.
        InputValueError: a broken mesh (:func:`~torchsym.mesh.validate_mesh`).
        InputShapeError: not a mesh, or fewer than ``n_eigen + 1`` vertices.
        SolverError: the eigensolver or the pairing program failed.
    """
    settings = resolve_settings(IntrinsicSymmetrySettings, settings, overrides)
    gen = generator if generator is not None else make_generator(settings.seed)
    if settings.coarse.enabled and isinstance(mesh, Mesh) and mesh.num_vertices > settings.coarse.max_vertices:
        return _solve_on_copy(mesh, settings, gen)  # steps 1-14 on a decimated copy
    watch, notes = Stopwatch(), []
    t_start = time.perf_counter()

    with watch("validate"):
        surface = prepare_surface(mesh, settings, notes)  # step 1
    plan = plan_bases(surface.n, settings, notes)
    spectrum = compute_spectrum(surface.v, surface.f, plan, settings, gen)  # step 2
    watch.add("eigen", spectrum.t_eigen)
    features = feature_points(spectrum, settings)  # step 3
    watch.add("features", spectrum.t_topology + features.seconds)
    with watch("pairs"):
        pair_sets, pair_notes = pair_features(spectrum.graph, features.points, features.desc, spectrum.evecs, plan.weights, settings)  # step 4
        sign_draws, seed = _draw_seeds(surface, spectrum, pair_sets, settings, gen)

    notes.extend(sample_notes(plan, surface.n, settings))
    with watch("select"):
        ws, t_sample = _workspace(surface, spectrum, features.dense_desc, plan, settings, seed)
    watch.add("select", t_sample)
    ws, candidates, images, seconds = _hypotheses(ws, pair_sets, pair_notes, sign_draws)  # steps 5-8
    watch.add_all(seconds)

    with watch("select"):
        candidates, table, seen = screen_and_refine(ws, candidates, images, [])  # step 9
        best, confidence = choose(ws, candidates, table)
        if _more_hypotheses(settings, confidence):  # step 8's sign hypotheses, then step 9 again
            candidates, table, seen = _with_sign_hypotheses(ws, candidates, table, seen)
            best, confidence = choose(ws, candidates, table)
    extrinsic_note = None
    holed = surface.holes_closed > 0 or spectrum.has_boundary
    if settings.extrinsic.enabled and holed and is_weak(table[best], settings.extrinsic.weak_defect):
        with watch("extrinsic"):
            candidates, table, best, taken, note = try_extrinsic(ws, candidates, table, best, seen, surface.patch_share, gen)  # step 10
        if taken:
            extrinsic_note = note
        else:
            notes.append(note)
    chosen = candidates[best]
    notes.extend(_choice_notes(candidates, table, best, extrinsic_note))

    state = _refine_chosen(ws, chosen, candidates, watch, notes)  # steps 11-14
    if not np.isfinite(table[best]).all() and chosen.usable and not state.rescued:
        notes.append(
            "no hypothesis passed the tests of an isometric involution (each left most of the shape "
            "in place, or distorted geodesics by more than the limit): the thesis's map is "
            "returned unrefined and is unreliable"
        )
    vmap, seconds = finish_map(ws, state)
    if state.step11 is not None:
        watch.add("refine", seconds)
    state = dataclasses.replace(state, vmap=vmap)
    score = map_score(ws, state.vmap)  # step 15
    if score < settings.select.weak_score:
        notes.append(
            f"the intrinsic symmetry found is weak (score {score:.2f} < select.weak_score {settings.select.weak_score:g}): "
            "the mesh may have no intrinsic reflection symmetry, or the map may be wrong"
        )
    watch.add("total", time.perf_counter() - t_start)
    return _result(surface, spectrum, features.points, chosen, state, score, settings.refine.before_refine_eps, watch.as_dict(), notes)


def _refine_chosen(ws: Workspace, chosen: Candidate, candidates: list[Candidate], watch: Stopwatch, notes: list[str]):
    """Steps 11-14 from the chosen hypothesis: the map state they hand on (each step's seconds to ``watch``, notes to ``notes``)."""
    state, seconds = refined_map(ws, chosen)  # step 11
    watch.add_all(seconds)
    state, step_notes, seconds = reorient(ws, chosen, candidates, state)  # step 12
    notes.extend(step_notes)
    if seconds is not None:
        watch.add("orientation_check", seconds)
    improvable = chosen.refined is not None or state.rescued
    plan = ws.plan
    if plan.polish and improvable:
        state, step_notes, seconds = polish(ws, state)  # step 13
        notes.extend(step_notes)
        watch.add("polish", seconds)
    if plan.realign and state.full.shape[0] and improvable:
        if ws.wound:
            state, step_notes, seconds = realign(ws, state)  # step 14
            notes.extend(step_notes)
            watch.add("realign", seconds)
        else:
            notes.append("realignment (step 14) skipped: the faces are not consistently wound, so the orientation is undefined")
    return state


def _solve_on_copy(mesh: Mesh, settings: IntrinsicSymmetrySettings, gen: torch.Generator) -> IntrinsicSymmetryResult:
    """Steps 1-14 on a copy of ``mesh`` decimated to about ``coarse.n_vertices`` vertices, the map carried to every vertex."""
    t_start = time.perf_counter()
    checked = validate_mesh(mesh, components=settings.components, min_vertices=settings.n_eigen + 1)
    v = checked.mesh.vertices.detach().cpu().double().numpy()  # (V', 3)
    f = checked.mesh.faces.detach().cpu().numpy()  # (F', 3)
    copy = coarse_copy(v, f, settings.coarse.n_vertices, np.random.default_rng(draw_seed(gen)))
    # the copy's own small holes (where regions meet irregularly) are no holes of the input: step 10
    # and step 9's limit on the distortion follow the input
    holed = bool((edge_face_counts(f)[1] == 1).any())
    select = settings.select if holed else dataclasses.replace(settings.select, max_distortion_open=settings.select.max_distortion)
    inner = intrinsic_symmetry(
        Mesh(torch.from_numpy(copy.vertices), torch.from_numpy(copy.faces)),
        dataclasses.replace(
            settings, coarse=dataclasses.replace(settings.coarse, enabled=False), select=select,
            extrinsic=dataclasses.replace(settings.extrinsic, enabled=settings.extrinsic.enabled and holed),
        ),
        generator=gen,
    )
    tic = time.perf_counter()
    vmap = checked.map_to_input(torch.from_numpy(carry_map(copy, v, inner.map.numpy())))
    to_input = torch.from_numpy(checked.vertex_index.numpy()[copy.to_input])  # copy vertex -> input vertex
    t_carry = time.perf_counter() - tic
    notes = [
        f"solved on a copy decimated to {copy.vertices.shape[0]} vertices (coarse.max_vertices "
        f"{settings.coarse.max_vertices}), the map carried to every vertex",
        *(f"copy: {n}" if n.startswith("kept the largest") else n for n in inner.notes),
    ]
    if checked.dropped_vertices:
        notes.insert(1, f"kept the largest of {checked.num_components} connected components; "
                        f"{checked.dropped_vertices} vertices dropped (map = -1 there)")
    timings = {**inner.timings, "coarsen": copy.seconds, "carry": t_carry}
    timings["total"] = time.perf_counter() - t_start
    return dataclasses.replace(
        inner,
        map=vmap,
        map_before_refine=Deferred(partial(_carried_before, checked, copy, v, inner)),
        pairs=to_input[inner.pairs],
        feature_points=to_input[inner.feature_points],
        timings=timings,
        num_components=checked.num_components,
        dropped_vertices=checked.dropped_vertices,
        notes=tuple(notes),
    )


def _carried_before(checked, copy, v: np.ndarray, inner: IntrinsicSymmetryResult) -> torch.Tensor:
    return checked.map_to_input(torch.from_numpy(carry_map(copy, v, inner.map_before_refine.numpy())))


def _draw_seeds(surface: Surface, spectrum: Spectrum, pair_sets: list, settings: IntrinsicSymmetrySettings, gen: torch.Generator) -> tuple:
    """The generator's draws in the serial order: each pairing's sign sample (step 7), then step 9's seed."""
    n_uncertain, max_search = settings.signs.n_uncertain, settings.select.max_search_vertices
    sign_seeds = [draw_seed(gen) if n_uncertain and pairs.shape[0] else None for pairs in pair_sets]
    sign_draws = [
        None if s is None else spectrum.sign_samples.get(s) or sign_sample(surface.n, np.random.default_rng(s), surface.v, max_search)
        for s in sign_seeds
    ]
    return sign_draws, draw_seed(gen)


def _workspace(surface: Surface, spectrum: Spectrum, dense_desc: np.ndarray, plan: Plan, settings: IntrinsicSymmetrySettings, seed: int) -> tuple[Workspace, float]:
    """The workspace of steps 5-14 on step 9's sample drawn from ``seed`` (drawn ahead when guessed right), and the sample's seconds."""
    sample = next((s for s in spectrum.samples if s.seed == seed), None) or draw_sample(
        seed, surface.v, surface.f, plan.n_rows, settings.select.max_search_vertices, plan.n_targets, spectrum.two_ring, spectrum.frames
    )
    ws = Workspace(
        settings, plan, surface.v, surface.f, spectrum.evals, spectrum.evecs, spectrum.big_evals, spectrum.big, spectrum.area,
        spectrum.graph, spectrum.two_ring, dense_desc, spectrum.has_boundary, spectrum.wound,
        sample.rows, sample.rng, sample.orient, SampledSearch(spectrum.big, sample.targets),
    )
    return ws, sample.seconds


def _probe_and_searches(ws: Workspace) -> tuple[GeodesicProbe, float]:
    """Step 9's geodesic probe (drawn from the sample's generator) and the sampled searches of steps 11 and 13, built before threads share them."""
    tic = time.perf_counter()
    probe = GeodesicProbe(ws.graph, ws.rows, ws.rng)
    for kk in (*ws.plan.ks, *ws.plan.schedule):
        ws.search.sample(kk)
    if ws.plan.polish:
        ws.search.dense(ws.plan.polish_k)
    return probe, time.perf_counter() - tic


def _orientation_branch(ws: Workspace) -> tuple:
    cand, t_fmap = orientation_candidate(ws)  # step 8
    probe, t_probe = _probe_and_searches(ws)
    tic = time.perf_counter()
    image = first_image(ws, cand)
    return cand, t_fmap, probe, t_probe + time.perf_counter() - tic, image


def _hypotheses(ws: Workspace, pair_sets: list, pair_notes: list, sign_draws: list) -> tuple:
    """Steps 5-8: the pairings' hypotheses beside the orientation hypothesis (with step 9's probe), on two
    threads. Returns the workspace with its probe, the hypotheses, their maps on the sample ``(S,)`` and
    the seconds per step."""
    pairings = partial(pairing_candidates, ws, pair_sets, pair_notes, sign_draws)
    if ws.settings.hypotheses.orientation:
        (candidates, images, seconds), (cand, t_orientation, probe, t_probe, image) = parallel.run_branches(
            [pairings, partial(_orientation_branch, ws)]
        )
        candidates = [*candidates, dataclasses.replace(cand, pairs=candidates[0].pairs)]
        images = [*images, image]
        seconds["orientation"] = t_orientation
    else:
        (candidates, images, seconds), (probe, t_probe) = parallel.run_branches([pairings, partial(_probe_and_searches, ws)])
    seconds["select"] += t_probe
    return dataclasses.replace(ws, probe=probe), candidates, images, seconds


def _more_hypotheses(settings: IntrinsicSymmetrySettings, confidence: float | None) -> bool:
    """Whether step 8's sign hypotheses are added: on, and no reflection of at least ``hypotheses.sign_basis_below`` found."""
    hyp = settings.hypotheses
    return hyp.sign_basis >= 2 and (confidence is None or confidence < hyp.sign_basis_below)


def _with_sign_hypotheses(ws: Workspace, candidates: list[Candidate], table: np.ndarray, seen: list) -> tuple:
    """Step 8's sign hypotheses, tested as in step 9 after ``candidates`` (tests ``table``); all of them and their tests."""
    signed = sign_basis_candidates(ws, ws.settings.hypotheses.sign_basis, candidates[0].pairs)
    images = [sign_basis_image(ws, cand) for cand in signed]
    more, more_table, seen = screen_and_refine(ws, signed, images, seen)
    return [*candidates, *more], np.vstack([table, more_table]), seen


def _choice_notes(candidates: list[Candidate], table: np.ndarray, best: int, extrinsic_note: str | None) -> list[str]:
    """The chosen hypothesis's notes and the note saying why it is not the thesis's."""
    chosen = candidates[best]
    for cand, row in zip(candidates, table):
        logger.debug("hypothesis %s: defects %s", cand.name, np.round(row, 4))
    notes = list(chosen.notes)
    if extrinsic_note is not None:
        notes.append(extrinsic_note)
    elif best != 0:
        notes.append(
            f"map from the {HYPOTHESIS_TEXT[chosen.name]}: ranked first on the tests of an isometric involution "
            f"(defects {np.array2string(table[best], precision=3)} against {np.array2string(table[0], precision=3)} "
            f"for the thesis's pairs)"
        )
    return notes


def _deferred_thesis_map(checked, chosen: Candidate, eps: float) -> torch.Tensor:
    return checked.map_to_input(torch.from_numpy(thesis_map(chosen, eps)[0]))


def _result(
    surface: Surface, spectrum: Spectrum, features: np.ndarray, chosen: Candidate, state, score: float, eps: float, timings, notes
) -> IntrinsicSymmetryResult:
    checked = surface.checked
    to_input = checked.vertex_index.numpy()
    refined = state.step11 is not None
    return IntrinsicSymmetryResult(
        map=checked.map_to_input(torch.from_numpy(state.vmap)),
        functional_map=torch.from_numpy(np.ascontiguousarray(chosen.fmap)),
        rotation=torch.from_numpy(chosen.rotation),
        map_before_refine=(
            Deferred(partial(_deferred_thesis_map, checked, chosen, eps)) if refined
            else checked.map_to_input(torch.from_numpy(state.coarse))
        ),
        refined_functional_map=torch.from_numpy(np.ascontiguousarray(state.full)),
        eigenvalues=torch.from_numpy(spectrum.evals),
        pairs=torch.from_numpy(to_input[chosen.pairs]),
        feature_points=torch.from_numpy(to_input[features]),
        timings=timings,
        num_components=checked.num_components,
        dropped_vertices=checked.dropped_vertices,
        correction_converged=bool(chosen.converged),
        hypothesis=chosen.name,
        holes_closed=surface.holes_closed,
        score=score,
        notes=tuple(notes),
    )


@register_solver("intrinsic_symmetry", kind="mesh", default=True)
class IntrinsicSymmetry(Solver):
    """Intrinsic reflection symmetry of a triangle mesh by functional maps (thesis Ch. 6).

    Module form of :func:`intrinsic_symmetry`, settings :class:`IntrinsicSymmetrySettings`.

    Example:
        >>> solver = IntrinsicSymmetry(n_eigen=13, seed=0)
        >>> result = solver(mesh)  # doctest: +SKIP
    """

    settings_class = IntrinsicSymmetrySettings

    def forward(self, mesh: Mesh, generator: torch.Generator | None = None) -> IntrinsicSymmetryResult:
        gen = generator if generator is not None else make_generator(self.settings.seed)
        return intrinsic_symmetry(mesh, self.settings, generator=gen)
