"""evaluate on small runs whose figures are worked out by hand (in the comments)."""

import json
import math

import pytest

from torchsym.errors import InputFileError, InputValueError
from torchsym.runner import evaluate, format_evaluation, read_truth
from torchsym.runner.store import ResultsStore


def _write(path, records):
    with ResultsStore(path, resume=False) as store:
        for rec in records:
            store.append({"size": 0, "mtime_ns": 0, "config_hash": "h", "error": None, **rec})
    return path


def _plane(name, normal, offset, score):
    return {"input": f"/data/{name}", "status": "ok", "result": {"type": "ReflectionPlaneResult", "normal": normal, "offset": offset, "score": score}}


class TestPlanes:
    def test_value(self, tmp_path):
        c3, s3 = math.cos(math.radians(3)), math.sin(math.radians(3))
        results = _write(tmp_path / "r.jsonl", [
            _plane("a.ply", [1, 0, 0], 0.0, 0.9),  # exact: correct
            _plane("b.ply", [0, c3, s3], 0.0, 0.8),  # 3 deg off, through the centre: correct
            _plane("c.ply", [0, 0, 1], -0.5, 0.7),  # parallel, 0.5 / (2 sqrt 3) = 0.144 of the diagonal away: wrong
            {"input": "/data/d.ply", "status": "crashed", "result": None},  # missed
            _plane("e.ply", [1, 0, 0], 0.0, 0.5),  # no ground truth: left out
        ])
        box = {"box_min": [-1, -1, -1], "box_max": [1, 1, 1]}
        truth = tmp_path / "planes.jsonl"
        truth.write_text("\n".join(json.dumps({"input": n, "normal": v, "offset": 0.0, **box})
                                   for n, v in [("a.ply", [1, 0, 0]), ("b.ply", [0, 1, 0]), ("c", [0, 0, 1]), ("d.ply", [1, 0, 0])]))
        ev = evaluate(results, truth)
        assert (ev.kind, ev.n_records, ev.n_scored, ev.n_failed, ev.n_no_truth) == ("pointcloud", 5, 4, 1, 1)
        plane = ev.figures["plane"]
        # 2 correct of 3 detections, 4 planes: P = 2/3, R = 1/2, F = 4/7
        assert plane["precision"] == pytest.approx(2 / 3) and plane["recall"] == pytest.approx(0.5)
        assert plane["f"] == pytest.approx(4 / 7)
        # PR over scores 0.9 (T), 0.8 (T), 0.7 (F): best at 0.8, P = 1, R = 1/2, F = 2/3
        assert plane["max_f"] == pytest.approx(2 / 3)
        rows = {r["input"].split("/")[-1]: r for r in ev.items}
        assert rows["b.ply"]["angle_deg"] == pytest.approx(3.0) and rows["b.ply"]["correct"]
        assert rows["c.ply"]["distance"] == pytest.approx(0.5 / (2 * math.sqrt(3))) and not rows["c.ply"]["correct"]
        assert rows["d.ply"]["status"] == "crashed" and rows["d.ply"]["angle_deg"] is None
        text = format_evaluation(ev)
        assert "| plane |" in text and "0.571" in text
        json.dumps(ev.to_dict())


def _axes(name, axes, scores):
    return {"input": f"/photos/{name}", "status": "ok",
            "result": {"type": "ReflectionAxesResult", "axes": axes, "scores": scores, "image_size": [100, 100]}}


