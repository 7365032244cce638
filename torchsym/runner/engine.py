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
it starts (:class:`~torchsym.runner.worker.WorkerSetup`). At most ``max_in_flight`` tasks (default: one per
worker thread) are submitted at a time, so a 100,000-input run never builds a large
graph. A worker that dies mid-task makes the scheduler raise ``KilledWorker`` for the
tasks it held (the local cluster is started with ``allowed-failures = 0``); the driver
resubmits each up to ``retries`` times, then records it as ``"crashed"``. The scheduler
blames every task a dead worker held, queued or running: one task per thread keeps the
queued ones out of the blame (docs/design/runner.md).
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from torchsym.errors import ConfigError, InputFileError, TorchsymError
from torchsym.runner.task import TaskSpec, run_task

__all__ = ["ENGINES", "EngineError", "Outcome", "dask_client", "dask_outcomes", "open_engine", "serial_outcomes"]

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
    """Run ``specs`` one after another in this process, torch limited to ``threads``."""
    import torch

    before = torch.get_num_threads()
    try:
        for spec in specs:
            yield spec, run_task(spec), 1
    finally:
        torch.set_num_threads(before)


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


@contextlib.contextmanager
def dask_client(
    engine: str, *, address: str | None, workers: int, threads: int, imports: Sequence[str] = (), connect_timeout: float = 5.0
) -> Iterator[Any]:
    """A ``distributed.Client`` on a fresh ``LocalCluster`` (``engine="local"``) or on the
    scheduler at ``address`` (``engine="dask"``), with :class:`~torchsym.runner.worker.WorkerSetup` registered.

    Raises:
        EngineError: the scheduler cannot be reached within ``connect_timeout`` seconds.
    """
    import dask
    from distributed import Client, LocalCluster

    from torchsym.runner.worker import WorkerSetup

    stack = contextlib.ExitStack()
    with stack:
        if engine == "local":
            conf = {"distributed.scheduler.allowed-failures": 0, "distributed.scheduler.worker-saturation": 1.0}
            with dask.config.set(conf):
                cluster = stack.enter_context(
                    LocalCluster(
                        n_workers=workers, threads_per_worker=threads, processes=True,
                        dashboard_address=None, silence_logs=logging.ERROR,
                    )
                )
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


def dask_outcomes(client: Any, specs: Sequence[TaskSpec], *, retries: int, max_in_flight: int) -> Iterator[Outcome]:
    """Run ``specs`` on ``client``'s workers, at most ``max_in_flight`` at a time, yielding
    each input's outcome as it completes; a task whose worker died is resubmitted up to
    ``retries`` times, then yields a ``"crashed"`` outcome."""
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    pending = iter(specs)
    flying: dict[str, tuple[TaskSpec, int]] = {}
    done = as_completed()
    token = f"{time.time_ns():x}"

    def submit(spec: TaskSpec, attempt: int) -> None:
        fut = client.submit(run_task, spec, key=f"torchsym-{token}-{spec.index}-{attempt}", pure=False, retries=0)
        flying[fut.key] = (spec, attempt)
        done.add(fut)

    for spec in pending:
        submit(spec, 1)
        if len(flying) >= max_in_flight:
            break
    for fut in done:
        spec, attempt = flying.pop(fut.key)
        try:
            outcome, exc = fut.result(), None
        except Exception as err:  # KilledWorker, or the task's result could not come back
            outcome, exc = None, err
        fut.release()
        if isinstance(exc, KilledWorker):
            if attempt <= retries:
                logger.warning("%s: its worker died (attempt %d); resubmitted", spec.input, attempt)
                submit(spec, attempt + 1)
                continue
            outcome = _crashed(attempt, exc)
        elif exc is not None:  # the task never ran to its end for another reason (e.g. unpicklable result)
            outcome = {"status": "error", "kind": None, "result": None, "seconds": 0.0, "artifacts": [],
                       "error": {"type": type(exc).__name__, "message": str(exc), "where": "engine"}}
        nxt = next(pending, None)
        if nxt is not None:
            submit(nxt, 1)
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
        limit = max_in_flight or max(1, sum(client.nthreads().values()))
        yield dask_outcomes(client, specs, retries=retries, max_in_flight=limit), time.perf_counter() - t0
