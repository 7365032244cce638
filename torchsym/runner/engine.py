"""Where the tasks of a dataset run are computed: in the driver, or on Dask workers.

Three engines give the same records (only where a task runs changes):

- ``"serial"``: one task after another in the driver process. No start-up cost; a task
  that kills the process kills the run (resume re-runs it).
- ``"local"``: a Dask ``LocalCluster`` of ``workers`` processes with
  ``threads_per_worker`` threads each, started and stopped by the run.
- ``"dask"``: an existing Dask scheduler, named by ``address`` (``tcp://host:8786`` or a
  ``scheduler.json`` file) or by ``DASK_SCHEDULER_ADDRESS``; SLURM/PBS clusters through
  ``dask-jobqueue``.

Each worker sets ``torch.set_num_threads(threads_per_worker)`` and imports torchsym when
it starts (:class:`~torchsym.runner.worker.WorkerSetup`). Two tasks per live worker thread are in
flight (``max_in_flight``), so a 100,000-input run never builds a large graph and no worker
waits for the driver. A worker that dies mid-task makes the scheduler raise ``KilledWorker``
for the tasks it held (the local cluster is started with ``allowed-failures = 0``); the
driver runs the task that was running again up to ``retries`` times, then records it as
``"crashed"``, and resubmits the tasks that were only waiting there uncounted
(docs/design/runner.md).
"""

from __future__ import annotations

import collections
import contextlib
import dataclasses
import itertools
import logging
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from torchsym.errors import ConfigError, InputFileError, TorchsymError
from torchsym.runner.task import TaskSpec, run_task

__all__ = [
    "BATCH_SECONDS", "ENGINES", "MAX_BATCH", "EngineError", "Outcome", "dask_client", "dask_outcomes", "local_cluster", "open_engine",
    "run_batch", "serial_outcomes",
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


def serial_outcomes(specs: Sequence[TaskSpec], threads: int) -> Iterator[Outcome]:
    """Run ``specs`` one after another in this process, torch, OpenCV, BLAS and OpenMP limited
    to ``threads`` threads as on a worker (the results do not depend on the engine)."""
    import cv2
    import torch
    from threadpoolctl import threadpool_limits

    before = torch.get_num_threads(), cv2.getNumThreads()
    try:
        with threadpool_limits(threads):  # BLAS and OpenMP as on a worker
            for spec in specs:
                yield spec, run_task(spec), 1
    finally:
        torch.set_num_threads(before[0])
        cv2.setNumThreads(before[1])


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


def local_cluster(workers: int, threads: int) -> Any:
    """A ``distributed.LocalCluster`` of ``workers`` processes with ``threads`` threads
    each, on loopback, no dashboard, whose scheduler fails a task on its first dead
    worker (``allowed-failures = 0``: the driver does the retries and counts them) and
    never moves a task between workers (no work stealing: each worker runs its tasks in
    submission order, which tells a running task from a waiting one when it dies)."""
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

    Raises:
        EngineError: the scheduler cannot be reached within ``connect_timeout`` seconds.
    """
    from distributed import Client

    from torchsym.runner.worker import WorkerSetup

    stack = contextlib.ExitStack()
    with stack:
        if engine == "local":
            cluster = stack.enter_context(local_cluster(workers, threads))
            client = stack.enter_context(Client(cluster))
            where = "a local cluster"
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


def _capacity(client: Any, max_in_flight: int | None) -> int:
    """Tasks to keep in flight: ``max_in_flight``, or two per live worker thread (one
    running, one waiting on the worker, so a worker never waits for the driver)."""
    live = sum(client.nthreads().values())
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
    the outcomes and the batch's wall seconds (pictures included, which size the batches)."""
    t0 = time.perf_counter()
    return [run_task(spec) for spec in specs], time.perf_counter() - t0


def _take(queue: collections.deque[_Item], size: int) -> tuple[_Item, ...]:
    """The next task's inputs: one that runs alone, or up to ``size`` that may share a task."""
    first = queue.popleft()
    items = [first]
    while not first[2] and queue and len(items) < size and not queue[0][2]:
        items.append(queue.popleft())
    return tuple(items)


def dask_outcomes(
    client: Any, specs: Sequence[TaskSpec], *, retries: int, max_in_flight: int | None = None, wait_workers: float = 600.0
) -> Iterator[Outcome]:
    """Run ``specs`` on ``client``'s workers, yielding each input's outcome as it completes.

    Two tasks per live worker thread are in flight, or ``max_in_flight``: one running and
    one waiting on the worker, so a worker starts its next task without waiting for the
    driver. Inputs shorter than ``BATCH_SECONDS`` (by the mean so far) share a task, up to
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
    capacity = full = _capacity(client, max_in_flight)
    size, seconds, finished = 1, 0.0, 0
    while queue or flying:
        while queue and len(flying) < capacity:
            items = _take(queue, size)
            n = next(order)
            specs_n = [item[0] for item in items]
            fut = client.submit(run_batch, specs_n, key=f"torchsym-{token}-{specs_n[0].index}-{n}", pure=False, retries=0, priority=-n)
            flying[fut.key] = _Flying(items, n, fut)
            done.add(fut)
            if len(items) > 1:
                logger.debug("batch of %d inputs in task %s", len(items), fut.key)
        if not flying:  # every worker is gone: wait for one (a nanny restarts them)
            try:
                client.wait_for_workers(1, timeout=wait_workers)
            except TimeoutError:
                raise EngineError(f"engine: no Dask worker for {wait_workers:g} s; {len(queue)} inputs left") from None
            capacity = _capacity(client, max_in_flight)
            continue
        fut, value = next(done)  # the result is gathered in the background
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
                        yield spec, _crashed(attempt, task.future.exception()), attempt
            fut.release()
            continue
        task = flying.pop(fut.key)
        fut.release()
        if exc is not None and len(task.items) > 1:  # a batch failed outside its inputs: each runs alone
            queue.extendleft((spec, attempt, True) for spec, attempt, _ in reversed(task.items))
            continue
        if exc is not None:  # the task's result could not come back (an error comes as (type, exc, tb))
            yield task.items[0][0], _error_outcome(exc), task.items[0][1]
            continue
        outcomes, wall = value
        seconds += wall
        finished += len(outcomes)
        size = max(1, min(MAX_BATCH, int(BATCH_SECONDS * finished / max(seconds, 1e-6))))
        for (spec, attempt, _), outcome in zip(task.items, outcomes, strict=True):
            yield spec, outcome, attempt


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
) -> Iterator[tuple[Iterator[Outcome], float]]:
    """``(outcomes, start-up seconds)`` of ``specs`` on ``engine`` (``"serial"``,
    ``"local"`` or ``"dask"``); the cluster, if any, is stopped on leaving. Nothing is
    started when ``specs`` is empty."""
    if engine == "serial" or not specs:
        yield serial_outcomes(specs, threads), 0.0
        return
    t0 = time.perf_counter()
    with dask_client(engine, address=address, workers=workers, threads=threads, imports=imports,
                     connect_timeout=connect_timeout) as client:
        yield dask_outcomes(client, specs, retries=retries, max_in_flight=max_in_flight), time.perf_counter() - t0
