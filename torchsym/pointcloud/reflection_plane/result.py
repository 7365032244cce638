"""The result of the reflection-plane detector, and the mirror pairs it reports."""

from __future__ import annotations

import dataclasses

import torch

from torchsym.core.results import Result
from torchsym.geometry.reflection import canonical_sign, reflect_points, reflection_matrix, reflection_transform
from torchsym.matching.knn import mutual_nearest
from torchsym.pointcloud.prepare import Normalised

__all__ = ["MirrorPairs", "ReflectionPlaneResult", "make_result", "mirror_pairs"]


@dataclasses.dataclass(frozen=True)
class ReflectionPlaneResult(Result):
    """The reflection plane of a point cloud.

    Attributes:
        normal: ``(3,)`` unit normal of the plane, largest-magnitude component positive.
        offset: ``()`` offset: the plane is ``normal . x + offset = 0``.
        matrix: ``(3, 3)`` the reflection's linear part ``I - 2 n n^T`` (the thesis's S).
        transform: ``(4, 4)`` homogeneous reflection acting on ``[x; 1]``.
        center: ``(3,)`` the thesis's ``c``: the centroid of the matched pairs' midpoints,
            a point on the plane.
        pairs: ``(M, 2)`` int64 index pairs ``(i, j)``, ``i <= j``, of mutual
            nearest-neighbour mirror points within the tolerance (``i == j``: a point on
            the plane).
        inliers: ``(N,)`` bool, points whose mirror image lands within the tolerance of
            the cloud.
        residual: median distance from a point's mirror image to its nearest point, over
            all points, in input units, at the plane of the last Algorithm 6 step (within
            the alternation's tolerances of ``normal``/``offset``).
        score: in [0, 1], the share of points off the plane whose mirror image lands within
            the tolerance, corrected for chance: ``(s - s0) / (1 - s0)`` with ``s0`` the
            highest share under random planes through the cloud (0: no better than chance).
        tolerance: the inlier distance used (``inlier_factor`` x the median spacing), in
            input units.
        iterations: alignment steps taken by the winning start (subsample + whole cloud).
        converged: whether the polish met the angle and offset tolerances.
        n_starts: starts refined.
        timings: seconds per stage: ``init``, ``refine``, ``polish``, ``kernel``, ``total``.
    """

    normal: torch.Tensor
    offset: torch.Tensor
    matrix: torch.Tensor
    transform: torch.Tensor
    center: torch.Tensor
    pairs: torch.Tensor
    inliers: torch.Tensor
    residual: float
    score: float
    tolerance: float
    iterations: int
    converged: bool
    n_starts: int
    timings: dict[str, float]

    def reflect(self, points: torch.Tensor) -> torch.Tensor:
        """Reflect ``(..., N, 3)`` points through the detected plane."""
        return reflect_points(points, self.normal.to(points), self.offset.to(points))


@dataclasses.dataclass(frozen=True)
class MirrorPairs:
    """Inliers ``(N,)`` bool, pairs ``(M, 2)`` int64 and centre ``(3,)`` on the plane
    (normalised units), as in :class:`ReflectionPlaneResult`."""

    inliers: torch.Tensor
    pairs: torch.Tensor
    center: torch.Tensor


def mirror_pairs(xs, dist, nn_idx, tol: float, normal, offset) -> MirrorPairs:
    """The mutual mirror pairs of ``xs (N, 3)`` within ``tol``, from each point's mirror
    residual ``dist (N,)`` and nearest point ``nn_idx (N,)``, and the centroid of their
    midpoints projected on the plane (of all points when there is no pair)."""
    n = xs.shape[0]
    inliers = dist <= tol
    mutual = mutual_nearest(nn_idx, nn_idx)
    idx = torch.arange(n, device=nn_idx.device)
    good = inliers & mutual & (idx <= nn_idx)
    pairs = torch.stack([idx[good], nn_idx[good]], dim=1)
    keep = mutual & inliers
    mids = 0.5 * (xs[keep] + xs[nn_idx[keep]]) if bool(keep.any()) else xs
    center = mids.mean(0)
    center = center - ((center @ normal) + offset) * normal  # project onto the plane
    return MirrorPairs(inliers, pairs, center)


def make_result(
    norm: Normalised,
    normal: torch.Tensor,
    offset: torch.Tensor,
    found: MirrorPairs,
    dist: torch.Tensor,
    tol: float,
    score: float,
    out_dtype: torch.dtype,
    *,
    iterations: int,
    converged: bool,
    n_starts: int,
    timings: dict[str, float],
) -> ReflectionPlaneResult:
    """The result in input units and ``out_dtype``, normal sign made canonical; ``dist``
    and ``tol`` as in :func:`mirror_pairs`, ``score`` and the other fields as in the result."""
    normal, offset = canonical_sign(normal, offset)
    normal_o = normal.to(out_dtype)
    offset_o = (offset * norm.scale - (normal * norm.origin).sum()).to(out_dtype)
    center_o = (found.center * norm.scale + norm.origin).to(out_dtype)
    return ReflectionPlaneResult(
        normal=normal_o,
        offset=offset_o,
        matrix=reflection_matrix(normal_o),
        transform=reflection_transform(normal_o, offset_o),
        center=center_o,
        pairs=found.pairs,
        inliers=found.inliers,
        residual=float(dist.median()) * norm.scale,
        score=float(score),
        tolerance=tol * norm.scale,
        iterations=int(iterations),
        converged=bool(converged),
        n_starts=n_starts,
        timings=timings,
    )
