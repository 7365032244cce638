"""The set-up every Dask worker of a run gets (imports ``distributed``; loaded by the engine)."""

from __future__ import annotations

import ctypes
import ctypes.util
import gc
import importlib
from collections.abc import Sequence
from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["WorkerSetup", "keep_freed_memory"]

#: glibc ``mallopt`` parameters
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
#: the bounds glibc's own adaptive thresholds reach on 64-bit (``DEFAULT_MMAP_THRESHOLD_MAX``, twice it)
MMAP_THRESHOLD, TRIM_THRESHOLD = 32 << 20, 64 << 20


def keep_freed_memory() -> bool:
    """Let glibc's ``malloc`` keep freed memory for reuse, as a plain process does: blocks
    up to ``MMAP_THRESHOLD`` (32 MiB) come from the heap, which is trimmed past
    ``TRIM_THRESHOLD`` (64 MiB). Returns whether it was applied (glibc only).

    A Dask nanny starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536``, which also
    turns off glibc's adaptive ``mmap`` threshold: every tensor over 128 KiB is then a
    fresh ``mmap`` whose pages fault in again, about 35,000 page faults and 12 % more CPU
    per 60,000-point plane detection (docs/design/runner.md).
    """
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    return bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))


class WorkerSetup(WorkerPlugin):
    """Prepare a worker for the run's tasks, once, as it joins (before its first task):
    limit torch, BLAS and OpenMP to ``threads`` threads (OpenCV per task), import
    torchsym (and ``imports``), keep freed memory for reuse (:func:`keep_freed_memory`),
    stop the worker's statistical profiler (a stack sample of the running task every
    10 ms, taken holding the GIL; 4 % of a worker's CPU beside a plane detection) and
    move the imported objects out of the garbage collector's reach (``gc.freeze``: the
    full collection at exit took 1.4-1.9 s with torch imported, past the nanny's 4-s
    wait for 2 workers closing on the loaded 2-core machine).

    Args:
        threads: ``torch.set_num_threads`` of the worker.
        imports: further modules to import (e.g. ones that register solvers).
    """

    name = "torchsym-setup"

    def __init__(self, threads: int, imports: Sequence[str] = ()) -> None:
        self.threads = int(threads)
        self.imports = tuple(imports)

    def setup(self, worker: Any) -> None:
        import torch
        from threadpoolctl import threadpool_limits

        torch.set_num_threads(self.threads)
        threadpool_limits(self.threads)  # BLAS and OpenMP, as the serial engine sets them
        keep_freed_memory()
        for name in ("profile", "profile-cycle"):
            callback = getattr(worker, "periodic_callbacks", {}).pop(name, None)
            if callback is not None:
                callback.stop()
        importlib.import_module("torchsym")
        for name in self.imports:
            importlib.import_module(name)
        gc.freeze()  # the modules' objects live as long as the worker: no collection walks them again
