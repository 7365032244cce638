"""Nearest neighbours: scipy's cKDTree for CPU tensors, chunked ``torch.cdist`` elsewhere.

On a CPU, a kd-tree answers a query in O(log n) and is about 50x faster than a dense
distance matrix; on a GPU a chunked ``cdist`` + ``topk`` keeps everything on the device.
"""

from __future__ import annotations

import numpy as np
import torch
from scipy.spatial import cKDTree

__all__ = ["KNNIndex", "mutual_nearest"]


class KNNIndex:
    """An index over ``(N, D)`` points answering k-nearest-neighbour queries.

    Args:
        points: ``(N, D)`` reference points.
        workers: threads for the CPU kd-tree query (at most 2 on small machines).
        chunk: query rows per ``cdist`` block on non-CPU devices.
    """

    def __init__(self, points: torch.Tensor, *, workers: int = 2, chunk: int = 4096) -> None:
        self.points = points
        self.workers = workers
        self.chunk = chunk
        self.on_cpu = points.device.type == "cpu"
        self._tree = cKDTree(points.detach().to(torch.float64).numpy()) if self.on_cpu else None

    def query(
        self, queries: torch.Tensor, k: int = 1, *, max_distance: float = float("inf")
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Distances and indices of the ``k`` nearest reference points.

        Args:
            queries: ``(M, D)`` query points.
            k: neighbours per query.
            max_distance: neighbours farther than this are not searched for: their
                distance is ``inf`` and their index ``N`` (one past the last point). Far
                queries are the slow ones, so a bound speeds up scoring with kernels that
                ignore large residuals anyway.

        Returns:
            ``dist (M,)`` and ``index (M,)`` int64 for ``k == 1``, else ``(M, k)`` each.
        """
        if self._tree is not None:
            # threads only pay off on large batches: starting them costs ~0.1 ms each
            workers = self.workers if queries.shape[0] * k >= 20000 else 1
            d, i = self._tree.query(
                queries.detach().to(torch.float64).numpy(), k=k, workers=workers, distance_upper_bound=max_distance
            )
            dist = torch.from_numpy(np.asarray(d)).to(queries.dtype)
            idx = torch.from_numpy(np.asarray(i, dtype=np.int64))
            return dist, idx
        ds, js = [], []
        for start in range(0, queries.shape[0], self.chunk):
            block = torch.cdist(queries[start : start + self.chunk], self.points)  # (m, N)
            d, j = block.topk(k, dim=1, largest=False)
            ds.append(d)
            js.append(j)
        dist, idx = torch.cat(ds), torch.cat(js)
        far = dist > max_distance
        dist = dist.masked_fill(far, float("inf"))
        idx = idx.masked_fill(far, self.points.shape[0])
        return (dist[:, 0], idx[:, 0]) if k == 1 else (dist, idx)


def mutual_nearest(forward: torch.Tensor, backward: torch.Tensor) -> torch.Tensor:
    """``(M,)`` bool: whether match ``i -> forward[i]`` is returned, ``backward[forward[i]] == i``."""
    return backward[forward] == torch.arange(forward.shape[0], device=forward.device)
