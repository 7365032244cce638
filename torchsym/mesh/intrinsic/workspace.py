"""What the steps of the method hand on: the prepared surface, the plan of bases and samples,
the workspace that steps 5-14 read, the hypotheses, and the stopwatch of the steps (all passed
explicitly; every record is frozen, a step returns a new one)."""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from torchsym.mesh.intrinsic.probe import GeodesicProbe
from torchsym.mesh.intrinsic.settings import IntrinsicSymmetrySettings
from torchsym.mesh.nearest import SampledSearch
from torchsym.mesh.operators import face_areas
from torchsym.mesh.orientation import OrientationTest
from torchsym.mesh.repair import close_holes
from torchsym.mesh.validate import ValidatedMesh, validate_mesh

__all__ = ["Candidate", "Plan", "Stopwatch", "Surface", "Workspace", "plan_bases", "prepare_surface"]


@dataclasses.dataclass(frozen=True)
class Surface:
    """Step 1's output: the solved component, holes covered, at unit area.

    Attributes:
        checked: the validated input (component and index maps).
        v: ``(V, 3)`` float64 vertices, centred and scaled to unit area.
        f: ``(F, 3)`` faces, the input's first, then the hole patches'.
        holes_closed: holes covered by a patch.
        patch_share: share of the area the patches cover.
    """

    checked: ValidatedMesh
    v: np.ndarray
    f: np.ndarray
    holes_closed: int
    patch_share: float

    @property
    def n(self) -> int:
        return int(self.v.shape[0])


@dataclasses.dataclass(frozen=True)
class Plan:
    """The bases and sample sizes of a run, from the settings and the vertex count.

    Attributes:
        n_eigen: ``k``. refine_iters: ZoomOut rounds of step 11 (0: off).
        refine_k, polish_k: eigenfunctions of steps 11 and 13. polish, realign: whether
        steps 13 and 14 can run. n_big: eigenpairs computed. n_rows: step 9's sample size.
        n_targets: vertices its searches look among on a large mesh. ks: ``(refine_iters,)``
        bases of step 11's rounds; schedule: ``(polish iters,)`` of step 13's. weights: the
        spectral weights of the pairings. width: tests per hypothesis in step 9.
    """

    n_eigen: int
    refine_iters: int
    refine_k: int
    polish: bool
    polish_k: int
    realign: bool
    n_big: int
    n_rows: int
    n_targets: int
    ks: np.ndarray
    schedule: np.ndarray
    weights: tuple[float, ...]

    @property
    def width(self) -> int:
        return 3 if self.refine_k > self.n_eigen else 2


@dataclasses.dataclass(frozen=True)
class Workspace:
    """What steps 5-14 read: the surface, its spectrum, step 9's sample, its searches and
    (once built, beside step 8) its geodesic probe. The searches and the probe keep caches
    that threads may share; nothing else changes after construction."""

    settings: IntrinsicSymmetrySettings
    plan: Plan
    v: np.ndarray  # (V, 3)
    f: np.ndarray  # (F, 3)
    evals: np.ndarray  # (k,)
    evecs: np.ndarray  # (V, k)
    big_evals: np.ndarray  # (K,)
    big: np.ndarray  # (V, K)
    area: np.ndarray  # (V,) lumped areas
    graph: object  # (V, V) edge graph
    two_ring: object  # (V, V) CSR
    dense_desc: np.ndarray  # (V, h) HKS
    has_boundary: bool
    wound: bool
    rows: np.ndarray  # (S,) step 9's sample
    rng: np.random.Generator  # the sample's generator
    orient: OrientationTest | None
    search: SampledSearch
    probe: GeodesicProbe | None = None

    @property
    def n(self) -> int:
        return int(self.v.shape[0])

    @property
    def limit(self) -> float:
        """Step 9's limit on the geodesic distortion."""
        sel = self.settings.select
        return sel.max_distortion_open if self.has_boundary else sel.max_distortion

    def reversed_share(self, vertex_map: np.ndarray) -> float:
        """Share of the sampled vertices around which ``vertex_map (V,)`` reverses the orientation."""
        return float(np.mean(self.orient(vertex_map) < 0))


@dataclasses.dataclass(frozen=True)
class Candidate:
    """One hypothesis: its map sends vertex ``i`` to the row of ``target`` nearest ``query[i]``.

    Steps 4-8 make it; step 9 returns a copy with ``start``, ``refined`` and its notes.

    Attributes:
        name: ``"pairs"``, ``"hks_pairs"``, ``"orientation"``, ``"signs"`` or ``"extrinsic"``.
        pairs: ``(P, 2)`` its sparse pairs. fmap: ``(k, k)`` its ``C``. rotation: ``(k, k)`` ``R``.
        converged: the correction converged. target, query: ``(V, m)`` rows of the map's search.
        usable: worth testing (not the identity). notes: its notes.
        refined: ``C`` of its ZoomOut refinement in step 9 (None: not refined).
        start: its map on step 9's sample ``(S,)`` (None: a duplicate or unusable, or not yet screened).
    """

    name: str
    pairs: np.ndarray
    fmap: np.ndarray
    rotation: np.ndarray
    converged: bool
    target: np.ndarray
    query: np.ndarray
    usable: bool
    notes: tuple[str, ...] = ()
    refined: np.ndarray | None = None
    start: np.ndarray | None = None


