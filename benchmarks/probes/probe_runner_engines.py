"""What two workers can give on this machine: the same plane detections serially, on a
plain 2-process pool and on a plain 2-worker Dask ``LocalCluster`` (no runner), interleaved.

Each task reads one cloud of ``benchmarks/bench_runner.py``'s set and runs
``torchsym.detect`` on it with one thread (torch, BLAS, OpenMP); it returns its own
seconds. Items per second leave out the start-up (one warm-up task per worker). The pool
is the bound of two independent processes; Dask is the engine the runner is built on
(docs/design/runner.md), so the runner's speed-up is compared with these.

Usage: python benchmarks/probes/probe_runner_engines.py [--work /tmp/bench_runner] [--n 40] [--repeats 3]
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]  # benchmarks/
sys.path.insert(0, str(HERE))
from report import write_report  # noqa: E402 -- benchmarks/report.py


def task(path: str) -> float:
    import torch
    from threadpoolctl import threadpool_limits

    import torchsym

    torch.set_num_threads(1)
    with threadpool_limits(1):
        t = time.perf_counter()
        torchsym.detect(torch.from_numpy(np.load(path)))
        return time.perf_counter() - t


def serial(paths: list[str], warm: str) -> tuple[float, float]:
    task(warm)
    t = time.perf_counter()
    r = [task(p) for p in paths]
    return len(paths) / (time.perf_counter() - t), statistics.mean(r)


def pool(paths: list[str], warm: str) -> tuple[float, float]:
    with mp.get_context("spawn").Pool(2) as p:
        p.map(task, [warm, warm], chunksize=1)
        t = time.perf_counter()
        r = p.map(task, paths, chunksize=1)
        return len(paths) / (time.perf_counter() - t), statistics.mean(r)


def dask_local(paths: list[str], warm: str) -> tuple[float, float]:
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as c, Client(c) as cl:
        cl.gather(cl.map(task, [warm, warm], pure=False))
        t = time.perf_counter()
        r = cl.gather(cl.map(task, paths, pure=False))
        return len(paths) / (time.perf_counter() - t), statistics.mean(r)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default="/tmp/bench_runner")
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args()
    clouds = sorted(str(p) for p in (Path(args.work) / "clouds").glob("*.npy"))
    if len(clouds) < args.n + 1:
        raise SystemExit(f"run benchmarks/bench_runner.py first: {args.work}/clouds holds {len(clouds)} clouds")
    warm, paths = clouds[0], clouds[1 : args.n + 1]
    engines = {"serial": serial, "process pool (2)": pool, "Dask LocalCluster (2)": dask_local}
    runs: dict[str, list[tuple[float, float]]] = {k: [] for k in engines}
    for rep in range(args.repeats):
        for name, fn in engines.items():
            runs[name].append(fn(paths, warm))
            print(f"{rep} {name}: {runs[name][-1][0]:.2f} items/s, task {runs[name][-1][1]:.3f} s", flush=True)
    base = statistics.mean(x[0] for x in runs["serial"])
    lines = [
        "# Two workers on this machine: serial, a plain process pool, plain Dask (no runner)",
        "",
        f"`python benchmarks/probes/probe_runner_engines.py --n {args.n} --repeats {args.repeats}`: {args.n} clouds of "
        f"`bench_runner.py` (plane detection, 1 thread), the three engines interleaved {args.repeats} times; "
        f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the end.",
        "",
        "| engine | items/s per repeat | mean | x serial | mean task s |",
        "|---|---|---|---|---|",
    ]
    for name, r in runs.items():
        ips = [x[0] for x in r]
        lines.append(f"| {name} | {', '.join(f'{v:.2f}' for v in ips)} | {statistics.mean(ips):.2f} | "
                     f"{statistics.mean(ips) / base:.2f}x | {statistics.mean(x[1] for x in r):.3f} |")
    write_report(args.out, "runner_engines", "\n".join(lines) + "\n", {"args": vars(args), "runs": runs})


if __name__ == "__main__":
    main()
