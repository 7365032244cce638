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
it starts (:class:`~torchsym.runner.worker.WorkerSetup`). One task per live worker thread is in flight
(``max_in_flight``), so a 100,000-input run never builds a large graph. A worker that dies
mid-task makes the scheduler raise ``KilledWorker`` for the tasks it held (the local
cluster is started with ``allowed-failures = 0``); the driver runs such a task again alone
(so that a second death is its own) up to ``retries`` times, then records it as
``"crashed"`` (docs/design/runner.md).
"""

from __future__ import annotations

import collections
import contextlib
import logging
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from torchsym.errors import ConfigError, InputFileError, TorchsymError
from torchsym.runner.task import TaskSpec, run_task

__all__ = ["ENGINES", "EngineError", "Outcome", "dask_client", "dask_outcomes", "local_cluster", "open_engine", "serial_outcomes"]

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
    worker (``allowed-failures = 0``: the driver does the retries and counts them)."""
    import dask
    from distributed import LocalCluster

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
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
    """Tasks to keep in flight: ``max_in_flight``, or one per live worker thread."""
    live = sum(client.nthreads().values())
    return live if max_in_flight is None or live == 0 else max_in_flight


def _error_outcome(exc: BaseException) -> dict[str, Any]:
    return {"status": "error", "kind": None, "result": None, "seconds": 0.0, "artifacts": [],
            "error": {"type": type(exc).__name__, "message": str(exc), "where": "engine"}}


def dask_outcomes(
    client: Any, specs: Sequence[TaskSpec], *, retries: int, max_in_flight: int | None = None, wait_workers: float = 600.0
) -> Iterator[Outcome]:
    """Run ``specs`` on ``client``'s workers, yielding each input's outcome as it completes.

    One task per live worker thread is in flight, or ``max_in_flight``. The scheduler
    blames every task a dying worker holds, queued or running, and a task sent to a
    worker dying at that moment: so a task whose worker died is a suspect, not a culprit.
    No new task is submitted until the tasks in flight are done; then each suspect runs
    alone on the cluster, where a second death is its own. A suspect runs up to
    ``retries`` more times, then yields a ``"crashed"`` outcome. With one task per
    thread no task waits queued on a worker, so ``attempts`` counts the deaths of the
    task's own worker; a larger ``max_in_flight`` hides the driver's round trip but a
    task queued behind a crashing one is run again (and counts an attempt).

    Raises:
        EngineError: no worker for ``wait_workers`` seconds.
    """
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    queue = collections.deque((spec, 1) for spec in specs)
    suspects: collections.deque[tuple[TaskSpec, int]] = collections.deque()
    flying: dict[str, tuple[TaskSpec, int]] = {}
    done = as_completed(with_results=True, raise_errors=False)
    token = f"{time.time_ns():x}"
    capacity = full = _capacity(client, max_in_flight)
    while queue or suspects or flying:
        if suspects and not flying:  # a suspect runs alone
            todo = [suspects.popleft()]
        else:
            todo = [queue.popleft() for _ in range(min(len(queue), capacity - len(flying)))] if not suspects else []
        for spec, attempt in todo:
            fut = client.submit(run_task, spec, key=f"torchsym-{token}-{spec.index}-{attempt}", pure=False, retries=0)
            flying[fut.key] = (spec, attempt)
            done.add(fut)
        if not flying:  # every worker is gone: wait for one (a nanny restarts them)
            try:
                client.wait_for_workers(1, timeout=wait_workers)
            except TimeoutError:
                raise EngineError(f"engine: no Dask worker for {wait_workers:g} s; {len(queue)} inputs left") from None
            capacity = _capacity(client, max_in_flight)
            continue
        fut, value = next(done)  # the result is gathered in the background
        spec, attempt = flying.pop(fut.key)
        if fut.status == "finished":
            outcome, exc = value, None
        else:  # KilledWorker, or the task's result could not come back; an error comes as (type, exc, tb)
            exc = value[1] if isinstance(value, tuple) else value
            outcome = _error_outcome(exc)
        fut.release()
        if isinstance(exc, KilledWorker) or capacity < full:
            capacity = _capacity(client, max_in_flight)
            full = max(full, capacity)
        if isinstance(exc, KilledWorker):
            if attempt <= retries:
                logger.warning("%s: its worker died (attempt %d); to run again alone", spec.input, attempt)
                suspects.append((spec, attempt + 1))
                continue
            outcome = _crashed(attempt, exc)
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
