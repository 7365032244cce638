import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import torchsym
from torchsym.cli import main


class TestCLI:
    def test_help(self):
        out = subprocess.run([sys.executable, "-m", "torchsym", "detect", "--help"], capture_output=True, text=True)
        assert out.returncode == 0 and "--config" in out.stdout and "pipeline" in out.stdout

    def test_demo(self, tmp_path, capsys):
        assert main(["demo", "--out", str(tmp_path)]) == 0
        assert (tmp_path / "chair.json").is_file() and (tmp_path / "chair_plane.png").is_file()
        assert (tmp_path / "chair_plane.ply").is_file()
        assert "angle to the true plane" in capsys.readouterr().out

    def test_detect_with_config_and_set(self, tmp_path):
        cfg = torchsym.data.sample_path("chair.ply").parents[2] / "configs" / "pointcloud_plane.yaml"
        args = ["detect", str(torchsym.data.sample_path("chair.ply")), "--out", str(tmp_path), "--set", "n_starts=2", "--no-figures"]
        assert cfg.is_file(), cfg
        args += ["--config", str(cfg)]
        assert main(args) == 0
        record = json.loads((tmp_path / "chair.json").read_text())
        assert record["result"]["type"] == "ReflectionPlaneResult" and record["config"]["steps"][0]["params"]["n_starts"] == 2

    def test_bad_input(self, tmp_path, capsys):
        bad = tmp_path / "x.ply"
        bad.write_text("nonsense")
        assert main(["detect", str(bad), "--out", str(tmp_path)]) == 1  # the input failed
        assert "cannot read" in capsys.readouterr().err

    def test_unknown_setting(self, tmp_path, capsys):
        code = main(["detect", str(torchsym.data.sample_path("chair.ply")), "--out", str(tmp_path), "--set", "n_strats=2"])
        assert code == 2 and "did you mean 'n_starts'" in capsys.readouterr().err

    def test_out_that_cannot_be_created(self, tmp_path, capsys):
        blocker = tmp_path / "file.txt"
        blocker.write_text("not a folder")
        code = main(["detect", str(torchsym.data.sample_path("chair.ply")), "--out", str(blocker / "sub"), "-q"])
        assert code == 2 and "--out: cannot create the folder" in capsys.readouterr().err
        assert main(["demo", "--out", str(blocker / "sub")]) == 2
        assert "--out: cannot create the folder" in capsys.readouterr().err

    @pytest.mark.slow
    def test_never_overwrites_an_input(self, tmp_path, capsys):
        import shutil

        sample = torchsym.data.sample_path("chair.ply")
        shutil.copy(sample, tmp_path / "chair.ply")
        # an input named as chair.ply's picture of the plane would be written
        shutil.copy(sample, tmp_path / "chair_plane.ply")
        before = (tmp_path / "chair_plane.ply").read_bytes()
        code = main(["detect", str(tmp_path), "--out", str(tmp_path), "-q"])
        err = capsys.readouterr().err
        assert code == 1 and "would overwrite the input" in err and "chair_plane.ply" in err
        assert (tmp_path / "chair_plane.ply").read_bytes() == before
        assert not (tmp_path / "chair.json").exists()  # nothing of the refused input was written
        assert (tmp_path / "chair_plane.json").is_file() and (tmp_path / "chair_plane_plane.ply").is_file()
        hidden = [q.name for q in tmp_path.iterdir() if q.name.startswith(".")]
        assert hidden == [".torchsym-outputs.json"]  # staging folders removed, the manifest kept

    @pytest.mark.slow
    def test_inputs_sharing_a_stem_keep_their_own_results(self, tmp_path, capsys):
        import shutil

        import numpy as np

        sample = torchsym.data.sample_path("chair.ply")
        (tmp_path / "a").mkdir()
        (tmp_path / "b").mkdir()
        shutil.copy(sample, tmp_path / "a" / "chair.ply")
        shutil.copy(sample, tmp_path / "b" / "chair.ply")
        np.savetxt(tmp_path / "a" / "chair.xyz", torchsym.data.sample_pointcloud().numpy())
        out = tmp_path / "out"
        assert main(["detect", str(tmp_path / "a"), str(tmp_path / "b"), "--out", str(out), "-q", "--no-figures"]) == 0
        names = sorted(q.name for q in out.iterdir() if not q.name.startswith("."))
        assert names == ["chair_ply.json", "chair_ply_2.json", "chair_xyz.json"]
        inputs = {json.loads((out / n).read_text())["input"] for n in names}
        assert len(inputs) == 3

    def test_unique_stems(self):
        from pathlib import Path

        from torchsym.io.inputs import unique_stems

        names = ["a/chair.xyz", "a/chair.npy", "b/chair.xyz", "a/chair_xyz.txt", "a/chair_xyz_2.pts", "a/table.ply"]
        stems = unique_stems([Path(n) for n in names])
        assert len(set(stems)) == len(stems) and stems[-1] == "table" and stems[3:5] == ["chair_xyz", "chair_xyz_2"]


