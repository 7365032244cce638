"""Nearest neighbours: scipy's cKDTree for CPU tensors; on other devices, brute force or the tree.

On a CPU, a kd-tree answers a query in O(log n) and is about 50x faster than a dense
distance matrix. On a GPU, brute force keeps small problems on the device: chunked
``cdist`` in its matrix-product form, in float64 on centred coordinates, picks ``k + 4``
candidates and their exact differences order them (the product form alone, in float32,
swapped close neighbours in 0.02-0.2 % of queries on a unit cube and returned a wrong
neighbour for most queries on a cloud 1 km wide; the exact form of ``cdist`` is 20-60x
slower). Its cost grows with
queries x points, so past ``brute_force_max`` distances a query copies the points to the
host and asks a kd-tree built there once. On an H100 beside 2 CPU threads the two cross
between 1e8 and 1e9 distances for one neighbour, later for more
(``benchmarks/results/device.md``).
"""

from __future__ import annotations

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.core.parallel import thread_budget
from torchsym.errors import InputValueError

__all__ = ["KNNIndex", "mutual_nearest"]

BRUTE_FORCE_MAX = 300_000_000  # queries x points above which a device query uses the host's kd-tree
RERANK_MARGIN = 4  # extra brute-force candidates whose exact distances are compared


class KNNIndex:
    """An index over ``(N, D)`` points answering k-nearest-neighbour queries.

    Args:
        points: ``(N, D)`` reference points.
        workers: threads for the CPU kd-tree query (default: :func:`~torchsym.core.parallel.thread_budget` at query time).
        chunk: query rows per ``cdist`` block on non-CPU devices.
        brute_force_max: on non-CPU devices, the most query-point distances a query computes
            by brute force; larger queries go to a kd-tree on the host, built on first use.
        method: ``"auto"`` (the tree on the CPU, the rule above elsewhere), ``"tree"`` or
            ``"brute"`` on any device.
    """

    def __init__(
        self,
        points: torch.Tensor,
        *,
        workers: int | None = None,
        chunk: int = 4096,
        brute_force_max: float = BRUTE_FORCE_MAX,
        method: str = "auto",
    ) -> None:
        if method not in ("auto", "tree", "brute"):
            raise InputValueError(f"method: expected 'auto', 'tree' or 'brute', got {method!r}")
        self.points = points
        self.workers = workers
        self.chunk = chunk
        self.brute_force_max = brute_force_max
        if method == "auto":
            method = "tree" if points.device.type == "cpu" else "auto"
        self.method = method
        self._tree = self._build() if method == "tree" else None
        self._points64: torch.Tensor | None = None
        self._centre: torch.Tensor | None = None
        self._centred: torch.Tensor | None = None

    def _build(self) -> cKDTree:
        return cKDTree(self.points.detach().to("cpu", torch.float64).numpy())

    def query(
        self, queries: torch.Tensor, k: int = 1, *, max_distance: float = float("inf")
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Distances and indices of the ``k`` nearest reference points.

        Args:
            queries: ``(M, D)`` query points.
            k: neighbours per query.
            max_distance: neighbours at this distance or farther are not searched for:
                their distance is ``inf`` and their index ``N`` (one past the last point). Far
                queries are the slow ones, so a bound speeds up scoring with kernels that
                ignore large residuals anyway.

        Returns:
            ``dist (M,)`` in the queries' floating dtype (float64 for integer queries) and ``index (M,)`` int64 for ``k == 1``, else
            ``(M, k)`` each; with fewer than ``k`` points the missing neighbours are ``inf``
            and ``N``, as from the kd-tree.
        """
        out_dtype = queries.dtype if queries.is_floating_point() else torch.float64
        big = queries.shape[0] * self.points.shape[0] > self.brute_force_max
        if self.method == "tree" or (self.method == "auto" and big):
            if self._tree is None:
                self._tree = self._build()
            # threads only pay off on large batches: starting them costs ~0.1 ms each
            workers = (self.workers or thread_budget()) if queries.shape[0] * k >= 20000 else 1
            d, i = self._tree.query(
                queries.detach().to("cpu", torch.float64).numpy(), k=k, workers=workers, distance_upper_bound=max_distance
            )
            dist = torch.from_numpy(np.asarray(d)).to(queries.device, out_dtype)
            idx = torch.from_numpy(np.asarray(i, dtype=np.int64)).to(queries.device)
            return dist, idx
        n_pts, m = self.points.shape[0], queries.shape[0]
        dist = torch.full((m, k), float("inf"), dtype=out_dtype, device=queries.device)
        idx = torch.full((m, k), n_pts, dtype=torch.int64, device=queries.device)
        if self._points64 is None:
            # float64 throughout: the product form's rounding grows with the cloud's extent
            # squared, and in float32 it swamps the spacing of a wide cloud (a scan 1 km across)
            self._points64 = self.points.detach().to(torch.float64)
            self._centre = self._points64.mean(dim=0)
            self._centred = self._points64 - self._centre
        k_eff = min(k, n_pts)
        n_cand = min(n_pts, k + RERANK_MARGIN)
        for start in range(0, m, self.chunk):
            q = queries[start : start + self.chunk].detach().to(torch.float64)
            # candidates by the fast matrix-product form |x|^2 + |y|^2 - 2 x.y on centred
            # coordinates, which can still swap near-equidistant neighbours; their exact
            # distances decide the order
            _, cand = torch.cdist(q - self._centre, self._centred).topk(n_cand, dim=1, largest=False)  # (m', k')
            exact = (q[:, None, :] - self._points64[cand]).norm(dim=-1)  # (m', k')
            d, order = exact.topk(k_eff, dim=1, largest=False)
            dist[start : start + q.shape[0], :k_eff] = d.to(out_dtype)
            idx[start : start + q.shape[0], :k_eff] = cand.gather(1, order)
        far = dist >= max_distance  # as the kd-tree: a neighbour at max_distance is not returned
        dist = dist.masked_fill(far, float("inf"))
        idx = idx.masked_fill(far, n_pts)
        return (dist[:, 0], idx[:, 0]) if k == 1 else (dist, idx)


def mutual_nearest(forward: torch.Tensor, backward: torch.Tensor) -> torch.Tensor:
    """``(M,)`` bool: whether match ``i -> forward[i]`` is returned, ``backward[forward[i]] == i``."""
    return backward[forward] == torch.arange(forward.shape[0], device=forward.device)
