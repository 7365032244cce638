"""A quick benchmark that ships with the package (``torchsym bench``).

The full benchmarks, with the thesis's protocols and peer tools, are the scripts in
``benchmarks/`` of the source tree; this one needs nothing but the package.
"""

from __future__ import annotations

import math
import statistics
import sys
import time

__all__ = ["quick_pointcloud_benchmark"]


def quick_pointcloud_benchmark(n: int = 30000, repeats: int = 5) -> list[dict[str, float]]:
    """Time :func:`detect_reflection_plane` on planted clouds beside one kd-tree build and query.

    Prints a table and returns its rows.
    """
    from tqdm import tqdm

    from torchsym.geometry import plane_angle
    from torchsym.matching import KNNIndex
    from torchsym.pointcloud import detect_reflection_plane, planted_symmetric_cloud

    rows = []
    for seed in tqdm(range(repeats), desc=f"bench {n} points", unit="cloud", file=sys.stderr, leave=False):
        cloud = planted_symmetric_cloud(n, generator=seed)
        t0 = time.perf_counter()
        res = detect_reflection_plane(cloud.points)
        t1 = time.perf_counter()
        KNNIndex(cloud.points).query(cloud.points)
        t2 = time.perf_counter()
        rows.append({"seed": seed, "seconds": t1 - t0, "knn_seconds": t2 - t1,
                     "angle_error_deg": float(plane_angle(res.normal, cloud.normal)) * 180 / math.pi, "score": res.score})
    print(f"{'seed':>4} {'time s':>8} {'kNN s':>8} {'ratio':>6} {'error deg':>10} {'score':>6}")
    for r in rows:
        print(f"{r['seed']:>4} {r['seconds']:8.3f} {r['knn_seconds']:8.3f} {r['seconds'] / r['knn_seconds']:6.1f} {r['angle_error_deg']:10.5f} {r['score']:6.3f}")
    med = statistics.median(r["seconds"] for r in rows)
    medk = statistics.median(r["knn_seconds"] for r in rows)
    print(f"median {med:.3f} s per cloud of {n} points; one kd-tree build + query {medk:.3f} s; ratio {med / medk:.1f}")
    return rows