def _small_cloud(path, n=300):
    pts = torchsym.data.sample_pointcloud()[:: 4000 // n].numpy()
    import numpy as np

    np.savetxt(path, pts)
    return path


def _one_error_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("torchsym: error: "), err
    assert "Traceback" not in err
    return lines[0]


class TestCLIFiles:
    def test_config_is_never_overwritten(self, tmp_path, capsys):
        scan = _small_cloud(tmp_path / "scan.xyz")
        cfg = tmp_path / "scan.json"
        cfg.write_text(json.dumps({"input": "pointcloud", "steps": [{"name": "reflection_plane"}]}))
        before = cfg.read_bytes()
        code = main(["detect", str(scan), "--config", str(cfg), "--out", str(tmp_path), "-q", "--no-figures"])
        line = _one_error_line(capsys.readouterr().err)
        assert code == 1 and "would overwrite the input" in line and "scan.json" in line
        assert cfg.read_bytes() == before

    @pytest.mark.slow
    def test_second_run_over_its_own_outputs(self, tmp_path, capsys):
        _small_cloud(tmp_path / "scan.xyz")
        for _ in range(2):
            assert main(["detect", str(tmp_path), "--out", str(tmp_path), "-q"]) == 0
            out = capsys.readouterr().out
            assert out.startswith("scan: ") and "scan_plane" not in out.split("\n")[0]  # one input, read alone
        manifest = json.loads((tmp_path / ".torchsym-outputs.json").read_text())
        assert "scan.json" in manifest["outputs"] and "scan_plane.ply" in manifest["outputs"]
        assert json.loads((tmp_path / "scan.json").read_text())["result"]["type"] == "ReflectionPlaneResult"

    def test_empty_out_refused(self, tmp_path, capsys, monkeypatch):
        monkeypatch.chdir(tmp_path)
        scan = _small_cloud(tmp_path / "scan.xyz")
        assert main(["detect", str(scan), "--out", "", "-q"]) == 2
        assert "--out: expected a folder" in _one_error_line(capsys.readouterr().err)
        assert sorted(q.name for q in tmp_path.iterdir()) == ["scan.xyz"]

    def test_empty_input_refused(self, capsys):
        assert main(["detect", "", "-q"]) == 2
        assert "inputs: expected a file, folder or glob pattern" in _one_error_line(capsys.readouterr().err)

    @pytest.mark.parametrize("value", [
        "!!python/object/apply:os.system [echo hi]",  # ConstructorError
        "[1, 2",  # ParserError
        "{a: 1}\n--- b",  # ComposerError (two documents)
        "&a [1, *a]",  # an alias
        "[[[[[[[[[[1]]]]]]]]]]",  # nested past 8
    ])
    def test_set_bad_yaml(self, tmp_path, capsys, value):
        scan = _small_cloud(tmp_path / "scan.xyz")
        assert main(["detect", str(scan), "--out", str(tmp_path / "o"), "--set", f"n_starts={value}"]) == 2
        line = _one_error_line(capsys.readouterr().err)
        assert "--set: n_starts=" in line
        assert not (tmp_path / "o" / "scan.json").exists()

    def test_symlink_loop(self, tmp_path, capsys):
        loop = tmp_path / "loop.xyz"
        loop.symlink_to(loop)
        assert main(["detect", str(loop), "--out", str(tmp_path / "o"), "-q"]) == 2
        line = _one_error_line(capsys.readouterr().err)
        assert "loop.xyz" in line and "symbolic link" in line

    def test_folder_run_goes_on_past_a_bad_file(self, tmp_path, capsys):
        d = tmp_path / "d"
        d.mkdir()
        (d / "a_empty.npy").write_bytes(b"")
        _small_cloud(d / "b.xyz")
        assert main(["detect", str(d), "--out", str(tmp_path / "o"), "-q", "--no-figures"]) == 1
        err = capsys.readouterr().err
        assert "a_empty.npy" in err and "cannot read" in err and "1 of 2 inputs failed" in err
        assert json.loads((tmp_path / "o" / "b.json").read_text())["result"]["type"] == "ReflectionPlaneResult"

    @pytest.mark.slow
    @pytest.mark.parametrize("argv", [["detect", "missing.xyz"], ["detect"], ["detect", "x.xyz", "--kind", "bogus"], ["nope"]])
    def test_errors_are_one_line(self, tmp_path, argv):
        env = {**os.environ, "PYTHONPATH": str(Path(torchsym.__file__).parents[1])}
        out = subprocess.run([sys.executable, "-m", "torchsym", *argv], capture_output=True, text=True, cwd=tmp_path, env=env)
        assert out.returncode == 2
        _one_error_line(out.stderr)
        assert not [q for q in tmp_path.iterdir() if q.name != "torchsym-out"]


class TestInputsAsUsersHaveThem:
    @pytest.mark.slow
    def test_cad_mesh_gets_its_plane_with_no_flags(self, tmp_path, capsys):
        import math

        import torch
        from cad_models import cad_chair, write_obj

        from torchsym.geometry import plane_angle

        mesh, normal, _ = cad_chair()
        path = write_obj(tmp_path / "model.obj", mesh)
        assert main(["detect", str(path), "--out", str(tmp_path / "o"), "-q"]) == 0
        err = capsys.readouterr().err
        assert "the intrinsic (mesh) pipeline cannot take this mesh" in err and "non-manifold" in err
        record = json.loads((tmp_path / "o" / "model.json").read_text())
        assert record["result"]["type"] == "ReflectionPlaneResult" and record["config"]["surface"]["points"] == 20000
        angle = float(plane_angle(torch.tensor(record["result"]["normal"], dtype=torch.float64), normal)) * 180 / math.pi
        assert angle < 1.0
        # --kind still forces either: the intrinsic pipeline refuses the non-manifold edge
        assert main(["detect", str(path), "--out", str(tmp_path / "m"), "-q", "--kind", "mesh"]) == 1
        assert "non-manifold edges" in capsys.readouterr().err

    def test_surface_not_vertices(self, tmp_path):
        # a mesh given to a point pipeline is sampled on its surface, area-weighted, seeded
        from cad_models import cad_chair

        from torchsym.api import prepare

        mesh, _, _ = cad_chair()
        cfg = torchsym.data.sample_path("chair.ply").parents[2] / "configs" / "pointcloud_plane.yaml"
        a = prepare(mesh, cfg, overrides={"surface.points": 3000})
        assert a.kind == "pointcloud" and a.data.shape == (3000, 3) and "sampled 3000 points" in a.notes[0]
        assert torch_equal(a.data, prepare(mesh, cfg, overrides={"surface.points": 3000}).data)
        assert not torch_equal(a.data, prepare(mesh, cfg, overrides={"surface.points": 3000, "surface.seed": 1}).data)

    @pytest.mark.slow
    def test_multiview_folder_reproduces_the_function(self, tmp_path, capsys):
        from test_contract import _scene_folder

        from torchsym.multiview import detect_multiview_plane

        cfg = torchsym.data.sample_path("chair.ply").parents[2] / "configs" / "multiview_plane.yaml"
        scenes = tmp_path / "scenes"
        _scene_folder(scenes / "a", seed=2)
        _scene_folder(scenes / "b", seed=3)
        expected = {name: detect_multiview_plane(scenes / name) for name in ("a", "b")}
        # torchsym detect FOLDER: one input, K.txt skipped with a note
        for _ in range(2):  # a second run replaces the first's outputs (the COLMAP model is a folder)
            assert main(["detect", str(scenes / "a"), "--config", str(cfg), "--out", str(tmp_path / "o"), "-q"]) == 0
            assert "K.txt" in capsys.readouterr().err
        assert (tmp_path / "o" / "a_colmap").is_dir() and not list((tmp_path / "o").glob(".torchsym-staging-*"))
        record = json.loads((tmp_path / "o" / "a.json").read_text())
        assert record["result"]["normal"] == expected["a"].normal.tolist()
        # the API with a list of paths and kind="multiview"
        photos = sorted(str(p) for p in (scenes / "a").glob("*.png"))
        assert torchsym.detect(photos, kind="multiview").normal.tolist() == expected["a"].normal.tolist()
        assert torchsym.detect(scenes / "a").normal.tolist() == expected["a"].normal.tolist()  # a folder: one scene
        # torchsym run over a folder of scenes: one record per scene
        out = tmp_path / "r.jsonl"
        assert main(["run", str(cfg), "--inputs", str(scenes), "--out", str(out), "--engine", "serial", "-q"]) == 0
        records = {Path(r["input"]).name: r for r in torchsym.read_results(out)}
        assert sorted(records) == ["a", "b"]
        for name in ("a", "b"):
            assert records[name]["result"]["normal"] == expected[name].normal.tolist()


def torch_equal(a, b) -> bool:
    import torch

    return bool(torch.equal(a, b))
