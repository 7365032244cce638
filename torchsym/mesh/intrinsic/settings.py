"""Settings of the intrinsic-symmetry method (thesis Ch. 6), one frozen dataclass with groups by stage."""

from __future__ import annotations

import dataclasses
from typing import Literal

from torchsym.core.settings import Settings, group, setting
from torchsym.errors import ConfigError

__all__ = [
    "Coarse",
    "Correction",
    "Extrinsic",
    "Features",
    "Hypotheses",
    "IntrinsicSymmetrySettings",
    "Pairs",
    "Polish",
    "Realign",
    "Refine",
    "Select",
    "Signs",
]


@dataclasses.dataclass(frozen=True)
class Features(Settings):
    """HKS feature points (step 3, Sec. 6.2.4)."""

    n_times: int = setting(50, "HKS time scales h (thesis: 50)", low=1)
    max_features: int = setting(25, "most feature points kept, strongest first (thesis: d <= 25)", low=2)
    radius: float = setting(
        0.15, "feature points this close (edge-graph distance) to a stronger one are dropped; 0 keeps all",
        unit="x sqrt(area)", low=0.0,
    )


@dataclasses.dataclass(frozen=True)
class Pairs(Settings):
    """Sparse pairs of symmetric feature points (step 4, Eq. 6.1)."""

    max_feature_pairs: int = setting(5, "most sparse pairs c", low=1)
    max_cost: float = setting(0.5, "pairs with a larger affinity cost are not taken", low=0.0, low_open=True)
    penalty: float = setting(1e6, "q of Sec. 6.2.4", low=0.0, low_open=True)
    spectral_weight: float = setting(1.0, "weight of the phi^2 term of the affinity (0: HKS only)", low=0.0)


@dataclasses.dataclass(frozen=True)
class Signs(Settings):
    """Signs of the eigenfunctions (step 5 and the sign hypotheses of step 7, Sec. 6.2.5)."""

    cross_pairs: bool = setting(True, "also read signs from geodesics between two pairs")
    min_confidence: float = setting(0.0, "eigenfunctions with weaker sign evidence are left out of C (0: thesis)", low=0.0, high=1.0)
    n_uncertain: int = setting(3, "least-confident eigenfunctions whose both signs are tried (0: thesis)", low=0)


@dataclasses.dataclass(frozen=True)
class Correction(Settings):
    """Eigenfunction correction R on SO(k) (step 6, Eq. 6.4)."""

    enabled: bool = setting(True, "run the correction")
    mu: float = setting(0.01, "weight of the pairing term of Eq. 6.4 (unit-area eigenvalues / lambda_k)", low=0.0)
    max_iters: int = setting(50, "trust-region iterations per correction", low=1)


@dataclasses.dataclass(frozen=True)
class Hypotheses(Settings):
    """Hypotheses besides the thesis's pairs (steps 4 and 8, extensions)."""

    hks_pairs: bool = setting(True, "also pair the feature points on HKS alone (spectral_weight 0)")
    orientation: bool = setting(True, "also fit an orientation-reversing functional map to the dense HKS")
    sign_basis: int = setting(
        4, "also start from C = diag(1, s) in this many first eigenfunctions, every sign vector s but all +1 (0: off)",
        low=0, high=8,
    )
    sign_basis_below: float = setting(
        0.8, "the sign hypotheses are added only when no other hypothesis passes step 9 as a reflection of at least "
        "this score ((1 - distortion / select.score_distortion) x reversed share; above 1: always added)", low=0.0,
    )


@dataclasses.dataclass(frozen=True)
class Extrinsic(Settings):
    """The vertices' mirror plane as a hypothesis when the intrinsic ones are weak on a mesh with holes (step 10, an extension)."""

    enabled: bool = setting(True, "try the plane's map when the chosen intrinsic map is weak and the mesh has holes")
    min_score: float = setting(
        0.3, "least calibrated score of the plane (asymmetric clouds stay below 0.3) for its map to be used", low=0.0, high=1.0
    )
    max_points: int = setting(3000, "most vertices the plane is fitted to", low=10)
    weak_defect: float = setting(0.5, "a chosen map whose functional defect in k eigenfunctions exceeds this is weak", low=0.0)
    clearly: float = setting(
        0.6, "the plane's map also replaces a weak one when each of its tests is at most this share of the weak map's", low=0.0
    )


@dataclasses.dataclass(frozen=True)
class Select(Settings):
    """Choice of a hypothesis on a vertex sample (step 9, an extension)."""

    n_samples: int = setting(1000, "vertices on which the hypotheses are refined and compared (at least 4 x the basis)", low=50)
    max_search_vertices: int = setting(
        6000, "on larger meshes the sampled searches look among this many evenly spread vertices", low=50
    )
    max_distortion: float = setting(
        0.14, "largest sampled geodesic distortion for a hypothesis to replace the thesis's pairs (closed meshes)",
        low=0.0, low_open=True,
    )
    max_distortion_open: float = setting(0.12, "max_distortion for meshes with boundary edges (the input's, on a coarse copy)", low=0.0, low_open=True)
    score_distortion: float = setting(
        0.25, "the returned map's sampled geodesic distortion at which its score reaches 0", low=0.0, low_open=True
    )
    weak_score: float = setting(0.5, "below this score the result says the symmetry found is weak", low=0.0, high=1.0)
    near_self: float = setting(
        0.45, "share of probed vertices a map may leave within the tolerance of themselves (more: a partial identity)",
        low=0.0, high=1.0,
    )
    reflects: float = setting(
        0.5, "a hypothesis is taken for a reflection when its map reverses the orientation at this share of the sample",
        low=0.0, high=1.0,
    )


