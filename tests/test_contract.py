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
        for name in ("score",):
            if hasattr(r, name):
                s = float(getattr(r, name))
                assert 0.0 <= s <= 1.0 and not math.isnan(s)

    def test_to_round_trips(self, entry):
        r = _run(entry, _input(entry.kind))
        assert _equal(r.to("cpu"), r)

    def test_bad_input_is_typed(self, entry):
        with pytest.raises(TorchsymError):
            entry.cls()(_BAD[entry.kind])
