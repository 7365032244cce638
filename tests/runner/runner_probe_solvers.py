"""A test-only solver for the runner's tests: its behaviour is chosen by the input.

Imported by the tests and, through ``torchsym.run(..., imports=["runner_probe_solvers"])``,
by every worker (the test folder is on the workers' ``sys.path``). The first point of the
cloud decides what happens:

- ``x0 == 666``: the process dies (``os._exit``) every time;
- ``x0 == 777``: the process dies the first time (a marker file in ``marker_dir``), then
  the task succeeds;
- ``x0 == 555``: a :class:`~torchsym.errors.InputValueError`;
- otherwise the result is the cloud's mean; with the environment variable
  ``RUNNER_PROBE_DIE_AFTER=k`` the process dies when it starts its k-th input (a counter
  file in ``marker_dir``), a driver killed mid-run (the config, hence its hash, unchanged).
"""

from __future__ import annotations

import dataclasses
import os
import time
from pathlib import Path

import torch

from torchsym.core.registry import SOLVERS, register_solver
from torchsym.core.results import Result
from torchsym.core.settings import Settings, Solver, setting
from torchsym.errors import InputValueError


@dataclasses.dataclass(frozen=True)
class ProbeSettings(Settings):
    marker_dir: str = setting("", "folder for the crash markers and the counter")
    sleep: float = setting(0.0, "seconds to sleep per input", unit="s", low=0.0)
    delay: float = setting(0.0, "seconds to wait before anything, crashes included", unit="s", low=0.0)


@dataclasses.dataclass(frozen=True)
class ProbeResult(Result):
    """Attributes: normal ``(3,)``: the mean point; offset: the number of points; score: 1."""

    normal: torch.Tensor
    offset: float
    score: float


def _count(marker_dir: str) -> int:
    path = Path(marker_dir) / "count"
    n = int(path.read_text()) + 1 if path.is_file() else 1
    path.write_text(str(n))
    return n


class ProbeSolver(Solver):
    """Test-only solver (tests/runner)."""

    settings_class = ProbeSettings

    def forward(self, data, generator=None):
        s = self.settings
        if s.delay:
            time.sleep(s.delay)
        x0 = float(data[0, 0])
        die_after = int(os.environ.get("RUNNER_PROBE_DIE_AFTER", "0"))
        if die_after and _count(s.marker_dir) == die_after:
            os._exit(3)
        if x0 == 666:
            os._exit(4)
        if x0 == 777:
            marker = Path(s.marker_dir) / "once"
            if not marker.exists():
                marker.write_text("died")
                os._exit(5)
        if x0 == 555:
            raise InputValueError("points: the probe refuses x0 = 555")
        if s.sleep:
            time.sleep(s.sleep)
        return ProbeResult(data.double().mean(0), float(data.shape[0]), 1.0)


def register() -> None:
    """Register ``runner_probe`` (done on import; the tests' fixture removes it after each test)."""
    if "runner_probe" not in SOLVERS:
        register_solver("runner_probe", kind="pointcloud")(ProbeSolver)


def unregister() -> None:
    SOLVERS._entries.pop("runner_probe", None)


register()
