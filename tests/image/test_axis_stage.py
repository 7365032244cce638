"""The axis stage: candidates, the photometric test, the calibrated score and the decision."""

from __future__ import annotations

import dataclasses

import pytest
import torch

import torchsym
from torchsym.errors import ConfigError
from torchsym.image.axes import AxisStage, AxisStageSettings, image_axes
from torchsym.image.axes.decision import calibrated_score
from torchsym.image.axes.level import band_level, from_level, to_level
from torchsym.image.axes.mirror_ncc import mirror_ncc
from torchsym.image.axes.refine import refine_axes
from torchsym.metrics.axes import match_axes


class TestAxisStage:
    def test_smoke(self, single_objects):
        img, gt = single_objects[0]
        res = image_axes(img)
        assert res.method == "axes" and res.axes.shape[1] == 4
        assert res.scores.shape == res.accepted.shape == (len(res),)
        assert bool(res.accepted[0])
        assert bool(match_axes(res.axes[:1], gt, image_size=(240, 240), criterion="challenge").any())

    def test_cardinality(self, single_objects):
        img, _ = single_objects[1]
        res = image_axes(img)
        assert bool((res.scores[:-1] >= res.scores[1:]).all())  # best first
        assert bool(((res.scores >= 0) & (res.scores <= 1)).all())
        dec = AxisStageSettings().decision
        expected = (res.scores >= dec.threshold) & torch.cat([torch.ones(1, dtype=torch.bool),
                                                              res.scores[1:] >= dec.second_threshold])
        assert torch.equal(res.accepted, expected)
        assert res.accepted_axes.shape == (int(res.accepted.sum()), 4)

    def test_default_for_photos(self, single_objects):
        img, _ = single_objects[2]
        res = torchsym.detect(img)
        assert res.method == "axes"
        assert "accepted" in res.summary()
        d = res.to_dict()
        assert len(d["accepted"]) == len(d["scores"])

    def test_noise_accepts_little(self):
        noise = torch.rand(3, 160, 160, generator=torch.Generator().manual_seed(3))
        res = image_axes(noise)
        assert int(res.accepted.sum()) <= 1
        assert "accepted" in res.summary()

    def test_module_matches_function(self, single_objects):
        img, _ = single_objects[3]
        a, b = AxisStage()(img), image_axes(img)
        assert torch.equal(a.axes, b.axes) and torch.equal(a.scores, b.scores)

    def test_exception(self):
        with pytest.raises(ConfigError):
            AxisStageSettings.from_dict({"decision": {"threshold": 1.5}})
        with pytest.raises(ConfigError):
            image_axes(torch.rand(3, 64, 64), photometric={"sidee": 100})


class TestPhotometric:
    def _mirror_image(self):
        g = torch.Generator().manual_seed(0)
        left = torch.rand(3, 64, 32, generator=g)
        img = torch.cat([left, left.flip(-1)], -1)  # mirrored about x = 31.5
        return img[None]

    def test_mirror_scores_high_and_turned_low(self):
        img = self._mirror_image()
        level, scale = band_level(img, 64, 0.0)
        seg = torch.tensor([[31.5, 4.0, 31.5, 59.0], [4.0, 31.5, 59.0, 31.5]])
        ncc, inside = mirror_ncc(level, to_level(seg, scale, 0.5))
        assert ncc[0] > 0.95 and ncc[1] < 0.5
        assert bool((inside > 0.9).all())

    def test_level_round_trip(self):
        seg = torch.tensor([[10.0, 20.0, 200.0, 150.0]])
        img = torch.rand(1, 3, 240, 320)
        _, scale = band_level(img, 128, 2.0)
        assert torch.allclose(from_level(to_level(seg, scale, 0.5), scale), seg, atol=1e-3)

    def test_refine_recovers_a_tilted_start(self):
        img = self._mirror_image()
        level, scale = band_level(img, 64, 0.0)
        start = to_level(torch.tensor([[29.0, 4.0, 33.0, 59.0]]), scale, 0.5)  # ~4 deg off
        axes, ncc, _ = refine_axes(level, start, rounds=5)
        seg = from_level(axes, scale)
        assert abs(float(seg[0, 0] - seg[0, 2])) < 1.0 and ncc[0] > 0.9

    def test_calibrated_score_in_unit_interval(self):
        s = calibrated_score(torch.tensor([-2.0, 0.0, 2.0]), torch.tensor([0.0, 0.1, 1.0]), torch.tensor([-1.0, 0.0, 1.0]),
                             torch.tensor([-1.0, 0.0, 1.0]), torch.tensor([0.0, 1.0, 0.0]),
                             AxisStageSettings().decision)
        assert bool(((s >= 0) & (s <= 1)).all()) and s[2] > s[0]

    def test_inputs_not_modified(self):
        img = self._mirror_image()
        before = img.clone()
        band_level(img, 32, 2.0)
        assert torch.equal(img, before)
