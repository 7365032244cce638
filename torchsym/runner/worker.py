"""The set-up every Dask worker of a run gets (imports ``distributed``; loaded by the engine)."""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["WorkerSetup"]


class WorkerSetup(WorkerPlugin):
    """Limit torch, BLAS and OpenMP to ``threads`` threads (OpenCV per task) and import torchsym (and ``imports``) once per
    worker, before its first task.

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
        importlib.import_module("torchsym")
        for name in self.imports:
            importlib.import_module(name)
