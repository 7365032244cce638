import json

import numpy as np

import torchsym
from torchsym.cli import main


class TestRunCommand:
    def test_run_then_evaluate(self, tmp_path, capsys):
        truth = []
        for i in range(2):
            cloud = torchsym.pointcloud.planted_symmetric_cloud(300, generator=i)
            np.savetxt(tmp_path / f"p{i}.xyz", cloud.points.numpy())
            truth.append({"input": f"p{i}.xyz", "normal": cloud.normal.tolist(), "offset": float(cloud.offset)})
        (tmp_path / "truth.jsonl").write_text("\n".join(json.dumps(t) for t in truth))
        cfg = torchsym.data.sample_path("chair.ply").parents[2] / "configs" / "pointcloud_plane.yaml"
        out = tmp_path / "r.jsonl"
        args = ["run", str(cfg), "--inputs", str(tmp_path / "p*.xyz"), "--out", str(out), "--engine", "serial",
                "--set", "n_starts=2", "--set", "polish.n_queries=300", "-q"]
        assert main(args) == 0
        assert "2 inputs, 0 already done; ran 2 on the serial engine: 2 ok" in capsys.readouterr().out
        assert main(args) == 0  # resumed: nothing left
        assert "2 already done; ran 0" in capsys.readouterr().out
        assert main(["evaluate", str(out), "--truth", str(tmp_path / "truth.jsonl"), "--json", str(tmp_path / "ev.json")]) == 0
        text = capsys.readouterr().out
        assert "pointcloud: 2 inputs scored" in text and "| plane |" in text
        ev = json.loads((tmp_path / "ev.json").read_text())
        assert ev["figures"]["plane"]["f"] == 1.0 and len(ev["items"]) == 2
        assert isinstance(json.loads(out.read_text().splitlines()[0])["result"]["pairs"], list)  # 600 <= 1024
        apart = tmp_path / "apart.jsonl"
        assert main([*args[:5], str(apart), *args[6:], "--max-inline", "64"]) == 0
        assert "$array" in json.loads(apart.read_text().splitlines()[0])["result"]["pairs"]

    def test_bad_input(self, tmp_path, capsys):
        cfg = torchsym.data.sample_path("chair.ply").parents[2] / "configs" / "image_ksymmetry.yaml"
        assert main(["run", str(cfg), "--inputs", str(tmp_path / "*.jpg"), "--out", str(tmp_path / "r.jsonl")]) == 2
        err = capsys.readouterr().err
        assert err.startswith("torchsym: error: inputs: ") and "matches no file" in err
        assert main(["evaluate", str(tmp_path / "r.jsonl"), "--truth", str(tmp_path / "t.txt")]) == 2
        assert "torchsym: error: results: file" in capsys.readouterr().err