@dataclasses.dataclass(frozen=True)
class Refine(Settings):
    """ZoomOut refinement of the chosen map (step 11) and its orientation check (step 12), extensions."""

    enabled: bool = setting(True, "refine by ZoomOut (False: the thesis's dense map)")
    max_iters: int = setting(4, "ZoomOut rounds", low=1)
    n_eigen: int = setting(25, "eigenfunctions of the last round (at least the top n_eigen)", low=1)
    involution: bool = setting(True, "average each round's C with its inverse's and make it an orthogonal involution")
    orientation_weight: float = setting(300.0, "weight of the orientation penalty of step 12 (0 skips the check)", low=0.0)
    orientation_scales: tuple[float, ...] = setting((0.1, 1.0), "penalty weights tried in step 12, times orientation_weight", low=0.0)
    keeps_orientation: float = setting(
        0.5, "step 12 re-refines a map reversing the orientation at fewer sampled vertices than this", low=0.0, high=1.0
    )
    reverses_orientation: float = setting(
        0.6, "and takes a re-refined map reversing it at at least this share", low=0.0, high=1.0
    )
    reoriented_near_self: float = setting(
        0.5, "a re-refined map must leave fewer sampled vertices near themselves than this", low=0.0, high=1.0
    )
    rescue_distortion: float = setting(
        1.5, "when no hypothesis passed step 9, step 12's distortion limit is this many times step 9's", low=1.0
    )
    orientation_max_k: int = setting(50, "step 12 is skipped above this basis (its dense penalty grows as its fourth power)", low=1)
    before_refine_eps: float = setting(
        0.5, "approximation of the reported thesis's map where ZoomOut's replaced it (each image at most 1 + this too far)",
        low=0.0,
    )


@dataclasses.dataclass(frozen=True)
class Polish(Settings):
    """ZoomOut on into a larger basis after the choice (step 13, an extension)."""

    enabled: bool = setting(True, "polish the map (skipped when n_eigen <= refine.n_eigen)")
    max_iters: int = setting(3, "ZoomOut rounds", low=1)
    n_eigen: int = setting(40, "eigenfunctions of the last round (also raises the eigenpairs of step 2)", low=1)
    orientation_drop: float = setting(
        0.05, "the polished map is dropped when its reversed share falls by more than this (negative: drop every one)"
    )


@dataclasses.dataclass(frozen=True)
class Realign(Settings):
    """Realignment by distances to anchors (step 14, an extension)."""

    enabled: bool = setting(True, "realign maps that reverse the orientation at under 90 % of the sample")
    n_anchors: int = setting(64, "anchor vertices", low=1)
    max_iters: int = setting(3, "realignment rounds", low=1)
    below: float = setting(0.9, "the step runs on maps reversing the orientation at fewer sampled vertices than this", low=0.0)
    gain: float = setting(
        0.02, "a realigned map is kept when it reverses the orientation at this share more of the sample (negative: keep any)"
    )


@dataclasses.dataclass(frozen=True)
class Coarse(Settings):
    """Solving a large mesh on a decimated copy and carrying the map to every vertex (an extension)."""

    enabled: bool = setting(True, "solve meshes with more than max_vertices vertices on a decimated copy")
    max_vertices: int = setting(8000, "meshes with more vertices are solved on the copy", low=4)
    n_vertices: int = setting(5000, "most vertices of the copy (evenly spread input vertices)", low=4)

    def check(self) -> None:
        if self.n_vertices > self.max_vertices:
            raise ConfigError(
                f"coarse.n_vertices: expected at most coarse.max_vertices ({self.max_vertices}), got {self.n_vertices}"
            )


@dataclasses.dataclass(frozen=True)
class IntrinsicSymmetrySettings(Settings):
    """Settings of :func:`~torchsym.mesh.intrinsic.intrinsic_symmetry` (thesis Ch. 6).

    Thesis values where it gives one (``k = 13``, ``h = 50``, ``d <= 25``, a large ``q``),
    else chosen on a development split of FAUST/TOSCA (``hypotheses.sign_basis``,
    ``select.max_distortion`` and ``select.reflects`` on SHREC'07, ``docs/design/intrinsic.md``).
    The thesis's method alone:
    ``signs.n_uncertain = 0``, ``hypotheses.hks_pairs = hypotheses.orientation = False``,
    ``hypotheses.sign_basis = 0``,
    ``extrinsic.enabled = refine.enabled = polish.enabled = realign.enabled = False``
    (and ``coarse.enabled = False`` to solve every vertex).
    """

    seed: int = setting(0, "seed of the generator of the Module form", low=0)
    n_eigen: int = setting(13, "k, eigenfunctions of the thesis's map (thesis: 13)", low=3)
    components: Literal["largest", "refuse"] = setting("largest", "keep the largest connected component, or refuse several")
    fill_holes: bool = setting(True, "cover holes with new triangles before the spectrum")
    coarse: Coarse = group(Coarse)
    features: Features = group(Features)
    pairs: Pairs = group(Pairs)
    signs: Signs = group(Signs)
    correction: Correction = group(Correction)
    hypotheses: Hypotheses = group(Hypotheses)
    extrinsic: Extrinsic = group(Extrinsic)
    select: Select = group(Select)
    refine: Refine = group(Refine)
    polish: Polish = group(Polish)
    realign: Realign = group(Realign)
