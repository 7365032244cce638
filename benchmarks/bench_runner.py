"""Benchmark of the dataset runner (``torchsym.run``) against its peers, over worker counts.

Dataset: ``--clouds`` generated point clouds with planted symmetry
(:func:`torchsym.pointcloud.planted_symmetric_cloud`, ``--points`` each, ``.npy``) and
the shipped config ``configs/pointcloud_plane.yaml``, one torch thread per task
everywhere. For each worker count of ``--workers`` and each of ``--repeats`` rounds,
interleaved: ``torchsym.run`` serially (once per round), ``torchsym.run`` on its local
engine, plain Dask (``client.map`` of ``torchsym.detect`` on a ``LocalCluster`` of
single-thread workers, Dask's defaults) and a spawn process pool of as many processes,
all on the same clouds. Per run: clouds/s in the steady part (from the ``w``-th
completion to the last), clouds/s with start-up and shut-down (the whole wall time),
the seconds lost to them (wall minus clouds over the steady rate), the machine's load.
Per input, the runner's stages as its engine logs them
(:data:`torchsym.runner.engine.STAGES`: read, solve, record, task CPU, worker process
CPU, page faults; the driver waiting, submitting, handling) and the peers' task wall,
CPU and page faults measured the same way.

Start-up: ``w`` processes importing torch and torchsym at once (the floor), the runner's
local cluster until ``w`` workers are set up, plain Dask's ``LocalCluster`` until its
workers have imported torchsym. Then the runner's own cost per input (a no-op solver on
tiny clouds), the 32 dev photos (``configs/image_ksymmetry.yaml``) serially and at the
largest worker count, a worker SIGKILLed a third of the way through a quarter of the
clouds on a separately started cluster (against the same clouds without a kill,
interleaved, twice), and a driver (local engine, sleeping no-op tasks) killed with
SIGKILL mid-run and resumed: the records before the kill, duplicates, missing inputs
and the tasks that ran twice. The clouds are scored against their planes.

Writes ``benchmarks/results/runner.md`` and ``runner.json``.

    python benchmarks/bench_runner.py [--clouds 48] [--points 60000] [--workers 1 2] [--repeats 3] [--work /tmp/bench_runner]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import multiprocessing as mp
import os
import platform
import resource
import shutil
import signal
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path[:0] = [str(REPO), str(HERE)]  # this tree's torchsym, and runner_noop

NOOP = {"input": "pointcloud", "steps": [{"name": "bench_noop"}]}
CLOUD_CONFIG = str(REPO / "configs" / "pointcloud_plane.yaml")


class PeakMemory:
    """Peak of the summed resident memory of some processes and their descendants."""

    def __init__(self, roots: list[int], interval: float = 0.1) -> None:
        self.roots, self.interval, self.peak = roots, interval, 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    def _total(self) -> int:
        import psutil

        total = 0
        for pid in self.roots:
            try:
                root = psutil.Process(pid)
                procs = [root] + root.children(recursive=True)
            except psutil.Error:
                continue
            for p in procs:
                try:
                    total += p.memory_info().rss
                except psutil.Error:
                    pass
        return total

    def _loop(self) -> None:
        while not self._stop.is_set():
            self.peak = max(self.peak, self._total())
            self._stop.wait(self.interval)

    def __enter__(self) -> PeakMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self._stop.set()
        self._thread.join()


class SeparateCluster:
    """A ``dask scheduler`` and a ``dask worker --nworkers 2 --nthreads 1`` on 127.0.0.1,
    in their own process groups, with ``allowed-failures = 0`` as the local engine sets it."""

    def __init__(self, work: Path, workers: int = 2) -> None:
        self.file = work / "scheduler.json"
        self.workers = workers
        self.procs: list[subprocess.Popen] = []

    def __enter__(self) -> SeparateCluster:
        from distributed import Client

        self.file.unlink(missing_ok=True)
        env = {**os.environ, "DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "0",
               "PYTHONPATH": os.pathsep.join([str(REPO), str(HERE), os.environ.get("PYTHONPATH", "")])}
        common = {"env": env, "start_new_session": True, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        self.procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
             "--scheduler-file", str(self.file), "--no-dashboard"], **common))
        while not self.file.is_file():
            time.sleep(0.1)
        self.procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(self.file),
             "--nworkers", str(self.workers), "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"], **common))
        with Client(scheduler_file=str(self.file), timeout="30s") as client:
            client.wait_for_workers(self.workers, timeout=120)
        return self

    @property
    def pids(self) -> list[int]:
        return [p.pid for p in self.procs]

    def worker_pids(self) -> list[int]:
        from distributed import Client

        with Client(scheduler_file=str(self.file), timeout="30s") as client:
            return list(client.run(os.getpid).values())

    def __exit__(self, *exc: Any) -> None:
        for p in reversed(self.procs):
            try:
                os.killpg(p.pid, signal.SIGTERM)
                p.wait(timeout=20)
            except (ProcessLookupError, subprocess.TimeoutExpired):
                os.killpg(p.pid, signal.SIGKILL)


def make_clouds(folder: Path, n: int, points: int) -> Path:
    """``n`` planted clouds ``c000.npy``... and their planes in ``planes.jsonl``; returns the truth file."""
    import numpy as np

    from torchsym.pointcloud.synthetic import planted_symmetric_cloud

    folder.mkdir(parents=True, exist_ok=True)
    lines = []
    for i in range(n):
        cloud = planted_symmetric_cloud(points, generator=i)
        np.save(folder / f"c{i:03d}.npy", cloud.points.numpy())
        lines.append(json.dumps({"input": f"c{i:03d}.npy", "normal": cloud.normal.tolist(), "offset": float(cloud.offset)}))
    truth = folder.parent / f"{folder.name}_planes.jsonl"
    truth.write_text("\n".join(lines) + "\n")
    return truth


def make_tiny(folder: Path, n: int) -> None:
    """``n`` clouds of 8 points, the first coordinate of each its index (the no-op's log)."""
    import numpy as np

    folder.mkdir(parents=True, exist_ok=True)
    for i in range(n):
        x = np.random.default_rng(i).normal(size=(8, 3))
        x[0, 0] = i
        np.save(folder / f"t{i:03d}.npy", x)


def machine() -> str:
    """Cores, CPU model, Python and OS of this machine."""
    model = platform.processor() or "?"
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    return f"{os.cpu_count()} cores ({model}), Python {platform.python_version()}, {platform.system()} {platform.release()}"


@contextlib.contextmanager
def own_environ() -> Any:
    """Put this process's environment back on leaving: a Dask nanny sets its
    ``pre-spawn-environ`` (``MALLOC_TRIM_THRESHOLD_``...) in the process that starts it,
    which a process pool started later would inherit."""
    saved = dict(os.environ)
    try:
        yield
    finally:
        for name in set(os.environ) - set(saved):
            del os.environ[name]
        os.environ.update(saved)


def load() -> float:
    return round(os.getloadavg()[0], 2)


class Completions:
    """Times (from the start) at which lines appear in a results file, polled every 10 ms."""

    def __init__(self, path: Path) -> None:
        self.path, self.times, self.t0 = path, [], time.perf_counter()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    def _loop(self) -> None:
        seen, stop = 0, False
        while not stop:
            stop = self._stop.is_set()  # one last count after the run
            n = _count_lines(self.path)
            now = time.perf_counter() - self.t0
            self.times += [now] * (n - seen)
            seen = max(seen, n)
            self._stop.wait(0.01)

    def __enter__(self) -> Completions:
        self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self._stop.set()
        self._thread.join()


class StageLog(logging.Handler):
    """Keeps the per-input stages the engine logs at the end of a run."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.stages: dict[str, float] = {}

    def emit(self, record: logging.LogRecord) -> None:
        if hasattr(record, "stages"):
            self.stages = dict(record.stages)


def _row(dataset: str, engine: str, workers: int, times: list[float], wall: float, load_before: float, **extra: Any) -> dict[str, Any]:
    """Steady rate from the ``workers``-th completion to the last; the rest of the wall is start-up and shut-down."""
    times = sorted(times)
    n = len(times)
    k = min(workers, n - 1)
    rate = (n - k) / max(times[-1] - times[k - 1], 1e-9) if n > 1 else n / wall
    row = {
        "dataset": dataset, "engine": engine, "workers": workers, "n": n, "wall_s": wall, "items_per_s": rate,
        "items_per_s_with_startup": n / wall, "startup_s": wall - n / rate, "first_s": times[0] if times else None,
        "load": load_before, **extra,
    }
    print(f"  {dataset:7s} {engine:12s} w={workers:2d} {n:4d} items: {rate:.2f}/s steady, {n / wall:.2f}/s with "
          f"{row['startup_s']:.1f} s start/stop (first after {row['first_s']:.1f} s), load {load_before}", flush=True)
    return row


def runner_run(dataset: str, cfg: Any, inputs: str, out: Path, engine: str, workers: int, **kwargs: Any) -> dict[str, Any]:
    """``torchsym.run`` on ``engine``: rates, stages per input (the engine's log), records' task seconds, peak memory."""
    from torchsym.runner import read_results, run

    out.unlink(missing_ok=True)
    log = StageLog()
    engine_logger = logging.getLogger("torchsym.runner.engine")
    engine_logger.addHandler(log)
    engine_logger.setLevel(logging.INFO)
    before = load()
    try:
        with PeakMemory([os.getpid()]) as mem, Completions(out) as done:
            t0 = time.perf_counter()
            summary = run(cfg, inputs, out, resume=False, engine=engine, workers=workers, **kwargs)
            wall = time.perf_counter() - t0
    finally:
        engine_logger.removeHandler(log)
    records = read_results(out, arrays=False)
    task = statistics.mean(r["seconds"] or 0.0 for r in records)
    label = "runner serial" if engine == "serial" else "runner"
    return _row(dataset, label, 1 if engine == "serial" else workers, done.times or [wall], wall, before,
                ok=summary.n_ok, task_s=task, stages=log.stages, peak_mb=mem.peak / 2**20)


def peer_task(path: str, config: str) -> tuple[float, float, float, int]:
    """``torchsym.detect(path, config)`` with one thread: (wall s, thread CPU s, process CPU s, minor page faults)."""
    import torch
    from threadpoolctl import threadpool_limits

    import torchsym

    torch.set_num_threads(1)
    with threadpool_limits(1):
        p0, c0 = resource.getrusage(resource.RUSAGE_SELF), time.thread_time()
        f0, t0 = resource.getrusage(resource.RUSAGE_THREAD).ru_minflt, time.perf_counter()
        torchsym.detect(path, config)
        wall, cpu = time.perf_counter() - t0, time.thread_time() - c0
        f1, p1 = resource.getrusage(resource.RUSAGE_THREAD).ru_minflt, resource.getrusage(resource.RUSAGE_SELF)
    return wall, cpu, (p1.ru_utime + p1.ru_stime) - (p0.ru_utime + p0.ru_stime), f1 - f0


def _peer_stats(results: list[tuple[float, float, float, int]]) -> dict[str, float]:
    return {k: statistics.mean(r[i] for r in results) for i, k in enumerate(("task", "cpu", "process_cpu", "faults"))}


def _pool_init() -> None:
    import torch

    import torchsym  # noqa: F401

    torch.set_num_threads(1)


def pool_run(paths: list[str], workers: int) -> dict[str, Any]:
    """A spawn process pool of ``workers`` over ``paths`` (start-up and shut-down included in the wall)."""
    before, results, times = load(), [], []
    t0 = time.perf_counter()
    with mp.get_context("spawn").Pool(workers, initializer=_pool_init) as pool:
        for r in pool.imap_unordered(_peer_call, paths, chunksize=1):
            times.append(time.perf_counter() - t0)
            results.append(r)
    wall = time.perf_counter() - t0
    return _row("clouds", "process pool", workers, times, wall, before, peer=_peer_stats(results))


def _peer_call(path: str) -> tuple[float, float, float, int]:
    return peer_task(path, CLOUD_CONFIG)


def dask_run(paths: list[str], workers: int) -> dict[str, Any]:
    """Plain Dask: ``client.map(torchsym.detect)`` on a fresh ``LocalCluster`` of single-thread workers, Dask's defaults."""
    from distributed import Client, LocalCluster, as_completed

    before, results, times = load(), [], []
    t0 = time.perf_counter()
    with own_environ(), LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                                     dashboard_address=None, silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        for fut in as_completed(client.map(peer_task, paths, config=CLOUD_CONFIG, pure=False)):
            times.append(time.perf_counter() - t0)
            results.append(fut.result())
            fut.release()
    wall = time.perf_counter() - t0
    return _row("clouds", "plain Dask", workers, times, wall, before, peer=_peer_stats(results))


def _import_torch(_: int = 0) -> float:
    import torchsym  # noqa: F401

    return time.perf_counter()


def startup(workers: int) -> dict[str, Any]:
    """Seconds until ``workers`` processes are ready: importing torch and torchsym at once
    (the floor), the runner's local cluster with its worker set-up, plain Dask's."""
    from distributed import Client, LocalCluster

    from torchsym.runner.engine import dask_client

    before = load()
    t0 = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, "-c", "import torch, torchsym"], env={**os.environ, "PYTHONPATH": str(REPO)})
             for _ in range(workers)]
    for p in procs:
        p.wait()
    floor = time.perf_counter() - t0
    t0 = time.perf_counter()
    with dask_client("local", address=None, workers=workers, threads=1) as client:
        client.wait_for_workers(1, timeout=600)
        client.run(_import_torch)  # returns once the workers up have run their set-up
        first = time.perf_counter() - t0
        client.wait_for_workers(workers, timeout=600)
        client.run(_import_torch)
        runner = time.perf_counter() - t0
        t1 = time.perf_counter()
    runner_stop = time.perf_counter() - t1
    t0 = time.perf_counter()
    with own_environ(), LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                                     dashboard_address=None, silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        client.run(_import_torch)
        plain = time.perf_counter() - t0
    row = {"workers": workers, "floor_s": floor, "runner_s": runner, "runner_first_s": first, "runner_stop_s": runner_stop,
           "plain_dask_s": plain, "load": before}
    print(f"  start-up w={workers}: floor {floor:.1f} s, runner {runner:.1f} s (first worker {first:.1f} s, stop "
          f"{runner_stop:.1f} s), plain Dask {plain:.1f} s, load {before}", flush=True)
    return row