class TestAxes:
    def test_value(self, tmp_path):
        results = _write(tmp_path / "r.jsonl", [
            _axes("i1.png", [[50, 0, 50, 100], [0, 50, 100, 50]], [5.0, 3.0]),  # right, then wrong
            _axes("i2.png", [[12, 0, 12, 100]], [4.0]),  # 2 px off: right under both criteria
            _axes("i3.png", [[40, 0, 40, 100]], [2.0]),  # 10 px off: thesis 2.5 px no, challenge 20 px yes
        ])
        truth = tmp_path / "axes.txt"
        truth.write_text("# image x1 y1 x2 y2\ni1.png 50 0 50 100\ni2.png 10 0 10 100\ni2.png 0 20 100 20\ni3.png 30 0 30 100\n")
        ev = evaluate(results, truth)
        assert (ev.kind, ev.n_scored) == ("image", 3)
        thesis, challenge = ev.figures["thesis"], ev.figures["challenge"]
        # thesis: 2 of 4 detections right, 4 axes: P = R = F = 1/2; best threshold 4: P = 1, R = 1/2
        assert (thesis["precision"], thesis["recall"], thesis["f"]) == pytest.approx((0.5, 0.5, 0.5))
        assert thesis["max_f"] == pytest.approx(2 / 3)
        # challenge: 3 of 4 right: P = R = F = 3/4, the best at the lowest threshold
        assert (challenge["precision"], challenge["recall"], challenge["max_f"]) == pytest.approx((0.75, 0.75, 0.75))
        rows = {r["input"].split("/")[-1]: r for r in ev.items}
        assert rows["i1.png"]["top_correct_thesis"] and rows["i1.png"]["correct_thesis"] == 1
        assert not rows["i3.png"]["top_correct_thesis"] and rows["i3.png"]["top_correct_challenge"]
        assert rows["i2.png"]["n_truth"] == 2

    def test_shared_axes_txt(self, shared_data):
        gt = read_truth(shared_data / "images" / "reflection_single_dev" / "axes.txt")
        assert gt.kind == "image" and len(gt.items) == 32
        assert gt.find("/anywhere/refs_003.jpg").tolist() == [[80.0, 32.0, 80.0, 145.0]]


def _grid_off(path):
    """A flat 5 x 5 grid, x in -2..2, y in 0..4 (area 16), vertex r * 5 + c at (c - 2, r)."""
    verts = [(c - 2, r, 0) for r in range(5) for c in range(5)]
    faces = []
    for r in range(4):
        for c in range(4):
            v = r * 5 + c
            faces += [(v, v + 1, v + 6), (v, v + 6, v + 5)]
    path.write_text("OFF\n" + f"{len(verts)} {len(faces)} 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in verts)
                    + "".join(f"3 {a} {b} {c}\n" for a, b, c in faces))
    return path


class TestMeshes:
    def test_value(self, tmp_path):
        mirror = [r * 5 + 4 - c for r in range(5) for c in range(5)]
        results = _write(tmp_path / "r.jsonl", [
            {"input": str(_grid_off(tmp_path / "m1.off")), "status": "ok", "result": {"type": "IntrinsicSymmetryResult", "map": mirror}},
            {"input": str(_grid_off(tmp_path / "m2.off")), "status": "ok", "result": {"type": "IntrinsicSymmetryResult", "map": list(range(25))}},
            {"input": str(tmp_path / "m3.off"), "status": "error", "result": None},
        ])
        corres = tmp_path / "truth" / "corres"
        corres.mkdir(parents=True)
        for name in ("m1", "m2", "m3"):  # row 2: (10, 14), (11, 13), (12, 12), 1-based
            (corres / f"{name}.vts").write_text("11\n12\n13\n")
            (corres / f"{name}.sym.vts").write_text("15\n14\n13\n")
        ev = evaluate(results, tmp_path / "truth")
        rows = {r["input"].split("/")[-1]: r for r in ev.items}
        # tolerance sqrt(16 / (20 pi)) = 0.505: the mirror map is exact; the identity map
        # is 4, 2 and 0 away from the truth: 1 of 3; the failed mesh counts 0
        assert rows["m1.off"]["rate"] == 1.0 and rows["m2.off"]["rate"] == pytest.approx(1 / 3)
        assert rows["m1.off"]["threshold"] == pytest.approx(math.sqrt(16 / (20 * math.pi)))
        assert rows["m3.off"]["rate"] == 0.0
        assert ev.figures["mesh"]["mesh_rate"] == pytest.approx(1 / 3)  # only m1 above 75 %
        assert ev.figures["mesh"]["mean_rate"] == pytest.approx(4 / 9)


def _bsds_mat(path, segmentations):
    """A BSDS500 groundTruth file: a 1 x N cell of structs with ``Segmentation``."""
    import numpy as np
    import scipy.io

    cell = np.empty((1, len(segmentations)), dtype=object)
    for i, seg in enumerate(segmentations):
        struct = np.empty((1, 1), dtype=[("Segmentation", object), ("Boundaries", object)])
        struct[0, 0] = (np.asarray(seg, dtype=np.uint16), np.zeros_like(seg, dtype=np.uint8))
        cell[0, i] = struct
    scipy.io.savemat(str(path), {"groundTruth": cell})


