"""Independent branches of a solver on threads, with results in a fixed order."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

import torch

__all__ = ["run_branches", "thread_budget"]

T = TypeVar("T")


def thread_budget() -> int:
    """Threads the library may use outside torch (kd-tree queries, solver branches):
    torch's thread count, so that one ``torch.set_num_threads`` (a user's limit, a dataset
    runner's worker) bounds them all."""
    return max(1, torch.get_num_threads())


def run_branches(tasks: Sequence[Callable[[], T]], max_workers: int | None = None) -> list[T]:
    """Run ``tasks`` (callables without arguments) on threads; their results in the order given.

    For branches of a solver that share no mutable state: each result is what the task
    would return alone, whatever the scheduling, so a seeded solver stays bit for bit
    deterministic. It pays where the branches spend their time in code that releases the
    GIL (numpy products, kd-tree searches) or where one branch holds the GIL (scipy's
    Dijkstra) while the other computes: the solvers hold BLAS to one thread, which leaves
    the second core idle in single-threaded stretches. The first exception raised by a
    task, in the order given, is raised here once every task has ended.

    Args:
        tasks: the branches.
        max_workers: threads; default ``min(len(tasks), thread_budget())``. 1 runs the
            tasks one after another on the calling thread.
    """
    tasks = list(tasks)
    workers = min(len(tasks), thread_budget()) if max_workers is None else int(max_workers)
    if workers <= 1 or len(tasks) <= 1:
        return [task() for task in tasks]
    with ThreadPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(task) for task in tasks]
    return [future.result() for future in futures]
