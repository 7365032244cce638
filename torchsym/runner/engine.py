"""Where the tasks of a dataset run are computed: in the driver, or on Dask workers.

Three engines give the same records (only where a task runs changes):

- ``"serial"``: one task after another in the driver process. No start-up cost; a task
  that kills the process kills the run (resume re-runs it).
- ``"local"``: a Dask ``LocalCluster`` of ``workers`` processes with
  ``threads_per_worker`` threads each, started and stopped by the run.
- ``"dask"``: an existing Dask scheduler, named by ``address`` (``tcp://host:8786`` or a
  ``scheduler.json`` file) or by ``DASK_SCHEDULER_ADDRESS``; SLURM/PBS clusters through
  ``dask-jobqueue``.

Each worker sets ``torch.set_num_threads(threads_per_worker)``, imports torchsym, keeps
freed memory for reuse and stops Dask's profiler when it joins, before its first task
(:class:`~torchsym.runner.worker.WorkerSetup`). The local cluster's workers start in
parallel while the first tasks are already submitted: the first worker up starts
computing. Two tasks per worker thread are in flight (``max_in_flight``), so a
100,000-input run never builds a large graph and no worker waits for the driver. A
worker that dies mid-task makes the scheduler raise ``KilledWorker`` for the tasks it
held (the local cluster is started with ``allowed-failures = 0``); the driver runs the
task that was running again up to ``retries`` times, then records it as ``"crashed"``,
and resubmits the tasks that were only waiting there uncounted (docs/design/runner.md).
"""

from __future__ import annotations

import collections
import contextlib
import dataclasses
import itertools
import logging
import os
import resource
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from torchsym.errors import ConfigError, InputFileError, TorchsymError
from torchsym.runner.task import TaskSpec, run_task

__all__ = [
    "BATCH_SECONDS", "ENGINES", "MAX_BATCH", "QUIET", "STAGES", "EngineError", "Outcome", "dask_client", "dask_outcomes", "local_cluster",
    "open_engine", "run_batch", "serial_outcomes",
]

logger = logging.getLogger(__name__)

ENGINES = ("auto", "serial", "local", "dask")


class EngineError(TorchsymError, ConnectionError):
    """The engine cannot start: an unreachable scheduler, a cluster that did not come up."""


#: what an engine yields per finished input: the spec, the task's outcome, the attempts made
Outcome = tuple[TaskSpec, dict[str, Any], int]


def _crashed(attempts: int, exc: BaseException) -> dict[str, Any]:
    return {
        "status": "crashed",
        "kind": None,
        "result": None,
        "error": {"type": type(exc).__name__, "message": f"the worker died on each of {attempts} attempts ({exc})", "where": ""},
        "seconds": 0.0,
        "artifacts": [],
    }


#: the breakdown an engine logs at the end of a run (``extra={"stages": {...}}``), seconds
#: (``faults``: minor page faults) per input: on the worker, ``read``, ``solve``,
#: ``record`` and ``figures`` (:func:`~torchsym.runner.task.run_task`), ``cpu`` (CPU
#: time of the task's thread), ``process_cpu`` (of the whole worker process meanwhile:
#: its other threads included); in the driver, ``wait`` (for a result), ``submit`` and
#: ``handle`` (the driver's own work on a result: writing its arrays and record)
STAGES = ("read", "solve", "record", "figures", "cpu", "process_cpu", "faults", "wait", "submit", "handle")

_RUSAGE_THREAD = getattr(resource, "RUSAGE_THREAD", resource.RUSAGE_SELF)


def _usage() -> tuple[float, float, int]:
    """(thread CPU s, process CPU s, minor page faults of the thread)."""
    proc = resource.getrusage(resource.RUSAGE_SELF)
    return time.thread_time(), proc.ru_utime + proc.ru_stime, resource.getrusage(_RUSAGE_THREAD).ru_minflt


def _timed_task(spec: TaskSpec) -> dict[str, Any]:
    """:func:`run_task` with its thread's CPU time, its process's and its page faults in ``stages``."""
    before = _usage()
    out = run_task(spec)
    after = _usage()
    out.setdefault("stages", {}).update(cpu=after[0] - before[0], process_cpu=after[1] - before[1], faults=after[2] - before[2])
    return out


