"""Benchmark of the dataset runner (``torchsym.run``) on its three engines.

Datasets: ``--clouds`` generated point clouds with planted symmetry
(:func:`torchsym.pointcloud.planted_symmetric_cloud`, ``--points`` each, ``.npy``, the
default config ``configs/pointcloud_plane.yaml``), the 32 dev photos
(``../shared/data/images/reflection_single_dev``, ``configs/image_ksymmetry.yaml``) and
as many tiny clouds run by a solver that does nothing (``benchmarks/runner_noop.py``),
which measures the runner's own cost per input. Engines: serial (in the driver), a
2-worker ``LocalCluster`` started by the run, and a separately started scheduler with 2
single-threaded workers (``dask scheduler`` / ``dask worker`` processes on 127.0.0.1).

Per dataset and engine: items per second (without and with the engine's start-up),
the mean seconds of a task as the records give them, the overhead per item
(``wall x workers / n - mean task seconds``), and the peak resident memory of the driver
and its cluster's processes together (sampled every 0.1 s). Then: the time lost when a
worker of the separate cluster is killed with SIGKILL a third of the way through a
quarter of the clouds (against the same clouds without a kill, interleaved, twice), and a driver (local engine, sleeping no-op tasks) killed with SIGKILL mid-run
and resumed: the records before the kill, duplicates, missing inputs and the tasks that
ran twice (those in flight at the kill). The clouds and photos are also scored with
``torchsym.evaluate`` against their ground truth.

Writes ``benchmarks/results/runner.md`` and ``runner.json``.

    python benchmarks/bench_runner.py [--clouds 200] [--points 60000] [--photos DIR] [--work /tmp/bench_runner]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
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


def timed_run(dataset: str, label: str, cfg: Any, inputs: str, out: Path, roots: list[int], **kwargs: Any) -> dict[str, Any]:
    from torchsym.runner import read_results, run

    out.unlink(missing_ok=True)
    with PeakMemory(roots) as mem:
        summary = run(cfg, inputs, out, resume=False, **kwargs)
    records = read_results(out)
    n = summary.n_run
    busy = summary.seconds - summary.engine_seconds
    workers = 1 if summary.engine == "serial" else 2
    task = sum(r["seconds"] or 0.0 for r in records) / max(1, len(records))
    row = {
        "dataset": dataset, "engine": label, "n": n, "ok": summary.n_ok, "error": summary.n_error,
        "crashed": summary.n_crashed, "wall_s": summary.seconds, "startup_s": summary.engine_seconds,
        "items_per_s": n / busy, "items_per_s_with_startup": n / summary.seconds, "mean_task_s": task,
        "overhead_ms": (busy * workers / n - task) * 1000.0, "peak_mb": mem.peak / 2**20,
    }
    print(f"  {dataset:7s} {label:9s} {n:4d} items: {row['items_per_s']:.2f}/s ({row['items_per_s_with_startup']:.2f}/s "
          f"with {summary.engine_seconds:.1f} s start-up), task {task:.3f} s, overhead {row['overhead_ms']:.1f} ms, "
          f"peak {row['peak_mb']:.0f} MB", flush=True)
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
    script = ("import json, sys; sys.path.insert(0, sys.argv[4]); import torchsym\n"
              "torchsym.run(json.loads(sys.argv[1]), sys.argv[2], sys.argv[3], engine='local', workers=2, imports=['runner_noop'])\n")
    proc = subprocess.Popen([sys.executable, "-c", script, json.dumps(cfg), inputs, str(out), str(HERE)], cwd=REPO,
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
    print(f"  {dataset}: {ev.summary}", flush=True)
    return {"dataset": dataset, "n_scored": ev.n_scored, "summary": ev.summary}


def _markdown(res: dict[str, Any]) -> str:
    a = res["args"]
    lines = [
        "# Dataset runner: serial, 2-worker LocalCluster, separate scheduler + 2 workers",
        "",
        f"Command: `python benchmarks/bench_runner.py --clouds {a['clouds']} --points {a['points']}`; "
        f"{res['machine']}; torch {res['torch']}, dask {res['dask']}; load average {res.get('load', '?')} (1 min) at the "
        "end of the run: on a machine shared with other jobs the speed-ups are lower than on an idle one.",
        "",
        "`items/s` leaves out the engine's start-up (cluster up, workers importing torch) and shut-down, "
        "`with start-up` includes them. `overhead ms` is wall x workers / n minus the mean task "
        "seconds of the records: the runner's cost per input (reading the input and writing the "
        "record with fsync included in the no-op row only). `peak MB`: driver and cluster processes together.",
        "",
        "| dataset | engine | n | ok | items/s | with start-up | speed-up | start + stop s | task s | overhead ms | peak MB |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    serial = {r["dataset"]: r["items_per_s"] for r in res["runs"] if r["engine"] == "serial"}
    for r in res["runs"]:
        lines.append(
            f"| {r['dataset']} | {r['engine']} | {r['n']} | {r['ok']} | {r['items_per_s']:.2f} | "
            f"{r['items_per_s_with_startup']:.2f} | {r['items_per_s'] / serial[r['dataset']]:.2f}x | {r['startup_s']:.1f} | "
            f"{r['mean_task_s']:.3f} | {r['overhead_ms']:.1f} | {r['peak_mb']:.0f} |"
        )
    k = res["killed_worker"]
    lines += [
        "",
        f"Worker killed (SIGKILL) on the separate cluster after {k['killed_after']} of {k['n']} clouds, against the "
        f"same clouds without a kill, interleaved, twice: clean {', '.join(f'{c:.1f}' for c in k['clean_s'])} s, "
        f"killed {', '.join(f'{c:.1f}' for c in k['killed_s'])} s: **{k['lost_s']:.1f} s lost** on average "
        f"(the task the worker was running, the one waiting behind it, and the "
        f"cluster at one worker while the nanny restarts it). {k['ok']} of {2 * k['n']} ok, {k['retried']} retried.",
    ]
    d = res["killed_driver"]
    lines += [
        "",
        f"Driver killed (SIGKILL, with its local cluster) after {d['records_before_kill']} of {d['n']} no-op tasks "
        f"({d['torn_bytes']} torn bytes cut): the resumed run skipped {d['skipped_on_resume']} and ran "
        f"{d['run_on_resume']}; {d['missing']} inputs missing, {d['duplicate_records']} duplicate records, "
        f"{d['tasks_run_twice']} tasks run twice (those in flight at the kill: two tasks per worker, each up to 16 quick inputs).",
        "",
        "Scores of the runs (`torchsym evaluate`):",
        "",
    ]
    for e in res["evaluations"]:
        lines.append(f"- {e['dataset']} ({e['n_scored']} inputs): " + "; ".join(
            f"{proto}: " + ", ".join(f"{k} {v:.3f}" for k, v in figs.items()) for proto, figs in e["summary"].items()))
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clouds", type=int, default=200)
    ap.add_argument("--points", type=int, default=60000)
    ap.add_argument("--photos", default=str(REPO.parent / "shared" / "data" / "images" / "reflection_single_dev"))
    ap.add_argument("--work", default="/tmp/bench_runner")
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args()

    import dask
    import torch

    import runner_noop  # noqa: F401  (registers bench_noop in the driver)

    torch.set_num_threads(1)
    work = Path(args.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    print(f"generating {args.clouds} clouds of {args.points} points and {args.clouds} tiny ones in {work}", flush=True)
    planes = make_clouds(work / "clouds", args.clouds, args.points)
    make_tiny(work / "tiny", args.clouds)
    photos = Path(args.photos)
    datasets = [
        ("no-op", NOOP, str(work / "tiny" / "*.npy"), {"imports": ["runner_noop"]}),
        ("clouds", str(REPO / "configs" / "pointcloud_plane.yaml"), str(work / "clouds" / "*.npy"), {}),
    ]
    if args.photos and (photos / "axes.txt").is_file():
        datasets.append(("photos", str(REPO / "configs" / "image_ksymmetry.yaml"), str(photos / "*.jpg"), {}))
    me = [os.getpid()]
    runs = []
    for name, cfg, inputs, extra in datasets:
        runs.append(timed_run(name, "serial", cfg, inputs, work / f"{name}_serial.jsonl", me, engine="serial", **extra))
        runs.append(timed_run(name, "local", cfg, inputs, work / f"{name}_local.jsonl", me, engine="local", workers=2, **extra))
    with SeparateCluster(work) as cluster:  # started now: idle, it would share the cores with the runs above
        for name, cfg, inputs, extra in datasets:
            runs.append(timed_run(name, "separate", cfg, inputs, work / f"{name}_separate.jsonl", me,
                                  address=str(cluster.file), **extra))
        clouds = sorted(str(p) for p in (work / "clouds").glob("*.npy"))[: max(30, args.clouds // 4)]
        kw = killed_worker(cluster, str(REPO / "configs" / "pointcloud_plane.yaml"), clouds, work)
    kd = killed_driver(str(work / "tiny" / "*.npy"), work, args.clouds, 0.05, args.clouds // 3)
    evaluations = [evaluate_row("clouds", work / "clouds_serial.jsonl", planes)]
    if args.photos and (photos / "axes.txt").is_file():
        evaluations.append(evaluate_row("photos", work / "photos_serial.jsonl", photos / "axes.txt"))
    res = {
        "args": vars(args), "machine": f"{os.cpu_count()} cores", "load": f"{os.getloadavg()[0]:.1f}", "torch": torch.__version__, "dask": dask.__version__,
        "runs": runs, "killed_worker": kw, "killed_driver": kd, "evaluations": evaluations,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "runner.json").write_text(json.dumps(res, indent=2))
    text = _markdown(res)
    (out / "runner.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
