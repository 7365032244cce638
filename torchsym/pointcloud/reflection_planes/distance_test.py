"""The geometric test of a symmetry: does the transform move the surface onto itself as
closely as two samples of the surface lie from each other?

A cloud is split at random into halves ``A`` and ``B``: two independent samples of one
surface. The sampling distance is the mean distance from points of ``A`` to ``B``; a
transform ``T`` (a reflection, or a rotation for :mod:`.revolution`) is an exact symmetry
when the mean distance from ``T(A)`` to ``B`` is about the same, and no symmetry when it is
several times larger. Their quotient, the *distance ratio*, is the truth criterion of the
dev set (``benchmarks/bench_planes.py``) measured on the input itself; thesis Sec. 5.2
measures the same residual ``|S P - P Pi|`` (Eq. 5.3) without the sampling baseline.
Points are normalised (unit bounding-box diagonal) or in any units: the ratio has none.
"""

from __future__ import annotations

import dataclasses

import torch

from torchsym.core.random import random_subset
from torchsym.geometry.reflection import reflection_transform
from torchsym.matching.knn import KNNIndex

__all__ = ["DistanceTest", "distance_test", "split_test"]


@dataclasses.dataclass(frozen=True)
class DistanceTest:
    """Two independent samples of one surface, ready to measure distance ratios.

    Attributes:
        queries: ``(Q, 3)`` points of the first sample.
        index: nearest-neighbour index over the second sample.
        base: mean distance from ``queries`` to the second sample (the sampling distance).
        local: None, or the first sample's index and ``(N1,)`` each of its points'
            distance to the second sample: the sampling distance is then measured where
            the moved queries land (the mean over the first sample's points nearest to
            them), so that a density falling across the shape does not raise the ratio
            of a transform that moves dense parts onto sparse ones.
    """

    queries: torch.Tensor
    index: KNNIndex
    base: float
    local: tuple[KNNIndex, torch.Tensor] | None = None

    def ratio(self, transform: torch.Tensor) -> float:
        """Mean distance from ``transform (4, 4)`` applied to the queries to the second
        sample, over :attr:`base` (inf when the base is 0)."""
        return float(self.ratios(transform[None])[0])

    def ratios(self, transforms: torch.Tensor, *, bound: float = float("inf")) -> torch.Tensor:
        """:meth:`ratio` of each of ``transforms (K, 4, 4)``: ``(K,)``, from one query.

        With a finite ``bound``, transforms whose ratio exceeds it get a value above the
        bound but not necessarily their ratio (far queries, the slow ones, are cut off at
        ``4 x bound`` sampling distances, and only the others are measured exactly)."""
        t = transforms.to(self.queries)
        k = t.shape[0]
        if k == 0:
            return torch.zeros(0, dtype=self.queries.dtype, device=self.queries.device)
        if self.base <= 0:
            return torch.full((k,), float("inf"), dtype=self.queries.dtype, device=self.queries.device)
        moved = self.queries @ t[:, :3, :3].transpose(1, 2) + t[:, None, :3, 3]  # (K, Q, 3)
        cut = 4.0 * bound * self.base
        d, _ = self.index.query(moved.reshape(-1, 3), max_distance=cut)
        d = d.reshape(k, -1)
        base = self._bases(moved)  # (K,)
        ratio = d.clamp_max(cut).mean(1) / base  # a lower bound; exact when nothing was cut
        redo = (ratio <= bound) & torch.isinf(d).any(1)
        for j in redo.nonzero()[:, 0].tolist():
            ratio[j] = self.index.query(moved[j])[0].mean() / base[j]
        return ratio

    def far_shares(self, transforms: torch.Tensor, factor: float = 3.0) -> torch.Tensor:
        """``(K,)`` the share of the queries that each of ``transforms (K, 4, 4)`` moves
        farther than ``factor`` sampling distances from the second sample, less the same
        share unmoved (the split's own far share). The mean distance forgives a small
        part moved far (a hexagonal bolt head turned by a generic angle, the edges of a
        filled cube or of a flat patch); this tail does not."""
        t = transforms.to(self.queries)
        cut = factor * self.base
        moved = self.queries @ t[:, :3, :3].transpose(1, 2) + t[:, None, :3, 3]
        d, _ = self.index.query(moved.reshape(-1, 3), max_distance=cut)
        d0, _ = self.index.query(self.queries, max_distance=cut)
        far = torch.isinf(d.reshape(t.shape[0], -1)).double().mean(1)
        return (far - torch.isinf(d0).double().mean()).to(self.queries.dtype)

    def _bases(self, moved: torch.Tensor) -> torch.Tensor:
        """``(K,)`` the sampling distance for each transform's moved queries ``(K, Q, 3)``."""
        k = moved.shape[0]
        if self.local is None:
            return torch.full((k,), self.base, dtype=moved.dtype, device=moved.device)
        index, dist = self.local
        # far images (not a symmetry) take the global sampling distance: their search is the slow one
        _, j = index.query(moved.reshape(-1, 3), max_distance=4.0 * self.base)
        dist = torch.cat([dist, dist.new_full((1,), self.base)])
        base = dist[j].reshape(k, -1).mean(1).to(moved.dtype)
        return torch.where(base > 0, base, torch.full_like(base, self.base))

    def plane_ratios(self, normals: torch.Tensor, offsets: torch.Tensor, *, bound: float = float("inf")) -> torch.Tensor:
        """:meth:`ratios` of the reflections in planes ``normals (K, 3)``, ``offsets (K,)``."""
        if normals.shape[0] == 0:
            return torch.zeros(0, dtype=self.queries.dtype, device=self.queries.device)
        return self.ratios(reflection_transform(normals, offsets), bound=bound)


def distance_test(
    first: torch.Tensor, second: torch.Tensor, n_queries: int, generator: torch.Generator, *, local: bool = False
) -> DistanceTest:
    """A :class:`DistanceTest` from two independent samples ``first (N, 3)`` and
    ``second (M, 3)`` of one surface, with up to ``n_queries`` random points of ``first``;
    ``local``: the sampling distance measured where the moved queries land."""
    queries = first[random_subset(first.shape[0], n_queries, generator)]
    index = KNNIndex(second)
    d, _ = index.query(queries)
    loc = None
    if local:
        loc = (KNNIndex(first), index.query(first)[0])
    return DistanceTest(queries, index, float(d.mean()), loc)


def split_test(points: torch.Tensor, n_queries: int, generator: torch.Generator, *, local: bool = False) -> DistanceTest:
    """A :class:`DistanceTest` from a random split of ``points (N, 3)`` into halves, of
    its distinct points: a point listed twice would land in both halves at distance 0,
    and a cloud of every point twice would have no sampling distance (and no plane)."""
    points = torch.unique(points, dim=0)
    perm = torch.randperm(points.shape[0], generator=generator)
    half = points.shape[0] // 2
    return distance_test(points[perm[:half]], points[perm[half:]], n_queries, generator, local=local)
