"""The worker set-up and the engines' stage breakdown, without starting a cluster."""

import gc
import logging
import sys

import pytest
from conftest import PROBE, probe_config, write_cloud

from torchsym.runner import run
from torchsym.runner.engine import STAGES, _Starting
from torchsym.runner.worker import WorkerSetup, keep_freed_memory


class _Callback:
    def __init__(self) -> None:
        self.stopped = False

    def stop(self) -> None:
        self.stopped = True


class _Worker:
    def __init__(self) -> None:
        self.periodic_callbacks = {"profile": _Callback(), "profile-cycle": _Callback(), "heartbeat": _Callback()}


def test_worker_setup_stops_the_profiler_and_freezes_the_imports():
    import torch

    worker, before = _Worker(), torch.get_num_threads()
    profile = worker.periodic_callbacks["profile"]
    try:
        WorkerSetup(1, imports=[PROBE]).setup(worker)
        assert torch.get_num_threads() == 1 and PROBE in sys.modules
        assert sorted(worker.periodic_callbacks) == ["heartbeat"] and profile.stopped
        assert not worker.periodic_callbacks["heartbeat"].stopped
        assert gc.get_freeze_count() > 0
    finally:
        gc.unfreeze()
        torch.set_num_threads(before)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_keep_freed_memory_on_glibc():
    assert keep_freed_memory() is True


def test_serial_engine_logs_the_stages(tmp_path, markers, caplog):
    folder = tmp_path / "in"
    folder.mkdir()
    for i in range(3):
        write_cloud(folder / f"c{i}.xyz", i)
    caplog.set_level(logging.INFO, logger="torchsym.runner.engine")
    run(probe_config(markers), str(folder), tmp_path / "r.jsonl", engine="serial", imports=[PROBE])
    (rec,) = [r for r in caplog.records if hasattr(r, "stages")]
    assert rec.n == 3 and sorted(rec.stages) == sorted(STAGES)
    assert rec.stages["solve"] > 0 and rec.stages["cpu"] > 0 and rec.stages["handle"] > 0  # the driver wrote 3 records


class _Client:
    def __init__(self, counts):
        self.counts = list(counts)

    def nthreads(self):
        n = self.counts.pop(0) if len(self.counts) > 1 else self.counts[0]
        return {f"w{i}": 1 for i in range(n)}


class _Done:
    def has_ready(self):
        return False


def test_starting_tells_the_workers_up_until_all_are():
    said = []
    starting = _Starting(_Client([0, 1, 2]), 2, said.append, wait_workers=60)
    starting.wait(_Done())  # returns once both are up
    assert said == ["waiting for workers: 0/2 threads up", "waiting for workers: 1/2 threads up", ""]
    assert not starting.active


def test_starting_without_any_worker_is_an_error():
    from torchsym.runner import EngineError

    with pytest.raises(EngineError, match="no Dask worker started within 0.3 s"):
        _Starting(_Client([0]), 2, None, wait_workers=0.3).wait(_Done())
