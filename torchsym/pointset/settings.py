"""Settings of PointSymm (thesis Ch. 7): one frozen dataclass, grouped by stage."""

from __future__ import annotations

import dataclasses
from typing import Literal

from torchsym.core.random import DEFAULT_SEED
from torchsym.core.settings import Settings, group, setting

__all__ = ["AssignmentSettings", "InitSettings", "PointSymmSettings", "ScanSettings", "SoftSettings"]


@dataclasses.dataclass(frozen=True)
class InitSettings(Settings):
    """The randomised pair search that starts the alternation (Sec. 7.2.4)."""

    method: Literal["search", "thesis"] = setting(
        "search", "'search' (tests on k-d tree neighbours, verified and polished) or 'thesis' (Sec. 7.2.4 word for word)"
    )
    n_runs: int = setting(10, "runs of the pair search, each giving one plane (thesis: 10)", low=1)
    eps_theta: float = setting(2.0, "angle tolerance between the two pairs' bisecting planes", unit="deg", low=0.0, high=90.0)
    eps_d: float = setting(0.05, "relative tolerance on the two pairs' distances to the plane", low=0.0, high=1.0)
    n_starts: int = setting(4, "most starting planes: the median plane, then the best runs' own planes", low=1)


@dataclasses.dataclass(frozen=True)
class ScanSettings(Settings):
    """Extra starts from a scan of planes through the centroid, when the best plane scores below 0.5."""

    enabled: bool = setting(True, "scan when the pair search's plane leaves most points without an exact mirror")
    n_normals: int = setting(200, "directions scanned besides the principal axes", low=1)
    n_starts: int = setting(4, "best scanned planes (at least 10 deg apart) the alternation also starts from", low=1)


@dataclasses.dataclass(frozen=True)
class AssignmentSettings(Settings):
    """The correspondence step: the mirror of every point (Sec. 7.2.3)."""

    method: Literal["auto", "exact", "sparse"] = setting(
        "auto", "'exact' (dense Jonker-Volgenant), 'sparse' (k nearest neighbours) or 'auto' (exact up to max_exact_points)"
    )
    n_neighbors: int = setting(10, "candidate mirrors per point of the sparse assignment", low=1)
    max_exact_points: int = setting(500, "largest N solved exactly under 'auto' (4x with match_fraction < 1)", low=2)


@dataclasses.dataclass(frozen=True)
class SoftSettings(Settings):
    """The plane refined by EM on soft, Sinkhorn-balanced correspondences after the hard fit."""

    enabled: bool = setting(True, "refine the plane on soft correspondences (skipped for exact symmetries and match_fraction < 1)")
    n_neighbors: int = setting(16, "candidate mirrors per point of the soft correspondences", low=1)
    max_iters: int = setting(100, "EM iterations at most", low=1)
    tol_se: float = setting(
        0.005, "stop when the normal moves less than this many standard errors of its fit (what is left to go included)",
        unit="x standard error", low=0.0,
    )


@dataclasses.dataclass(frozen=True)
class PointSymmSettings(Settings):
    """Settings of :func:`~torchsym.pointset.point_symm` (thesis Ch. 7, Algorithm 7)."""

    max_iters: int = setting(50, "alternations of the correspondences and (R, t) ('till convergence')", low=1)
    max_trust_region_dim: int = setting(
        16, "largest D whose (R, t) step runs the trust region (Sec. 7.2.2); above it, the closed-form least-squares reflection", low=2
    )
    match_fraction: float = setting(1.0, "largest fraction of points that get a mirror (Sec. 7.4.4)", low=0.0, high=1.0, low_open=True)
    init: InitSettings = group(InitSettings)
    scan: ScanSettings = group(ScanSettings)
    assignment: AssignmentSettings = group(AssignmentSettings)
    soft: SoftSettings = group(SoftSettings)
    max_points: int = setting(10_000, "largest N accepted (subsample larger sets)", low=2)
    max_dim: int = setting(512, "largest D accepted (the result holds D-1 dense D x D rotations)", low=2)
    seed: int = setting(DEFAULT_SEED, "seed of the generator a module uses when called without one", low=0)