def _log_stages(engine: str, stages: collections.Counter[str], n: int) -> None:
    if n:
        per = {k: stages[k] / n for k in STAGES}
        logger.info(
            "%s engine, per input (%d): worker read %.1f ms, solve %.1f ms, record %.1f ms, figures %.1f ms, cpu %.1f ms "
            "(process %.1f ms), %.0f page faults; driver waiting %.1f ms, submitting %.1f ms, handling %.1f ms",
            engine, n, *(1e3 * per[k] for k in STAGES[:6]), per["faults"], *(1e3 * per[k] for k in STAGES[7:]),
            extra={"stages": per, "n": n},
        )


def serial_outcomes(specs: Sequence[TaskSpec], threads: int) -> Iterator[Outcome]:
    """Run ``specs`` one after another in this process, torch, OpenCV, BLAS and OpenMP limited
    to ``threads`` threads as on a worker (the results do not depend on the engine); logs
    the :data:`STAGES` at the end."""
    import cv2
    import torch
    from threadpoolctl import threadpool_limits

    before = torch.get_num_threads(), cv2.getNumThreads()
    stages: collections.Counter[str] = collections.Counter()
    n = 0
    try:
        with threadpool_limits(threads):  # BLAS and OpenMP as on a worker
            for spec in specs:
                outcome = _timed_task(spec)
                stages.update(outcome["stages"])
                n += 1
                t = time.perf_counter()
                yield spec, outcome, 1
                stages["handle"] += time.perf_counter() - t
    finally:
        torch.set_num_threads(before[0])
        cv2.setNumThreads(before[1])
        _log_stages("serial", stages, n)


def _scheduler_target(address: str | None) -> dict[str, Any]:
    import dask

    addr = address if address is not None else dask.config.get("scheduler-address", None)
    if not addr:
        raise ConfigError(
            "--address: the dask engine needs a scheduler: --address tcp://host:8786, --address scheduler.json "
            "or DASK_SCHEDULER_ADDRESS; got none"
        )
    addr = str(addr)
    if "://" not in addr and (addr.endswith(".json") or Path(addr).exists()):
        if not Path(addr).is_file():
            raise InputFileError(f"--address: scheduler file {addr!r} does not exist")
        return {"scheduler_file": addr}
    return {"address": addr}


#: the local cluster's workers check their event loop, memory and system once a second
#: (Dask: every 20 ms, 100 ms and 500 ms): each wake takes the GIL from the running task;
#: with them, 0.07-0.13 s of other threads' CPU per cloud on the loaded 2-core machine,
#: 0.02-0.025 s without (docs/design/runner.md)
QUIET = {
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "1s",
}


def local_cluster(workers: int, threads: int) -> Any:
    """A ``distributed.LocalCluster`` of ``workers`` processes with ``threads`` threads
    each (0: none yet, ``cluster.scale(n)`` starts them), on loopback, no dashboard,
    whose scheduler fails a task on its first dead worker (``allowed-failures = 0``: the
    driver does the retries and counts them) and never moves a task between workers (no
    work stealing: each worker runs its tasks in submission order, which tells a running
    task from a waiting one when it dies)."""
    import dask
    from distributed import LocalCluster

    with dask.config.set({"distributed.scheduler.allowed-failures": 0, "distributed.scheduler.work-stealing": False}):
        return LocalCluster(
            n_workers=workers, threads_per_worker=threads, processes=True, host="127.0.0.1",
            dashboard_address=None, silence_logs=logging.ERROR,
        )