def _count_lines(path: Path) -> int:
    return path.read_bytes().count(b"\n") if path.is_file() else 0


def _separate_run(cluster: SeparateCluster, cfg: Any, inputs: list[str], out: Path, kill_after: int | None) -> tuple[float, Any]:
    """Busy seconds of one run on the separate cluster, SIGKILLing one worker after
    ``kill_after`` records (None: no kill); and the run's summary."""
    from distributed import Client

    from torchsym.runner import run

    out.unlink(missing_ok=True)
    pid = cluster.worker_pids()[0]

    def killer() -> None:
        while _count_lines(out) < kill_after:
            time.sleep(0.02)
        os.kill(pid, signal.SIGKILL)

    thread = threading.Thread(target=killer, daemon=True)
    if kill_after is not None:
        thread.start()
    summary = run(cfg, inputs, out, address=str(cluster.file), resume=False)
    if kill_after is not None:
        thread.join(timeout=1)
        with Client(scheduler_file=str(cluster.file), timeout="30s") as client:
            client.wait_for_workers(cluster.workers, timeout=120)  # the nanny's restart, before the next run
    return summary.seconds - summary.engine_seconds, summary


def killed_worker(cluster: SeparateCluster, cfg: Any, inputs: list[str], work: Path) -> dict[str, Any]:
    """Runs of ``inputs`` on the separate cluster, clean and with one worker SIGKILLed a
    third of the way, interleaved (clean, killed, clean, killed): the time lost is the
    mean killed run minus the mean clean run."""
    from torchsym.runner import read_results

    at = len(inputs) // 3
    clean, killed, retried, ok = [], [], 0, 0
    for rep in range(2):
        clean.append(_separate_run(cluster, cfg, inputs, work / "clean_worker.jsonl", None)[0])
        busy, summary = _separate_run(cluster, cfg, inputs, work / "killed_worker.jsonl", at)
        killed.append(busy)
        ok += summary.n_ok
        retried += sum(1 for r in read_results(work / "killed_worker.jsonl") if r["attempts"] > 1)
    mean_clean, mean_killed = sum(clean) / 2, sum(killed) / 2
    row = {
        "n": len(inputs), "killed_after": at, "repeats": 2, "ok": ok, "retried": retried,
        "clean_s": clean, "killed_s": killed, "lost_s": mean_killed - mean_clean,
    }
    print(f"  worker killed after {at} of {len(inputs)} (2 repeats): {ok} ok, {retried} retried; clean "
          f"{[round(c, 1) for c in clean]} s, killed {[round(k, 1) for k in killed]} s: {row['lost_s']:.1f} s lost", flush=True)
    return row


