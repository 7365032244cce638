"""Settings of the whole-group detector: the every-plane detector's, the rotation axes
found directly, and the group's closure."""

from __future__ import annotations

import dataclasses

from torchsym.core.settings import Settings, group, setting
from torchsym.pointcloud.reflection_planes.settings import ReflectionPlanesSettings

__all__ = ["GroupSettings", "RotationSettings", "SymmetrySettings"]


@dataclasses.dataclass(frozen=True)
class RotationSettings(Settings):
    """Rotation axes found directly (chiral shapes have no plane), each tested like a plane."""

    enabled: bool = setting(True, "look for rotation axes directly, not only those the planes imply")
    max_order: int = setting(12, "highest order n tested (rotations by 2 pi / n, n = 2 .. max_order)", low=2, high=64)
    max_ratio: float = setting(
        1.6, "accept a rotation whose images lie at most this far from the cloud", unit="x sampling distance", low=1.0
    )
    refine_ratio: float = setting(
        12.0, "candidate axes whose best rotation lies within this are refined and tested", unit="x sampling distance",
        low=1.0,
    )
    relative_ratio: float = setting(
        1.15, "... and within this factor of the axis's best order's ratio (near-cylinders pass many orders)", low=1.0
    )
    max_far_share: float = setting(
        0.02, "... moving at most this share more of the points beyond 3 sampling distances than the split itself",
        low=0.0, high=1.0,
    )
    n_queries: int = setting(1500, "points the ICP refinement of an axis moves", low=16, high=100000)
    min_score: float = setting(0.05, "... and whose share of points moved onto the surface beats chance by this", low=0.0, high=1.0)
    rotoreflections: bool = setting(True, "test the rotoreflection by pi / n about each n-fold axis, and the inversion")


@dataclasses.dataclass(frozen=True)
class GroupSettings(Settings):
    """The closure of every symmetry found into one point group."""

    tol: float = setting(0.05, "two elements are one within this Frobenius distance of their linear parts", low=0.0, low_open=True, high=1.0)
    max_order: int = setting(240, "most discrete elements generated", low=1, high=10000)


@dataclasses.dataclass(frozen=True)
class SymmetrySettings(Settings):
    """Settings of :func:`~torchsym.pointcloud.detect_symmetry`."""

    planes: ReflectionPlanesSettings = group(ReflectionPlanesSettings)
    rotations: RotationSettings = group(RotationSettings)
    group: GroupSettings = group(GroupSettings)