@contextlib.contextmanager
def dask_client(
    engine: str, *, address: str | None, workers: int, threads: int, imports: Sequence[str] = (), connect_timeout: float = 5.0
) -> Iterator[Any]:
    """A ``distributed.Client`` on a fresh ``LocalCluster`` (``engine="local"``) or on the
    scheduler at ``address`` (``engine="dask"``), with :class:`~torchsym.runner.worker.WorkerSetup` registered.

    The local cluster's ``workers`` are started after the set-up is registered and are
    not waited for: each imports torch and torchsym as it joins, all at once, while the
    client is already in use; they wake once a second, not every 20-500 ms, to watch
    their event loop, memory and system (:data:`QUIET`). This process's environment,
    which Dask's nannies change, is put back on leaving.

    Raises:
        EngineError: the scheduler cannot be reached within ``connect_timeout`` seconds.
    """
    import dask
    from distributed import Client

    from torchsym.runner.worker import WorkerSetup

    with contextlib.ExitStack() as stack:
        stack.enter_context(_quiet_dask_logs())
        if engine == "local":
            stack.callback(_restore_environ, dict(os.environ))
            stack.enter_context(dask.config.set(QUIET))  # while nannies start (and restart) workers
            cluster = stack.enter_context(local_cluster(0, threads))
            client = stack.enter_context(Client(cluster))
            client.register_plugin(WorkerSetup(threads, imports))
            cluster.scale(workers)
            logger.info("dask engine on a local cluster: starting %d workers", workers)
        else:
            target = _scheduler_target(address)
            where = next(iter(target.values()))
            try:
                client = stack.enter_context(Client(**target, timeout=f"{connect_timeout}s"))
            except (OSError, TimeoutError) as exc:
                raise EngineError(
                    f"--address: cannot reach the Dask scheduler at {where!r} within {connect_timeout:g} s ({exc})"
                ) from None
            client.register_plugin(WorkerSetup(threads, imports))
            logger.info("dask engine on %s: %d workers", where, len(client.scheduler_info()["workers"]))
        yield client


@contextlib.contextmanager
def _quiet_dask_logs() -> Iterator[None]:
    """Dask's INFO lines (scheduler and nanny start-up, connections: about 30 a run) held
    back unless torchsym itself logs at INFO (``-v``); warnings and errors still show."""
    dask_logger = logging.getLogger("distributed")
    saved = dask_logger.level
    if not logger.isEnabledFor(logging.INFO):
        dask_logger.setLevel(max(saved, logging.WARNING))
    try:
        yield
    finally:
        dask_logger.setLevel(saved)


def _restore_environ(saved: dict[str, str]) -> None:
    """Put back this process's environment: a Dask nanny sets its ``pre-spawn-environ``
    (``MALLOC_TRIM_THRESHOLD_``, ``OMP_NUM_THREADS=1``...) in the process that starts it,
    where every process started later (a user's process pool) would inherit it."""
    for name in set(os.environ) - set(saved):
        del os.environ[name]
    os.environ.update(saved)


def _capacity(client: Any, max_in_flight: int | None, expected: int = 0) -> int:
    """Tasks to keep in flight: ``max_in_flight``, or two per worker thread, live or
    ``expected`` (one running, one waiting on the worker, so a worker never waits for
    the driver)."""
    live = max(sum(client.nthreads().values()), expected)
    return 2 * live if max_in_flight is None or live == 0 else max_in_flight


def _error_outcome(exc: BaseException) -> dict[str, Any]:
    return {"status": "error", "kind": None, "result": None, "seconds": 0.0, "artifacts": [],
            "error": {"type": type(exc).__name__, "message": str(exc), "where": "engine"}}


def _worker_of(exc: BaseException) -> tuple[str | None, int]:
    """(address, threads) of the worker a ``KilledWorker`` names; ``(None, 1)`` if it names none."""
    ws = getattr(exc, "last_worker", None)
    return getattr(ws, "address", None), max(int(getattr(ws, "nthreads", 1) or 1), 1)


def _killed_with(fut: Any, exc: BaseException, flying: dict[str, Any]) -> list[tuple[Any, bool]]:
    """The tasks one worker's death took, oldest first, each with whether it was running.

    The scheduler reports every task of a dead worker in one message, so the others are
    already erred in ``flying``. A worker runs its tasks in submission order (each task's
    priority is its place in it), so of the tasks it held the ``threads`` oldest were
    running and the rest were waiting. A scheduler that steals work (not the local
    cluster's) can move an older task behind a running one; it is then counted as run.
    """
    from distributed.scheduler import KilledWorker

    address, threads = _worker_of(exc)
    killed = [flying.pop(fut.key)]
    if address is not None:
        for key in [k for k, task in flying.items() if task.future.status == "error"]:
            other = flying[key].future.exception()
            if isinstance(other, KilledWorker) and _worker_of(other)[0] == address:
                killed.append(flying.pop(key))
    killed.sort(key=lambda task: task.order)
    return [(task, rank < threads) for rank, task in enumerate(killed)]


#: a batch of inputs is sized to take about this many seconds on a worker
BATCH_SECONDS = 0.2
#: and holds at most this many inputs
MAX_BATCH = 16

#: an input waiting to run: its spec, the attempt it is at, and whether it runs as a task of its own
_Item = tuple[TaskSpec, int, bool]