class TestSuperpixels:
    def test_value(self, tmp_path):
        import numpy as np

        cols = np.tile(np.array([0, 0, 1, 1]), (4, 1))  # two superpixels: left and right halves
        rows_ = cols.T.copy()  # top and bottom halves
        truth = tmp_path / "gt"
        truth.mkdir()
        _bsds_mat(truth / "a.mat", [cols + 1, rows_ + 1])  # BSDS labels start at 1
        _bsds_mat(truth / "b.mat", [cols + 1])
        results = _write(tmp_path / "r.jsonl", [
            {"input": "/p/a.jpg", "status": "ok", "result": {"type": "SymmSlicResult", "labels": cols.tolist()}},
            {"input": "/p/b.jpg", "status": "error", "result": None},
        ])
        ev = evaluate(results, truth)
        assert (ev.kind, ev.n_scored, ev.n_failed) == ("superpixels", 2, 1)
        a, b = ev.items
        # against the halves it matches: ASA 1, USE 0; against top/bottom each superpixel
        # keeps 4 of its 8 pixels in one segment (ASA 1/2) and leaks min(4, 4) into each of
        # the two segments it crosses (USE (4 * 4) / 16 = 1)
        assert a["asa_best"] == 1.0 and a["asa_mean"] == pytest.approx(0.75)
        assert a["use_best"] == 0.0 and a["use_mean"] == pytest.approx(0.5)
        assert a["br_best"] == 1.0 and a["n_superpixels"] == 2
        assert b["asa_mean"] == 0.0 and b["use_mean"] == 1.0  # failed: the worst values
        assert ev.figures["superpixels"]["asa_mean"] == pytest.approx(0.375)

    def test_record_without_labels(self, tmp_path):
        truth = tmp_path / "gt"
        truth.mkdir()
        _bsds_mat(truth / "a.mat", [[[1, 2]]])
        results = _write(tmp_path / "r.jsonl", [_axes("a.jpg", [[0, 0, 1, 1]], [1.0])])
        # scored by its type: axes are no superpixels
        with pytest.raises(InputValueError, match="is superpixels ground truth, which scores SymmSlicResult; the run's results are ReflectionAxesResult"):
            evaluate(results, truth)
        no_labels = _write(tmp_path / "s.jsonl", [{"input": "/p/a.jpg", "status": "ok", "result": {"type": "SymmSlicResult"}}])
        with pytest.raises(InputValueError, match="has no 'labels' array to score"):
            evaluate(no_labels, truth)


class TestSegmentation:
    def test_value(self, tmp_path):
        import cv2
        import numpy as np

        gt = np.zeros((4, 5), np.uint8)
        gt[:, :2] = 255  # the object: the two left columns
        gt[:, 2] = 128  # GrabCut's unlabelled band
        truth = tmp_path / "masks"
        truth.mkdir()
        cv2.imwrite(str(truth / "a.png"), gt)
        cv2.imwrite(str(truth / "b.bmp"), gt)
        mask = np.zeros((4, 5), bool)
        mask[:, :3] = True  # the band is not counted
        mask[0, 4] = True  # one pixel wrong
        results = _write(tmp_path / "r.jsonl", [
            {"input": "/p/a.jpg", "status": "ok", "result": {"type": "SymmSlicResult", "mask": mask.tolist()}},
            {"input": "/p/b.jpg", "status": "crashed", "result": None},
        ])
        ev = evaluate(results, truth)
        a, b = ev.items
        # 16 counted pixels, the box the object's 8 of them (band excluded): 1/16 and 1/8;
        # the crash finds nothing: 8 wrong
        assert (ev.kind, a["over_image"], a["over_box"]) == ("segmentation", 1 / 16, 1 / 8)
        assert (b["over_image"], b["over_box"]) == (0.5, 1.0)
        assert ev.figures["segmentation"]["over_image"] == pytest.approx((1 / 16 + 0.5) / 2)


