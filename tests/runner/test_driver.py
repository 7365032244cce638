import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import PROBE, probe_config, write_cloud

import torchsym
from torchsym.errors import ConfigError, InputFileError, InputValueError
from torchsym.runner import EngineError, expand_inputs, read_results, run


def _clouds(folder: Path, n: int, **special) -> list[Path]:
    """``n`` clouds c0.xyz... in ``folder``; ``special`` maps an index (``i2=555``) to the probe's x0."""
    folder.mkdir(exist_ok=True)
    return [write_cloud(folder / f"c{i}.xyz", i, special.get(f"i{i}")) for i in range(n)]


class TestRunSerial:
    def test_smoke(self, tmp_path, markers):
        _clouds(tmp_path / "in", 3, i1=555)
        out = tmp_path / "r.jsonl"
        summary = run(probe_config(markers), str(tmp_path / "in" / "*.xyz"), out, engine="serial", imports=[PROBE])
        assert (summary.engine, summary.n_inputs, summary.n_ok, summary.n_error, summary.n_crashed) == ("serial", 3, 2, 1, 0)
        records = {Path(r["input"]).name: r for r in read_results(out)}
        ok, err = records["c0.xyz"], records["c1.xyz"]
        assert ok["status"] == "ok" and ok["kind"] == "pointcloud" and ok["attempts"] == 1 and ok["error"] is None
        assert ok["result"]["type"] == "ProbeResult" and ok["result"]["offset"] == 20.0 and ok["seconds"] >= 0
        assert set(ok) >= {"input", "size", "mtime_ns", "config_hash", "status", "result", "error", "seconds", "attempts"}
        # a TorchsymError is final: recorded once, never retried
        assert err["status"] == "error" and err["attempts"] == 1 and err["result"] is None
        assert err["error"]["type"] == "InputValueError" and "x0 = 555" in err["error"]["message"]

    def test_resume_skips_done_inputs(self, tmp_path, markers):
        files = _clouds(tmp_path / "in", 3, i1=555)
        out = tmp_path / "r.jsonl"
        cfg = probe_config(markers)
        run(cfg, [str(f) for f in files], out, engine="serial", imports=[PROBE])
        again = run(cfg, [str(f) for f in files], out, engine="serial", imports=[PROBE])
        assert (again.n_skipped, again.n_run) == (3, 0)  # errors are final too
        os.utime(files[0], ns=(10**18, 10**18))  # a changed file runs again
        assert run(cfg, [str(f) for f in files], out, engine="serial", imports=[PROBE]).n_run == 1
        other = run(cfg, [str(f) for f in files], out, engine="serial", imports=[PROBE], overrides={"sleep": 0.001})
        assert other.n_run == 3  # another config runs everything again
        fresh = run(cfg, [str(f) for f in files], out, engine="serial", imports=[PROBE], resume=False)
        assert fresh.n_run == 3 and len(read_results(out, latest=False)) == 3

    @pytest.mark.slow
    def test_driver_killed_and_resumed(self, tmp_path, markers):
        files = _clouds(tmp_path / "in", 6)
        out = tmp_path / "r.jsonl"
        script = (
            "import sys, torchsym; sys.path.insert(0, sys.argv[1]); import runner_probe_solvers\n"
            "from conftest import probe_config\nrunner_probe_solvers.register()\n"
            "torchsym.run(probe_config(sys.argv[2]), sys.argv[3], sys.argv[4], engine='serial')\n"
        )
        env = {**os.environ, "RUNNER_PROBE_DIE_AFTER": "4"}
        args = [sys.executable, "-c", script, str(Path(__file__).parent), str(markers), str(tmp_path / "in" / "*.xyz"), str(out)]
        proc = subprocess.run(args, env=env, cwd=Path(torchsym.__file__).parents[1], capture_output=True, text=True)
        assert proc.returncode == 3, proc.stderr  # the probe's os._exit(3) on its 4th input
        assert [Path(r["input"]).name for r in read_results(out)] == ["c0.xyz", "c1.xyz", "c2.xyz"]
        summary = run(probe_config(markers), [str(f) for f in files], out, engine="serial", imports=[PROBE])
        assert (summary.n_skipped, summary.n_ok) == (3, 3)  # the lock died with the driver
        lines = read_results(out, latest=False)
        assert sorted(Path(r["input"]).name for r in lines) == [f"c{i}.xyz" for i in range(6)]  # nothing repeated

    def test_figures(self, tmp_path):
        cloud = torchsym.pointcloud.planted_symmetric_cloud(400, generator=0)
        path = tmp_path / "planted.xyz"
        import numpy as np

        np.savetxt(path, cloud.points.numpy())
        cfg = {"input": "pointcloud", "steps": [{"name": "reflection_plane", "params": {"n_starts": 2, "seed": 0}}]}
        run(cfg, [str(path)], tmp_path / "r.jsonl", engine="serial", figures=tmp_path / "fig")
        rec = read_results(tmp_path / "r.jsonl")[0]
        assert rec["status"] == "ok" and rec["artifacts"]
        assert all(Path(a).is_file() and Path(a).parent == tmp_path / "fig" for a in rec["artifacts"])

    def test_large_arrays_beside_the_record(self, tmp_path, caplog):
        import json

        import numpy as np

        cloud = torchsym.pointcloud.planted_symmetric_cloud(300, generator=0)
        path = tmp_path / "planted.xyz"
        np.savetxt(path, cloud.points.numpy())
        cfg = {"input": "pointcloud", "steps": [{"name": "reflection_plane", "params": {"n_starts": 2, "seed": 0}}]}
        run(cfg, [str(path)], tmp_path / "apart.jsonl", engine="serial", max_inline=64)
        run(cfg, [str(path)], tmp_path / "inline.jsonl", engine="serial", max_inline=None)
        line = json.loads((tmp_path / "apart.jsonl").read_text())
        ref = line["result"]["pairs"]
        assert ref["$array"] == "pairs" and ref["shape"][1] == 2 and line["arrays"].endswith(".npz")
        assert (tmp_path / "apart_arrays" / line["arrays"]).is_file()
        assert line["result"]["normal"] == json.loads((tmp_path / "inline.jsonl").read_text())["result"]["normal"]
        apart, inline = read_results(tmp_path / "apart.jsonl")[0], read_results(tmp_path / "inline.jsonl")[0]
        assert inline["arrays"] is None and isinstance(inline["result"]["pairs"], list)
        for name in ("pairs", "inliers"):
            assert isinstance(apart["result"][name], np.ndarray) and apart["result"][name].tolist() == inline["result"][name]
        assert read_results(tmp_path / "apart.jsonl", arrays=False)[0]["result"]["pairs"] == ref
        (tmp_path / "apart_arrays" / line["arrays"]).unlink()  # a results file copied without its arrays
        with caplog.at_level("WARNING"):
            assert read_results(tmp_path / "apart.jsonl")[0]["result"]["pairs"] == ref
        assert "references kept" in caplog.text