class Stopwatch:
    """Seconds per step of one run: ``with watch("select"):`` adds the block's wall time to
    ``"select"``; :meth:`add` adds seconds a branch on a thread measured on its own."""

    def __init__(self) -> None:
        self._seconds: dict[str, float] = {}

    @contextmanager
    def __call__(self, name: str) -> Iterator[None]:
        tic = time.perf_counter()
        try:
            yield
        finally:
            self.add(name, time.perf_counter() - tic)

    def add(self, name: str, seconds: float) -> None:
        self._seconds[name] = self._seconds.get(name, 0.0) + seconds

    def add_all(self, seconds: dict[str, float]) -> None:
        for name, value in seconds.items():
            self.add(name, value)

    def as_dict(self) -> dict[str, float]:
        return dict(self._seconds)


def prepare_surface(mesh, settings: IntrinsicSymmetrySettings, notes: list[str]) -> Surface:
    """Step 1: validate, keep the largest component, cover holes (``fill_holes``), scale to unit area."""
    checked = validate_mesh(mesh, components=settings.components, min_vertices=settings.n_eigen + 1)
    if checked.dropped_vertices:
        notes.append(
            f"kept the largest of {checked.num_components} connected components; "
            f"{checked.dropped_vertices} vertices dropped (map = -1 there)"
        )
    v = checked.mesh.vertices.detach().cpu().double().numpy()  # (V', 3)
    f = checked.mesh.faces.detach().cpu().numpy()  # (F', 3)
    holes_closed = 0
    patch_share = 0.0  # share of the (closed) surface's area that the hole patches cover
    if settings.fill_holes:
        n_faces = f.shape[0]
        filling = close_holes(v, f)
        f, holes_closed = filling.faces, filling.holes_closed  # (F'', 3) the input's triangles first
        if holes_closed:
            notes.append(
                f"closed {holes_closed} holes with {f.shape[0] - n_faces} new triangles before computing the "
                "spectrum (fill_holes)"
            )
        notes.extend(f"fill_holes: {note}" for note in filling.notes)
    tri_area = face_areas(v, f)  # (F,)
    if holes_closed:
        patch_share = float(tri_area[n_faces:].sum() / tri_area.sum())
    v = (v - v.mean(axis=0)) / math.sqrt(tri_area.sum())  # unit area
    return Surface(checked, v, f, holes_closed, patch_share)


def plan_bases(n: int, settings: IntrinsicSymmetrySettings, notes: list[str]) -> Plan:
    """The bases of steps 2, 11 and 13 and step 9's sample sizes for ``n`` vertices (lowered, with a note, on small meshes)."""
    s = settings
    n_eigen = s.n_eigen
    refine_iters = s.refine.max_iters if s.refine.enabled else 0
    refine_k = max(s.refine.n_eigen, n_eigen) if refine_iters else n_eigen
    polish_k = s.polish.n_eigen
    polish = bool(refine_iters) and s.polish.enabled and polish_k > refine_k
    realign = bool(refine_iters) and s.realign.enabled
    if refine_k >= n:
        notes.append(f"refine.n_eigen lowered from {refine_k} to {n - 1}, one less than the {n} vertices")
        refine_k = max(n_eigen, n - 1)
    if polish and polish_k >= n:
        notes.append(f"polish.n_eigen lowered from {polish_k} to {n - 1}, one less than the {n} vertices")
        polish_k = n - 1
        polish = polish_k > refine_k
    n_big = polish_k if polish else refine_k
    weights = [s.pairs.spectral_weight]
    if s.hypotheses.hks_pairs and s.pairs.spectral_weight != 0.0:
        weights.append(0.0)
    n_rows = min(n, max(s.select.n_samples, 4 * n_big))  # the least-squares fits have n_big unknowns per column
    n_targets = max(s.select.max_search_vertices, 2 * n_rows)
    ks = np.linspace(n_eigen, refine_k, refine_iters + 1).round().astype(int)[1:] if refine_iters else np.zeros(0, int)
    schedule = (
        np.linspace(refine_k, polish_k, s.polish.max_iters + 1).round().astype(int)[1:] if polish else np.zeros(0, int)
    )
    return Plan(n_eigen, refine_iters, refine_k, polish, polish_k, realign, n_big, n_rows, n_targets, ks, schedule, tuple(weights))


def sample_notes(plan: Plan, n: int, settings: IntrinsicSymmetrySettings) -> list[str]:
    """Notes on step 9's sample sizes raised above the settings."""
    sel, out = settings.select, []
    if plan.n_rows > sel.n_samples and n > sel.n_samples:
        out.append(f"select.n_samples raised from {sel.n_samples} to {plan.n_rows}, 4 x {'polish.n_eigen' if plan.polish else 'refine.n_eigen'}")
    if n > sel.max_search_vertices and plan.n_targets > sel.max_search_vertices:
        out.append(f"select.max_search_vertices raised from {sel.max_search_vertices} to {plan.n_targets}, twice the vertex sample")
    return out
