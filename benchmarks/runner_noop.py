"""A solver that does nothing, for measuring the dataset runner's cost per input
(``benchmarks/bench_runner.py``; imported on each worker through ``imports=``)."""

from __future__ import annotations

import dataclasses
import time

import torch

from torchsym.core.registry import SOLVERS, register_solver
from torchsym.core.results import Result
from torchsym.core.settings import Settings, Solver, setting


@dataclasses.dataclass(frozen=True)
class NoopSettings(Settings):
    sleep: float = setting(0.0, "seconds to sleep per input", unit="s", low=0.0)
    log: str = setting("", "file to which each call appends the input's first coordinate; empty: none")


@dataclasses.dataclass(frozen=True)
class NoopResult(Result):
    """Attributes: n: the number of points."""

    n: int


if "bench_noop" not in SOLVERS:

    @register_solver("bench_noop", kind="pointcloud")
    class NoopSolver(Solver):
        """Returns the number of points (benchmarks only)."""

        settings_class = NoopSettings

        def forward(self, data: torch.Tensor, generator: torch.Generator | None = None) -> NoopResult:
            if self.settings.log:
                with open(self.settings.log, "a") as fh:
                    fh.write(f"{float(data[0, 0])!r}\n")
            if self.settings.sleep:
                time.sleep(self.settings.sleep)
            return NoopResult(int(data.shape[0]))