def killed_driver(inputs: str, work: Path, n: int, sleep: float, kill_after: int) -> dict[str, Any]:
    """A driver on the local engine killed with SIGKILL (with its cluster) after
    ``kill_after`` records, then resumed; the no-op solver logs every task it starts."""
    from torchsym.runner import ResultsStore, read_results, run

    out, log = work / "killed_driver.jsonl", work / "killed_driver.log"
    out.unlink(missing_ok=True)
    log.unlink(missing_ok=True)
    cfg = {"input": "pointcloud", "steps": [{"name": "bench_noop", "params": {"sleep": sleep, "log": str(log)}}]}
    script = ("import json, sys; import torchsym\n"
              "torchsym.run(json.loads(sys.argv[1]), sys.argv[2], sys.argv[3], engine='local', workers=2, imports=['runner_noop'])\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(HERE), os.environ.get("PYTHONPATH")]))}
    proc = subprocess.Popen([sys.executable, "-c", script, json.dumps(cfg), inputs, str(out)], cwd=REPO, env=env,
                            start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    while _count_lines(out) < kill_after and proc.poll() is None:
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    time.sleep(0.5)  # orphaned workers finishing a task would still log it
    before = len(read_results(out, latest=False))
    with ResultsStore(out) as store:
        torn = store.torn_bytes
    summary = run(cfg, inputs, out, engine="local", workers=2, imports=["runner_noop"])
    lines = read_results(out, latest=False)
    starts = log.read_text().split()
    row = {
        "n": n, "records_before_kill": before, "torn_bytes": torn, "skipped_on_resume": summary.n_skipped,
        "run_on_resume": summary.n_run, "records": len(lines), "duplicate_records": len(lines) - len({r["input"] for r in lines}),
        "missing": n - len({r["input"] for r in lines if r["status"] == "ok"}), "tasks_run_twice": len(starts) - len(set(starts)),
    }
    print(f"  driver killed after {before} records: resumed with {row['skipped_on_resume']} skipped, {row['run_on_resume']} run; "
          f"{row['missing']} missing, {row['duplicate_records']} duplicate records, {row['tasks_run_twice']} tasks run twice", flush=True)
    return row


def evaluate_row(dataset: str, out: Path, truth: Path) -> dict[str, Any]:
    from torchsym.runner import evaluate

    ev = evaluate(out, truth)
    print(f"  {dataset}: {ev.figures}", flush=True)
    return {"dataset": dataset, "n_scored": ev.n_scored, "summary": ev.figures}


def _stage_cells(r: dict[str, Any]) -> str:
    if "stages" in r:
        s = r["stages"]
        return (f"{1e3 * (s.get('read', 0) + s.get('solve', 0) + s.get('record', 0)):.0f} | {1e3 * s.get('read', 0):.0f} | "
                f"{1e3 * s.get('solve', 0):.0f} | {1e3 * s.get('record', 0):.1f} | {1e3 * s.get('cpu', 0):.0f} | "
                f"{1e3 * s.get('process_cpu', 0):.0f} | {s.get('faults', 0):.0f} | {1e3 * s.get('wait', 0):.0f} | "
                f"{1e3 * s.get('submit', 0):.1f} | {1e3 * s.get('handle', 0):.1f}")
    p = r["peer"]
    return (f"{1e3 * p['task']:.0f} | | | | {1e3 * p['cpu']:.0f} | {1e3 * p['process_cpu']:.0f} | {p['faults']:.0f} | | | ")


def _markdown(res: dict[str, Any]) -> str:
    a = res["args"]
    runs = [r for r in res["runs"] if r["dataset"] == "clouds"]
    serial = statistics.mean(r["items_per_s"] for r in runs if r["engine"] == "runner serial")
    lines = [
        "# Dataset runner against plain Dask and a process pool, by worker count",
        "",
        f"Command: `python benchmarks/bench_runner.py --clouds {a['clouds']} --points {a['points']} --workers "
        f"{' '.join(map(str, a['workers']))} --repeats {a['repeats']}`; {res['machine']}; torch {res['torch']}, dask "
        f"{res['dask']}. `load` is the 1-minute load average before each run: on a machine shared with other jobs "
        "every figure is slower and noisier than on an idle one.",
        "",
        f"{a['clouds']} planted clouds of {a['points']} points, `configs/pointcloud_plane.yaml`, one torch thread per task. "
        "`clouds/s`: the steady part, from the w-th completion to the last; `with start-up`: clouds over the whole wall "
        "time (cluster or pool started and stopped inside it); `start/stop s`: wall minus clouds over the steady rate; "
        "`first s`: the first result. Rounds interleaved: serial, then per worker count the runner, plain Dask, the pool.",
        "",
        "| round | engine | workers | clouds/s | x serial | with start-up | start/stop s | first s | load |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        lines.append(f"| {r['round']} | {r['engine']} | {r['workers']} | {r['items_per_s']:.2f} | {r['items_per_s'] / serial:.2f}x | "
                     f"{r['items_per_s_with_startup']:.2f} | {r['startup_s']:.1f} | {r['first_s']:.1f} | {r['load']} |")
    lines += ["", "Mean over the rounds:", "", "| engine | workers | clouds/s | x serial | x pool | with start-up | start/stop s |",
              "|---|---|---|---|---|---|---|"]
    keys = sorted({(r["engine"], r["workers"]) for r in runs}, key=lambda k: (k[1], k[0]))
    mean = {k: {f: statistics.mean(r[f] for r in runs if (r["engine"], r["workers"]) == k)
                for f in ("items_per_s", "items_per_s_with_startup", "startup_s")} for k in keys}
    for k in keys:
        m = mean[k]
        pool = mean.get(("process pool", k[1]), {}).get("items_per_s")
        lines.append(f"| {k[0]} | {k[1]} | {m['items_per_s']:.2f} | {m['items_per_s'] / serial:.2f}x | "
                     f"{m['items_per_s'] / pool if pool else float('nan'):.2f}x | {m['items_per_s_with_startup']:.2f} | {m['startup_s']:.1f} |")
    lines += [
        "",
        "Where a cloud's time goes, ms per input (means of each run): `task` is read + solve + record for the runner "
        "(wall on the worker), the whole `torchsym.detect` for the peers; `cpu` the task thread's CPU time, `proc cpu` "
        "its whole process's meanwhile (a Dask worker's event loop and profiler included), `faults` the task thread's "
        "minor page faults; driver `wait` for a result, `submit`, `handle` (writing the arrays and the record, fsync-ed).",
        "",
        "| round | engine | workers | task | read | solve | record | cpu | proc cpu | faults | driver wait | submit | handle |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        lines.append(f"| {r['round']} | {r['engine']} | {r['workers']} | {_stage_cells(r)} |")
    lines += ["", "Start-up until w workers are ready (`floor`: w processes importing torch and torchsym at once; the "
              "runner's local cluster until every worker has run its set-up, and its first worker; plain Dask's "
              "`LocalCluster` until its workers have imported torchsym):", "",
              "| workers | floor s | runner s | runner first worker s | runner stop s | plain Dask s | load |", "|---|---|---|---|---|---|---|"]
    for s in res["startup"]:
        lines.append(f"| {s['workers']} | {s['floor_s']:.1f} | {s['runner_s']:.1f} | {s['runner_first_s']:.1f} | "
                     f"{s['runner_stop_s']:.1f} | {s['plain_dask_s']:.1f} | {s['load']} |")
    others = [r for r in res["runs"] if r["dataset"] != "clouds"]
    if others:
        lines += ["", "The runner's own cost (`no-op`: a solver that does nothing, on tiny clouds; `overhead ms`: workers "
                  "over the steady rate minus the records' mean task seconds) and the 32 dev photos:", "",
                  "| dataset | engine | workers | n | items/s | with start-up | overhead ms | load |", "|---|---|---|---|---|---|---|---|"]
        for r in others:
            over = (r["workers"] / r["items_per_s"] - r["task_s"]) * 1e3
            lines.append(f"| {r['dataset']} | {r['engine']} | {r['workers']} | {r['n']} | {r['items_per_s']:.2f} | "
                         f"{r['items_per_s_with_startup']:.2f} | {over:.1f} | {r['load']} |")
    k = res.get("killed_worker")
    if k:
        lines += ["", f"Worker killed (SIGKILL) on a separately started cluster after {k['killed_after']} of {k['n']} clouds, "
                  f"against the same clouds without a kill, interleaved, twice: clean {', '.join(f'{c:.1f}' for c in k['clean_s'])} s, "
                  f"killed {', '.join(f'{c:.1f}' for c in k['killed_s'])} s: **{k['lost_s']:.1f} s lost** on average. "
                  f"{k['ok']} of {2 * k['n']} ok, {k['retried']} retried."]
    d = res.get("killed_driver")
    if d:
        lines += ["", f"Driver killed (SIGKILL, with its local cluster) after {d['records_before_kill']} of {d['n']} no-op tasks "
                  f"({d['torn_bytes']} torn bytes cut): the resumed run skipped {d['skipped_on_resume']} and ran "
                  f"{d['run_on_resume']}; **{d['missing']} inputs missing, {d['duplicate_records']} duplicate records**, "
                  f"{d['tasks_run_twice']} tasks run twice (those in flight at the kill)."]
    if res.get("evaluations"):
        lines += ["", "Scores (`torchsym evaluate`):", ""]
        for e in res["evaluations"]:
            lines.append(f"- {e['dataset']} ({e['n_scored']} inputs): " + "; ".join(
                f"{proto}: " + ", ".join(f"{k} {v:.3f}" for k, v in figs.items()) for proto, figs in e["summary"].items()))
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clouds", type=int, default=48)
    ap.add_argument("--points", type=int, default=60000)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--photos", default=str(REPO.parent / "shared" / "data" / "images" / "reflection_single_dev"))
    ap.add_argument("--no-kills", action="store_true", help="leave out the killed worker and driver checks")
    ap.add_argument("--work", default="/tmp/bench_runner")
    ap.add_argument("--out", default=str(HERE / "results"))
    ap.add_argument("--report", help="rewrite the Markdown of this JSON of an earlier run, and stop")
    args = ap.parse_args()
    if args.report:
        from report import write_report

        res = json.loads(Path(args.report).read_text())
        write_report(args.out, "runner", _markdown(res), res)
        return

    import dask
    import torch

    import runner_noop  # noqa: F401  (registers bench_noop in the driver)
    from report import write_report

    torch.set_num_threads(1)
    work = Path(args.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    print(f"{machine()}; generating {args.clouds} clouds of {args.points} points and {args.clouds} tiny ones in {work}", flush=True)
    planes = make_clouds(work / "clouds", args.clouds, args.points)
    make_tiny(work / "tiny", args.clouds)
    clouds = str(work / "clouds" / "*.npy")
    paths = sorted(str(p) for p in (work / "clouds").glob("*.npy"))
    runs: list[dict[str, Any]] = []
    for rnd in range(args.repeats):
        runs.append({"round": rnd, **runner_run("clouds", CLOUD_CONFIG, clouds, work / "serial.jsonl", "serial", 1)})
        for w in args.workers:
            runs.append({"round": rnd, **runner_run("clouds", CLOUD_CONFIG, clouds, work / f"local{w}.jsonl", "local", w)})
            runs.append({"round": rnd, **dask_run(paths, w)})
            runs.append({"round": rnd, **pool_run(paths, w)})
    starts = [startup(w) for w in args.workers]
    top = max(args.workers)
    tiny = str(work / "tiny" / "*.npy")
    for engine in ("serial", "local"):
        runs.append(runner_run("no-op", NOOP, tiny, work / f"noop_{engine}.jsonl", engine, top, imports=["runner_noop"]))
    photos = Path(args.photos)
    if args.photos and (photos / "axes.txt").is_file():
        for engine in ("serial", "local"):
            runs.append(runner_run("photos", str(REPO / "configs" / "image_ksymmetry.yaml"), str(photos / "*.jpg"),
                                   work / f"photos_{engine}.jsonl", engine, top))
    res: dict[str, Any] = {"args": vars(args), "machine": machine(), "torch": torch.__version__, "dask": dask.__version__,
                           "runs": runs, "startup": starts}
    if not args.no_kills:
        with SeparateCluster(work) as cluster:
            res["killed_worker"] = killed_worker(cluster, CLOUD_CONFIG, paths[: max(30, args.clouds // 4)], work)
        res["killed_driver"] = killed_driver(tiny, work, args.clouds, 0.05, args.clouds // 3)
    res["evaluations"] = [evaluate_row("clouds", work / "serial.jsonl", planes)]
    write_report(args.out, "runner", _markdown(res), res)


if __name__ == "__main__":
    main()
