import json
import subprocess
import sys

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
        assert main(["detect", str(bad), "--out", str(tmp_path)]) == 2
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
        assert not [q for q in tmp_path.iterdir() if q.name.startswith(".")]  # staging folders removed

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
        names = sorted(q.name for q in out.iterdir())
        assert names == ["chair_ply.json", "chair_ply_2.json", "chair_xyz.json"]
        inputs = {json.loads((out / n).read_text())["input"] for n in names}
        assert len(inputs) == 3

    def test_unique_stems(self):
        from pathlib import Path

        from torchsym.cli import _unique_stems

        names = ["a/chair.xyz", "a/chair.npy", "b/chair.xyz", "a/chair_xyz.txt", "a/chair_xyz_2.pts", "a/table.ply"]
        stems = _unique_stems([Path(n) for n in names])
        assert len(set(stems)) == len(stems) and stems[-1] == "table" and stems[3:5] == ["chair_xyz", "chair_xyz_2"]