class TestSymmetryMap:
    def test_value(self, tmp_path):
        import cv2
        import numpy as np

        gt = np.zeros((8, 8), np.uint8)
        gt[2:6, 2:6] = 255
        truth = tmp_path / "segmentations"
        truth.mkdir()
        cv2.imwrite(str(truth / "a_seg0.png"), gt)  # matched to a.png by its stem and a suffix
        cv2.imwrite(str(truth / "b_seg0.png"), gt)
        half = (gt > 0).astype(np.float32)[::2, ::2]  # the map at half resolution
        results = _write(tmp_path / "r.jsonl", [
            {"input": "/p/a.png", "status": "ok", "result": {"type": "SymmetryMapResult", "score_map": half.tolist()}},
            {"input": "/p/b.png", "status": "error", "result": None},
        ])
        ev = evaluate(results, truth)
        a, b = ev.items
        assert (a["auc"], a["precision"], a["recall"]) == (1.0, 1.0, 1.0)
        assert b["recall"] == 0.0 and b["auc"] == 0.5  # a failed input: an all-zero map
        assert set(ev.figures) == {"ssm"} and ev.figures["ssm"]["recall"] == 0.5

    def test_score_map_in_the_sink(self):
        import torch

        from torchsym.core.results import ArraySink
        from torchsym.image.symmetry_map.result import SymmetryMapResult

        ssm = torch.rand(2, 40, 50, generator=torch.Generator().manual_seed(0))
        r = SymmetryMapResult(torch.zeros(2, 40, 50, 2), ssm, torch.zeros(2, 3), torch.zeros(0, 4),
                              torch.zeros(0, dtype=torch.int64), torch.zeros(3, 40, 50), 1.0, "irs", 1)
        sink = ArraySink()
        d = r.to_dict(sink)
        assert d["score_map"]["$array"] == "score_map" and (sink.arrays["score_map"] == ssm.max(0).values.numpy()).all()
        assert "score_map" not in r.to_dict()  # the CLI's summary


class TestPointSymmImage:
    def test_one_axis_segment(self, tmp_path):
        results = _write(tmp_path / "r.jsonl", [
            {"input": "/photos/a.png", "status": "ok",
             "result": {"type": "ImageAxisResult", "segment": [[50, 0], [50, 100]], "score": 0.7, "image_size": [100, 100]}},
        ])
        truth = tmp_path / "axes.txt"
        truth.write_text("a.png 50 0 50 100\n")
        ev = evaluate(results, truth)
        assert ev.items[0]["n_detections"] == 1 and ev.items[0]["correct_thesis"] == 1


class TestExceptions:
    def test_bad_truth(self, tmp_path):
        bad = tmp_path / "axes.txt"
        bad.write_text("i1.png 1 2 3\n")
        with pytest.raises(InputFileError, match=r"line 1 of .*axes\.txt.*expected 'image x1 y1 x2 y2'"):
            read_truth(bad)
        planes = tmp_path / "p.jsonl"
        planes.write_text('{"input": "a", "normal": [1, 0], "offset": 0}\n')
        with pytest.raises(InputFileError, match=r"line 1 of .*p\.jsonl.*expected 'normal' as a list of 3 numbers"):
            read_truth(planes)
        with pytest.raises(InputFileError, match="holds no NAME.vts"):
            read_truth(tmp_path)
        with pytest.raises(InputFileError, match="--truth: .*nothing.txt' does not exist"):
            read_truth(tmp_path / "nothing.txt")

    def test_no_matching_names(self, tmp_path):
        results = _write(tmp_path / "r.jsonl", [_plane("a.ply", [1, 0, 0], 0.0, 0.9)])
        truth = tmp_path / "planes.jsonl"
        truth.write_text(json.dumps({"input": "zzz.ply", "normal": [1, 0, 0], "offset": 0}) + "\n")
        with pytest.raises(InputValueError, match=r"no record of the run has ground truth .*'a\.ply'.*zzz\.ply"):
            evaluate(results, truth)


def test_detect_and_run_write_one_record_schema(tmp_path):
    """``torchsym detect``'s ``<stem>.json`` is a run's record: ``evaluate`` scores the folder."""
    import numpy as np

    import torchsym
    from torchsym.cli import main

    points = torchsym.data.sample_pointcloud().numpy()
    np.save(tmp_path / "chair.npy", points)
    n, d = torchsym.data.sample_plane()
    truth = tmp_path / "planes.jsonl"
    truth.write_text(json.dumps({"input": "chair.npy", "normal": n.tolist(), "offset": float(d),
                                 "box_min": points.min(0).tolist(), "box_max": points.max(0).tolist()}) + "\n")
    assert main(["detect", str(tmp_path / "chair.npy"), "--out", str(tmp_path / "o"), "--no-figures", "-q"]) == 0
    torchsym.run("pointcloud_plane", [str(tmp_path / "chair.npy")], tmp_path / "r.jsonl")
    detect_rec = json.loads((tmp_path / "o" / "chair.json").read_text())
    run_rec = torchsym.read_results(tmp_path / "r.jsonl")[0]
    assert set(detect_rec) == set(run_rec)
    assert evaluate(tmp_path / "o", truth).figures["plane"]["f"] == 1.0
    assert type(torchsym.load_result(tmp_path / "o" / "chair.json")).__name__ == "ReflectionPlaneResult"
