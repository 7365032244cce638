"""Where a task loses time on a Dask worker: the same plane detections in the driver (its
main thread, a second thread) and on a one-worker ``LocalCluster`` with Dask's defaults,
without the nanny's ``MALLOC_TRIM_THRESHOLD_``, without the profiler, with the runner's
worker set-up (:class:`torchsym.runner.worker.WorkerSetup`), and with it and the local
engine's quiet event loop (:data:`torchsym.runner.engine.QUIET`), as the runner's local
cluster runs them, interleaved.

Each task runs ``torchsym.detect`` on one cloud of ``benchmarks/bench_runner.py``'s set
with ``configs/pointcloud_plane.yaml`` and one thread, and measures its wall time, its
thread's CPU time, its whole process's CPU time meanwhile (a worker's event loop and
profiler included) and its thread's minor page faults. CPU time and page faults depend
far less on the machine's load than wall time, which is why they are the figures to
read on a shared machine. Medians over ``--n`` clouds after one warm-up task.

Usage: python benchmarks/probes/probe_runner_engines.py [--work /tmp/bench_runner] [--n 12] [--repeats 2]
"""

from __future__ import annotations

import argparse
import logging
import os
import statistics
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE.parent), str(HERE)]

from bench_runner import CLOUD_CONFIG, machine, own_environ, peer_task  # noqa: E402
from report import write_report  # noqa: E402

FIELDS = ("wall", "cpu", "process_cpu", "faults")


def _task(path: str) -> tuple[float, float, float, int]:
    return peer_task(path, CLOUD_CONFIG)


def in_driver(paths: list[str], warm: str, thread: bool) -> list[tuple]:
    if not thread:
        _task(warm)
        return [_task(p) for p in paths]
    with ThreadPoolExecutor(1) as ex:
        ex.submit(_task, warm).result()
        return list(ex.map(_task, paths))


def on_worker(paths: list[str], warm: str, variant: str) -> list[tuple]:
    import dask
    from distributed import Client, LocalCluster

    from torchsym.runner.worker import WorkerSetup

    cfg: dict = {}
    if variant == "no trim":
        cfg["distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"] = None  # None: not set
    if variant == "no profiler":
        cfg["distributed.worker.profile.enabled"] = False
    if variant == "runner":
        from torchsym.runner.engine import QUIET

        cfg.update(QUIET)
    with own_environ(), dask.config.set(cfg), LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                            dashboard_address=None, silence_logs=logging.ERROR) as c, Client(c) as cl:
        if variant in ("runner set-up", "runner"):
            cl.register_plugin(WorkerSetup(1))
        cl.submit(_task, warm, pure=False).result()
        return [cl.submit(_task, p, pure=False).result() for p in paths]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default="/tmp/bench_runner")
    ap.add_argument("--n", type=int, default=12)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--out", default=str(HERE.parent / "results"))
    args = ap.parse_args()
    clouds = sorted(str(p) for p in (Path(args.work) / "clouds").glob("*.npy"))
    if len(clouds) < args.n + 1:
        raise SystemExit(f"run benchmarks/bench_runner.py first: {args.work}/clouds holds {len(clouds)} clouds")
    warm, paths = clouds[0], clouds[1 : args.n + 1]
    variants = {
        "driver, main thread": lambda: in_driver(paths, warm, False),
        "driver, second thread": lambda: in_driver(paths, warm, True),
        "Dask worker, Dask's defaults": lambda: on_worker(paths, warm, "defaults"),
        "Dask worker, no MALLOC_TRIM_THRESHOLD_": lambda: on_worker(paths, warm, "no trim"),
        "Dask worker, no profiler": lambda: on_worker(paths, warm, "no profiler"),
        "Dask worker, runner set-up": lambda: on_worker(paths, warm, "runner set-up"),
        "Dask worker, runner set-up and quiet loop (the runner's)": lambda: on_worker(paths, warm, "runner"),
    }
    rows = []
    for rep in range(args.repeats):
        for name, fn in variants.items():
            load = round(os.getloadavg()[0], 2)
            res = fn()
            med = {k: statistics.median(r[i] for r in res) for i, k in enumerate(FIELDS)}
            rows.append({"round": rep, "variant": name, "load": load, **med})
            print(f"{rep} {name:40s} wall {med['wall']:.3f} cpu {med['cpu']:.3f} process {med['process_cpu']:.3f} "
                  f"faults {med['faults']:.0f} load {load}", flush=True)
    lines = [
        "# Where a task loses time on a Dask worker",
        "",
        f"`python benchmarks/probe_runner_engines.py --n {args.n} --repeats {args.repeats}`: {args.n} clouds of "
        f"`bench_runner.py` (plane detection, `configs/pointcloud_plane.yaml`, 1 thread), medians per task; {machine()}; "
        "`load`: 1-minute load average before each row. `cpu`: the task thread's CPU s; `process cpu`: the whole "
        "process's meanwhile (a worker's event loop and profiler included); `faults`: the task thread's minor page faults.",
        "",
        "| round | where | wall s | cpu s | process cpu s | faults | load |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['round']} | {r['variant']} | {r['wall']:.3f} | {r['cpu']:.3f} | {r['process_cpu']:.3f} | "
                     f"{r['faults']:.0f} | {r['load']} |")
    write_report(args.out, "runner_engines", "\n".join(lines) + "\n", {"args": vars(args), "rows": rows})


if __name__ == "__main__":
    main()