class TestBadInput:
    def test_max_inline(self, tmp_path, markers):
        _clouds(tmp_path / "in", 1)
        with pytest.raises(InputValueError, match="max_inline: expected a count >= 0 or None, got -1"):
            run(probe_config(markers), str(tmp_path / "in"), tmp_path / "r.jsonl", imports=[PROBE], max_inline=-1)

    def test_glob_matches_nothing(self, tmp_path, markers):
        with pytest.raises(InputFileError, match=r"inputs: '.*nothing\*\.ply' matches no file"):
            run(probe_config(markers), [str(tmp_path / "nothing*.ply")], tmp_path / "r.jsonl", imports=[PROBE])
        assert not (tmp_path / "r.jsonl").exists()

    def test_config_for_another_kind(self, tmp_path):
        _clouds(tmp_path / "in", 2)
        cfg = {"input": "image", "steps": [{"name": "ksymmetry"}]}
        with pytest.raises(InputValueError, match=r"inputs: no image input .* \(skipped 2 file\(s\) that hold no image input .*: c0.xyz, c1.xyz\)"):
            run(cfg, str(tmp_path / "in"), tmp_path / "r.jsonl")
        with pytest.raises(ConfigError, match=r"takes 'image' input .*, but '.*c0\.xyz' is not one \(2 of 2 inputs\)"):
            run(cfg, [str(tmp_path / "in" / "c*.xyz")], tmp_path / "r.jsonl")

    def test_unreachable_address(self, tmp_path, markers):
        _clouds(tmp_path / "in", 2)
        with pytest.raises(EngineError, match=r"--address: cannot reach the Dask scheduler at 'tcp://127\.0\.0\.1:9' within 0\.5 s"):
            run(probe_config(markers), str(tmp_path / "in"), tmp_path / "r.jsonl", imports=[PROBE],
                address="tcp://127.0.0.1:9", connect_timeout=0.5)

    def test_missing_scheduler_file(self, tmp_path, markers):
        _clouds(tmp_path / "in", 2)
        with pytest.raises(InputFileError, match=r"--address: scheduler file '.*sched\.json' does not exist"):
            run(probe_config(markers), str(tmp_path / "in"), tmp_path / "r.jsonl", imports=[PROBE],
                engine="dask", address=str(tmp_path / "sched.json"))

    def test_dask_without_address(self, tmp_path, markers, monkeypatch):
        monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
        _clouds(tmp_path / "in", 2)
        with pytest.raises(ConfigError, match="--address: the dask engine needs a scheduler"):
            run(probe_config(markers), str(tmp_path / "in"), tmp_path / "r.jsonl", imports=[PROBE], engine="dask")

    def test_unknown_engine(self, tmp_path, markers):
        _clouds(tmp_path / "in", 1)
        with pytest.raises(InputValueError, match="engine: expected one of auto, serial, local, dask, got 'ray'"):
            run(probe_config(markers), str(tmp_path / "in"), tmp_path / "r.jsonl", imports=[PROBE], engine="ray")


