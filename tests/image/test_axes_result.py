"""Shared pieces: axis lines and segments, the result type, artifacts, registry and configs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch

import torchsym
from torchsym.image.axes import (
    ReflectionAxesResult,
    axis_segment,
    build_result,
    clip_line_to_image,
    pair_axes,
)
from torchsym.io import read_image

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


class TestPairAxes:
    def test_bisector(self):
        line = pair_axes(torch.tensor([[2.0, 5.0]]), torch.tensor([[8.0, 5.0]]))[0]
        assert torch.allclose(line, torch.tensor([-1.0, 0.0, 5.0]))  # x = 5


class TestSegments:
    def test_extent_of_support(self):
        line = torch.tensor([1.0, 0.0, -50.0], dtype=torch.float64)  # x = 50
        pts = torch.tensor([[40.0, 20.0], [60.0, 70.0]])
        x1, y1, x2, y2 = axis_segment(line, pts, 100, 100)
        assert (x1, x2) == (50.0, 50.0) and sorted([y1, y2]) == [20.0, 70.0]

    def test_clipped_to_image(self):
        line = torch.tensor([0.0, 1.0, -10.0], dtype=torch.float64)  # y = 10
        seg = clip_line_to_image(line, -1e9, 1e9, 64, 32)
        assert sorted([seg[0], seg[2]]) == [0.0, 63.0] and seg[1] == seg[3] == 10.0
        assert clip_line_to_image(torch.tensor([0.0, 1.0, -40.0]), -1e9, 1e9, 64, 32) is None


class TestResult:
    def _result(self):
        pairs = torch.tensor([[40.0, 20.0, 60.0, 20.0], [45.0, 70.0, 55.0, 70.0], [1.0, 1.0, 3.0, 3.0]])
        line = torch.tensor([1.0, 0.0, -50.0], dtype=torch.float64)
        return build_result([line], [torch.tensor([0, 1])], [2.0], pairs, 100, 120, "test")

    def test_fields_and_json(self):
        res = self._result()
        assert isinstance(res, ReflectionAxesResult)
        assert res.axes.shape == (1, 4) and res.pair_axis.tolist() == [0, 0, -1]
        d = json.loads(res.to_json())
        assert d["type"] == "ReflectionAxesResult" and d["method"] == "test" and len(d["axes"]) == 1

    def test_write_artifacts(self, tmp_path):
        res = self._result()
        paths = res.write_artifacts(torch.rand(3, 100, 120), tmp_path, "photo")
        assert [p.name for p in paths] == ["photo_axes.png"]
        drawn = read_image(paths[0])
        assert drawn.shape == (3, 100, 120)
        assert float(drawn[0, 50, 50]) > 0.9 and float(drawn[1, 50, 50]) < 0.1  # the best axis is red


class TestRegistryAndConfigs:
    def test_registered(self):
        names = torchsym.SOLVERS.names("image")
        assert "ksymmetry" in names and "boundary_cliques" in names
        assert torchsym.SOLVERS.default_for("image").name in ("ksymmetry", "boundary_cliques")

    @pytest.mark.parametrize("name", ["image_ksymmetry.yaml", "image_boundary_cliques.yaml"])
    def test_config_builds(self, name):
        pipe = torchsym.build_pipeline(torchsym.load_config(CONFIGS / name))
        assert pipe is not None

    def test_detect_default(self, single_objects):
        img, _ = single_objects[0]
        res = torchsym.detect(img)
        assert isinstance(res, ReflectionAxesResult)
        assert res.method == torchsym.SOLVERS.default_for("image").name


class TestRealPhotos:
    def test_one_dev_photo(self, shared_data):
        folder = shared_data / "images" / "reflection_single_dev"
        if not folder.is_dir():
            pytest.skip(f"{folder} is absent")
        img = read_image(folder / "refs_039.jpg")
        res = torchsym.image.boundary_clique_axes(img)
        assert res.image_size == tuple(img.shape[-2:]) and res.axes.shape[0] >= 1
