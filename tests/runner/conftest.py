from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import runner_probe_solvers

runner_probe_solvers.unregister()  # registered by the fixture below, during runner tests only

PROBE = "runner_probe_solvers"


def write_cloud(path: Path, seed: int, x0: float | None = None, n: int = 20) -> Path:
    """A small random cloud in ``.xyz``; ``x0`` sets its first coordinate (the probe's switch)."""
    x = np.random.default_rng(seed).normal(size=(n, 3))
    if x0 is not None:
        x[0, 0] = x0
    np.savetxt(path, x)
    return path


def probe_config(marker_dir: Path, **params) -> dict:
    return {"input": "pointcloud", "steps": [{"name": "runner_probe", "params": {"marker_dir": str(marker_dir), **params}}]}


@pytest.fixture
def markers(tmp_path: Path) -> Path:
    d = tmp_path / "markers"
    d.mkdir()
    return d


@pytest.fixture(autouse=True)
def probe_solver():
    """The test-only solver ``runner_probe``, registered during each test only (the
    registry-wide tests elsewhere must not see it)."""
    runner_probe_solvers.register()
    yield
    runner_probe_solvers.unregister()