class TestExpandInputs:
    def test_folders_globs_and_duplicates(self, tmp_path):
        files = _clouds(tmp_path / "in", 3)
        (tmp_path / "in" / "notes.md").write_text("x")
        (tmp_path / "in" / "deep").mkdir()
        write_cloud(tmp_path / "in" / "deep" / "d.xyz", 9)
        got = expand_inputs([str(tmp_path / "in"), str(files[0]), str(tmp_path / "in" / "c*.xyz")], "pointcloud")
        assert [s.files for s in got] == [(str(f),) for f in files] and [s.stem for s in got] == ["c0", "c1", "c2"]
        assert got[0].notes == ("skipped 1 file(s) that hold no pointcloud input (.ply .obj .off .stl .xyz .npy .txt .pts): notes.md",)
        assert len(expand_inputs([str(tmp_path / "**" / "*.xyz")])) == 4

    def test_scenes(self, tmp_path):
        # multiview: a folder of photos is one scene, a folder of folders one scene per folder, loose photos one scene
        for scene in ("a", "b"):
            (tmp_path / "s" / scene).mkdir(parents=True)
            for i in range(3):
                (tmp_path / "s" / scene / f"{i}.png").write_bytes(b"")
        (tmp_path / "s" / "a" / "K.txt").write_text("1 0 0")
        got = expand_inputs([str(tmp_path / "s")], "multiview")
        assert [(Path(s.name).name, len(s.files), s.stem) for s in got] == [("a", 3, "a"), ("b", 3, "b")]
        assert got[0].notes and "K.txt" in got[0].notes[0] and not got[1].notes
        one = expand_inputs([str(tmp_path / "s" / "a")], "multiview")
        assert len(one) == 1 and len(one[0].files) == 3
        loose = expand_inputs([str(tmp_path / "s" / "a" / "*")], "multiview")
        assert len(loose) == 1 and len(loose[0].files) == 3 and "K.txt" in loose[0].notes[0]
        with pytest.raises(InputValueError, match="inputs: no multiview input"):
            expand_inputs([str(tmp_path / "s" / "a" / "K.txt")], "multiview")


class TestChooseEngine:
    def test_auto(self, monkeypatch):
        from torchsym.runner.driver import SERIAL_MAX, _choose_engine

        monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
        assert _choose_engine("auto", SERIAL_MAX, None) == "serial"
        assert _choose_engine("auto", SERIAL_MAX + 1, None) == "local"
        assert _choose_engine("auto", 1, "tcp://127.0.0.1:8786") == "dask"
        monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "tcp://127.0.0.1:8786")
        assert _choose_engine("auto", 1, None) == "dask"
        assert _choose_engine("serial", 100, None) == "serial"


class TestEngineOptions:
    def test_options_object_and_keywords_agree(self, tmp_path):
        from torchsym.runner import EngineOptions

        cloud = tmp_path / "c.npy"
        np.save(cloud, torchsym.data.sample_pointcloud().numpy()[:400])
        a = torchsym.run("pointcloud_plane", [str(cloud)], tmp_path / "a.jsonl", options=EngineOptions(engine="serial"))
        b = torchsym.run("pointcloud_plane", [str(cloud)], tmp_path / "b.jsonl", engine="serial")
        assert a.engine == b.engine == "serial"
        ra, rb = torchsym.read_results(tmp_path / "a.jsonl")[0], torchsym.read_results(tmp_path / "b.jsonl")[0]
        assert ra["result"]["normal"] == rb["result"]["normal"]

    def test_unknown_option_is_named(self, tmp_path):
        with pytest.raises(torchsym.InputValueError, match="wrokers: not an option of torchsym.run"):
            torchsym.run("pointcloud_plane", ["x.npy"], tmp_path / "a.jsonl", wrokers=2)