@dataclasses.dataclass
class _Flying:
    items: tuple[_Item, ...]
    order: int
    future: Any


def run_batch(specs: Sequence[TaskSpec]) -> tuple[list[dict[str, Any]], float]:
    """:func:`~torchsym.runner.task.run_task` on each spec in turn (one Dask task); returns
    the outcomes (with the task's CPU time and page faults in their ``stages``) and the
    batch's wall seconds (pictures included, which size the batches)."""
    t0 = time.perf_counter()
    return [_timed_task(spec) for spec in specs], time.perf_counter() - t0


def _take(queue: collections.deque[_Item], size: int) -> tuple[_Item, ...]:
    """The next task's inputs: one that runs alone, or up to ``size`` that may share a task."""
    first = queue.popleft()
    items = [first]
    while not first[2] and queue and len(items) < size and not queue[0][2]:
        items.append(queue.popleft())
    return tuple(items)


class _Starting:
    """The workers of a cluster still starting: counted at most every 0.25 s while the
    driver waits, told to ``status``; no worker within ``wait_workers`` s is an error."""

    def __init__(self, client: Any, expected: int, status: Callable[[str], Any] | None, wait_workers: float) -> None:
        self.client, self.expected, self.status, self.wait_workers = client, expected, status, wait_workers
        self.t0 = self.checked = time.perf_counter()
        self.live = sum(client.nthreads().values()) if expected else 0
        self.active = self.live < expected
        self._say()

    def _say(self) -> None:
        if self.status is not None:
            self.status(f"waiting for workers: {self.live}/{self.expected} threads up" if self.active else "")

    def wait(self, done: Any) -> None:
        """Return once ``done`` has a result or every expected worker is up."""
        while self.active and not done.has_ready():
            time.sleep(0.02)
            now = time.perf_counter()
            if now - self.checked < 0.25:
                continue
            self.checked = now
            self.live = sum(self.client.nthreads().values())
            self.active = self.live < self.expected
            self._say()
            if self.live == 0 and now - self.t0 > self.wait_workers:
                raise EngineError(f"engine: no Dask worker started within {self.wait_workers:g} s")

    def done(self) -> None:
        if self.active:
            self.active = False
            self._say()


