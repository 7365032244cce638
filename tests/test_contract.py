"""The contract every registered solver keeps, checked over the whole registry.

Same seed, same bits; ``to_dict()`` is strict JSON; bad input raises a typed error naming
the argument; ``.to()`` round-trips; the function and the module share one settings
class; every setting is reachable from YAML; scores lie in [0, 1].
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

import torchsym
from torchsym.core.config import build_pipeline
from torchsym.core.settings import Settings, Solver
from torchsym.errors import TorchsymError


def _mesh() -> torchsym.mesh.Mesh:
    """A sphere pushed out by two bumps at mirror positions: symmetric about x = 0 only."""
    from torchsym.mesh.synthetic import icosphere

    s = icosphere(3)
    v = s.vertices.numpy()
    bump = sum(np.exp(-((v - c) ** 2).sum(1) / 0.05) for c in ([0.5, 0.6, 0.62], [-0.5, 0.6, 0.62]))
    w = v * (1 + 0.5 * v[:, 1:2] ** 2 + 0.2 * v[:, 2:3] + 0.7 * bump[:, None])
    return torchsym.mesh.Mesh(torch.from_numpy(w), s.faces)


def _image() -> torch.Tensor:
    from torchsym.image.synthetic import mirrored_objects_image

    image, _ = mirrored_objects_image(1, height=160, width=200, generator=torch.Generator().manual_seed(3))
    return image


def _input(kind: str):
    if kind == "pointcloud":
        return torchsym.data.sample_pointcloud()[::4].contiguous()
    if kind == "points":
        from torchsym.pointset.synthetic import make_symmetric_pointset

        return make_symmetric_pointset(60, 4, generator=torch.Generator().manual_seed(1)).points
    if kind == "image":
        return _image()
    if kind == "mesh":
        return _mesh()
    if kind == "multiview":
        from torchsym.multiview.synthetic import symmetric_scene

        return symmetric_scene(6, height=360, width=480, generator=torch.Generator().manual_seed(2)).images
    return None


_BAD = {
    "pointcloud": torch.zeros(5),
    "points": torch.zeros(5),
    "image": torch.zeros(7),
    "mesh": torch.zeros(3, 3),
    "multiview": torch.zeros(5),
}

ENTRIES = [e for e in torchsym.SOLVERS if e.kind != "any"]
CACHE: dict[str, object] = {}


def _run(entry, data):
    key = entry.name
    if key not in CACHE:
        CACHE[key] = entry.cls()(data)
    return CACHE[key]


def _leaves(value):
    if isinstance(value, torch.Tensor):
        yield value
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            yield from _leaves(getattr(value, f.name))
    elif isinstance(value, (list, tuple)):
        for v in value:
            yield from _leaves(v)
    elif isinstance(value, dict):
        for v in value.values():
            yield from _leaves(v)


def _without_timings(d):
    """The result's dict without ``timings``, ``seconds`` and ``stage_seconds`` (wall-clock seconds, the one field that
    differs from run to run)."""
    if isinstance(d, dict):
        return {k: _without_timings(v) for k, v in d.items() if k not in ("timings", "seconds", "stage_seconds")}
    if isinstance(d, list):
        return [_without_timings(v) for v in d]
    return d


def _equal(a, b) -> bool:
    da, db = _without_timings(a.to_dict()), _without_timings(b.to_dict())
    return json.dumps(da, sort_keys=True) == json.dumps(db, sort_keys=True)


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda e: e.name)
class TestSolverContract:
    def test_is_a_solver_with_settings(self, entry):
        assert issubclass(entry.cls, Solver), f"{entry.name}: not a torchsym.core.settings.Solver"
        assert issubclass(entry.settings_class, Settings) and entry.settings_class is not Settings
        # the module holds the settings and calls the function: no own __init__
        assert "__init__" not in vars(entry.cls), f"{entry.name}: the module defines its own __init__"

    def test_function_takes_the_same_settings(self, entry):
        module = sys.modules[entry.cls.__module__]
        package = sys.modules[entry.cls.__module__.rsplit(".", 1)[0]]
        found = []
        for mod in {module, package}:
            for name, fn in vars(mod).items():
                if not inspect.isfunction(fn) or name.startswith("_"):
                    continue
                params = inspect.signature(fn).parameters
                ann = str(params["settings"].annotation) if "settings" in params else ""
                if entry.settings_class.__name__ in ann:
                    found.append((name, params))
        assert found, f"{entry.name}: no public function takes settings: {entry.settings_class.__name__}"
        for name, params in found:
            names = {row[0].split(".")[0] for row in entry.settings_class.describe()}
            extra = [p for p in params.values() if p.name in names and p.default is not p.empty]
            assert not extra, f"{name} lists settings of its own: {[p.name for p in extra]}"

    def test_every_setting_reachable_from_yaml(self, entry):
        kind = entry.kind
        for name, *_ in entry.settings_class.describe():
            default = entry.settings_class()
            value = default
            for part in name.split("."):
                value = getattr(value, part)
            params: dict = {}
            cur = params
            parts = name.split(".")
            for part in parts[:-1]:
                cur = cur.setdefault(part, {})
            cur[parts[-1]] = list(value) if isinstance(value, tuple) else value
            pipe = build_pipeline({"input": kind, "steps": [{"name": entry.name, "params": params}]})
            assert pipe.steps[0].settings == default

    def test_typo_names_valid_keys(self, entry):
        with pytest.raises(torchsym.ConfigError, match="valid:"):
            build_pipeline({"input": entry.kind, "steps": [{"name": entry.name, "params": {"no_such_setting": 1}}]})

    def test_same_seed_same_bits(self, entry):
        data = _input(entry.kind)
        a = _run(entry, data)
        b = entry.cls()(data)
        assert _equal(a, b)

    def test_to_dict_is_strict_json(self, entry):
        d = _run(entry, _input(entry.kind)).to_dict()
        json.dumps(d, allow_nan=False)

    def test_fields_finite_and_score_bounded(self, entry):
        r = _run(entry, _input(entry.kind))
        for t in _leaves(r):
            if t.is_floating_point():
                assert bool(torch.isfinite(t).all())
        s = float(r.score)  # every solver's result has one
        assert 0.0 <= s <= 1.0 and not math.isnan(s)
        assert r.to_dict()["score"] == pytest.approx(s)

    def test_summary_is_one_line(self, entry):
        line = _run(entry, _input(entry.kind)).summary()
        assert line.startswith(type(_run(entry, _input(entry.kind))).__name__ + ": ") and "\n" not in line

    def test_saved_json_loads_back_typed(self, entry, tmp_path):
        r = _run(entry, _input(entry.kind))
        r.to_json(tmp_path / "r.json")
        required = [f.name for f in dataclasses.fields(r)
                    if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
        if not all(name in r.to_dict() for name in required):
            with pytest.raises(torchsym.InputValueError, match="needs field"):  # a summary, not every field
                torchsym.load_result(tmp_path / "r.json")
            return
        back = torchsym.load_result(tmp_path / "r.json")
        assert type(back) is type(r)
        _close(back.to_dict(), json.loads((tmp_path / "r.json").read_text()))  # floats come back as float32


def _close(a, b, where="result"):
    """``a`` and ``b`` equal in structure, numbers to float32 precision."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), where
        for k in a:
            _close(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _close(x, y, f"{where}[{i}]")
    elif isinstance(a, float) and isinstance(b, (int, float)):
        assert a == pytest.approx(b, rel=1e-6, abs=1e-6), where
    else:
        assert a == b, where

    def test_to_round_trips(self, entry):
        r = _run(entry, _input(entry.kind))
        assert _equal(r.to("cpu"), r)

    def test_bad_input_is_typed(self, entry):
        with pytest.raises(TorchsymError):
            entry.cls()(_BAD[entry.kind])


# --- the front door: every shipped config through torchsym.detect, the CLI and torchsym run ---

CONFIGS = sorted((Path(torchsym.__file__).parents[1] / "configs").glob("*.yaml"))


def _scene_folder(folder: Path, seed: int = 2) -> Path:
    """Five photos of the synthetic symmetric scene as PNG files, and a ``K.txt`` beside
    them (not a photo: skipped with a note)."""
    import cv2

    from torchsym.multiview.synthetic import symmetric_scene

    folder.mkdir(parents=True)
    scene = symmetric_scene(5, height=240, width=320, generator=torch.Generator().manual_seed(seed))
    for i, img in enumerate(scene.images):
        rgb = (img.permute(1, 2, 0).numpy() * 255).round().astype(np.uint8)
        cv2.imwrite(str(folder / f"view_{i}.png"), rgb[:, :, ::-1])
    np.savetxt(folder / "K.txt", scene.intrinsics.numpy())
    return folder


def _input_file(kind: str, folder: Path) -> Path:
    """A small input of ``kind`` as users have it: a file, or a folder of photos."""
    from cad_models import cad_chair, write_obj

    from torchsym.io import write_image, write_mesh

    if kind == "pointcloud":  # a CAD model: several parts, a non-manifold edge
        return write_obj(folder / "chair.obj", cad_chair()[0])
    if kind == "points":
        path = folder / "pointset.npy"
        np.save(path, _input("points").numpy())
        return path
    if kind == "image":
        return write_image(folder / "photo.png", _image())
    if kind == "mesh":
        return write_mesh(folder / "bumps.off", _mesh())
    if kind == "multiview":
        return _scene_folder(folder / "scene")
    raise AssertionError(kind)


#: settings that only shrink the input (the CAD model's surface sample), never the method
SHRINK = {"pointcloud": ["surface.points=4000"], "points": []}


def _result(d):
    return json.dumps(_without_timings(d), sort_keys=True)


@pytest.mark.slow
@pytest.mark.parametrize("config", CONFIGS, ids=lambda p: p.stem)
def test_config_runs_through_every_front_door(config, tmp_path):
    from torchsym.cli import main
    from torchsym.core.config import load_config, parse_overrides

    kind = load_config(config).input
    path = _input_file(kind, tmp_path)
    sets = SHRINK.get(kind, [])
    try:
        api = torchsym.detect(path, config, **parse_overrides(sets))
    except AttributeError as exc:  # an OpenCV build without the contrib modules shadows opencv-contrib
        if "createEdgeDrawing" not in str(exc):
            raise
        pytest.skip(f"this OpenCV lacks the contrib module EdgeDrawing ({exc})")
    # the CLI: <stem>.json and a picture
    out = tmp_path / "cli"
    assert main(["detect", str(path), "--config", str(config), "--out", str(out), "-q", *[a for s in sets for a in ("--set", s)]]) == 0
    record = json.loads((out / f"{Path(path).stem}.json").read_text())
    assert record["result"]["type"] == type(api).__name__ and record["artifacts"]
    assert all(Path(a).exists() for a in record["artifacts"])
    # torchsym run: a results file and the pictures
    run_out = tmp_path / "run.jsonl"
    summary = torchsym.run(config, [str(path)], run_out, engine="serial", overrides=parse_overrides(sets),
                           figures=tmp_path / "figs", max_inline=None)
    assert (summary.n_inputs, summary.n_ok) == (1, 1)
    (rec,) = torchsym.read_results(run_out)
    assert rec["artifacts"] and all(Path(a).exists() for a in rec["artifacts"])
    # one path: the same result from each door
    assert _result(record["result"]) == _result(api.to_dict()) == _result(rec["result"])
    if kind == "multiview":
        assert any("K.txt" in n for n in record["notes"])
    if kind == "pointcloud":
        assert any("sampled 4000 points" in n for n in record["notes"])