def dask_outcomes(
    client: Any,
    specs: Sequence[TaskSpec],
    *,
    retries: int,
    max_in_flight: int | None = None,
    wait_workers: float = 600.0,
    expected: int = 0,
    status: Callable[[str], Any] | None = None,
) -> Iterator[Outcome]:
    """Run ``specs`` on ``client``'s workers, yielding each input's outcome as it completes;
    logs the :data:`STAGES` at the end.

    Two tasks per worker thread are in flight, live or ``expected`` (the threads of
    workers still starting), or ``max_in_flight``: one running and one waiting on the
    worker, so a worker starts its next task without waiting for the driver. Until
    ``expected`` threads are up, ``status`` (if given) is told how many are. Inputs
    shorter than ``BATCH_SECONDS`` (by the mean so far) share a task, up to
    ``MAX_BATCH`` of them, so Dask's cost per task is paid once per batch.

    The scheduler fails every task a dying worker held, running or waiting
    (``KilledWorker``); of those, the ``threads`` oldest were running. A waiting task is
    submitted again as it was. A running batch is split and its inputs submitted again
    one per task, uncounted; a running single input counts an attempt and runs again, up
    to ``retries`` times, then yields a ``"crashed"`` outcome. So ``attempts`` counts the
    runs of an input as a task of its own. A batch that fails otherwise (its result cannot
    come back) is split the same way; a single input gets that failure as its ``"error"``.
    With several threads per worker, every task running beside the one that killed it
    counts an attempt.

    Raises:
        EngineError: no worker for ``wait_workers`` seconds.
    """
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    queue: collections.deque[_Item] = collections.deque((spec, 1, False) for spec in specs)
    flying: dict[str, _Flying] = {}
    done = as_completed(with_results=True, raise_errors=False)
    token = f"{time.time_ns():x}"
    order = itertools.count()
    capacity = full = _capacity(client, max_in_flight, expected)
    size, seconds, finished = 1, 0.0, 0
    stages: collections.Counter[str] = collections.Counter()
    starting = _Starting(client, expected, status, wait_workers)

    def handled(outcome: Outcome) -> Iterator[Outcome]:
        t = time.perf_counter()
        yield outcome
        stages["handle"] += time.perf_counter() - t

    try:
        while queue or flying:
            t = time.perf_counter()
            while queue and len(flying) < capacity:
                items = _take(queue, size)
                n = next(order)
                specs_n = [item[0] for item in items]
                fut = client.submit(run_batch, specs_n, key=f"torchsym-{token}-{specs_n[0].index}-{n}", pure=False, retries=0, priority=-n)
                flying[fut.key] = _Flying(items, n, fut)
                done.add(fut)
                if len(items) > 1:
                    logger.debug("batch of %d inputs in task %s", len(items), fut.key)
            t1 = time.perf_counter()
            stages["submit"] += t1 - t
            if not flying:  # every worker is gone: wait for one (a nanny restarts them)
                try:
                    client.wait_for_workers(1, timeout=wait_workers)
                except TimeoutError:
                    raise EngineError(f"engine: no Dask worker for {wait_workers:g} s; {len(queue)} inputs left") from None
                capacity = _capacity(client, max_in_flight)
                continue
            starting.wait(done)
            fut, value = next(done)  # the result is gathered in the background
            stages["wait"] += time.perf_counter() - t1
            if fut.key not in flying:  # already handled with the worker death that took it
                fut.release()
                continue
            exc = None if fut.status == "finished" else (value[1] if isinstance(value, tuple) else value)
            if isinstance(exc, KilledWorker) or capacity < full:
                capacity = _capacity(client, max_in_flight)
                full = max(full, capacity)
            if isinstance(exc, KilledWorker):
                for task, ran in reversed(_killed_with(fut, exc, flying)):
                    for spec, attempt, alone in reversed(task.items):
                        if not ran:
                            queue.appendleft((spec, attempt, alone))
                        elif len(task.items) > 1:
                            queue.appendleft((spec, attempt, True))
                        elif attempt <= retries:
                            logger.warning("%s: its worker died (attempt %d); to run again", spec.input, attempt)
                            queue.appendleft((spec, attempt + 1, True))
                        else:
                            yield from handled((spec, _crashed(attempt, task.future.exception()), attempt))
                fut.release()
                continue
            task = flying.pop(fut.key)
            fut.release()
            if exc is not None and len(task.items) > 1:  # a batch failed outside its inputs: each runs alone
                queue.extendleft((spec, attempt, True) for spec, attempt, _ in reversed(task.items))
                continue
            if exc is not None:  # the task's result could not come back (an error comes as (type, exc, tb))
                yield from handled((task.items[0][0], _error_outcome(exc), task.items[0][1]))
                continue
            outcomes, wall = value
            seconds += wall
            finished += len(outcomes)
            size = max(1, min(MAX_BATCH, int(BATCH_SECONDS * finished / max(seconds, 1e-6))))
            for (spec, attempt, _), outcome in zip(task.items, outcomes, strict=True):
                stages.update(outcome.get("stages", {}))
                yield from handled((spec, outcome, attempt))
    finally:
        starting.done()
        _log_stages("dask", stages, finished)


@contextlib.contextmanager
def open_engine(
    engine: str,
    specs: Sequence[TaskSpec],
    *,
    address: str | None,
    workers: int,
    threads: int,
    imports: Sequence[str],
    retries: int,
    max_in_flight: int | None,
    connect_timeout: float,
    status: Callable[[str], Any] | None = None,
) -> Iterator[tuple[Iterator[Outcome], float]]:
    """``(outcomes, start-up seconds)`` of ``specs`` on ``engine`` (``"serial"``,
    ``"local"`` or ``"dask"``); the cluster, if any, is stopped on leaving. Nothing is
    started when ``specs`` is empty. The local cluster's workers are not waited for
    (:func:`dask_client`): the start-up seconds are the scheduler's, and ``status``
    is told how many workers are up until all are (:func:`dask_outcomes`)."""
    if engine == "serial" or not specs:
        yield serial_outcomes(specs, threads), 0.0
        return
    t0 = time.perf_counter()
    with dask_client(engine, address=address, workers=workers, threads=threads, imports=imports,
                     connect_timeout=connect_timeout) as client:
        expected = workers * threads if engine == "local" else 0
        yield (dask_outcomes(client, specs, retries=retries, max_in_flight=max_in_flight, expected=expected, status=status),
               time.perf_counter() - t0)
