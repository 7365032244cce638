"""Batches and large images (torchsym.image.batching)."""

from __future__ import annotations

import pytest
import torch

import torchsym
from torchsym.image.batching import to_input_pixels
from torchsym.image.lines import pair_axes
from torchsym.image.results import build_result
from torchsym.image.synthetic import mirrored_objects_image
from torchsym.metrics.axes import axis_angle, axis_center_distance


class TestMaxSide:
    def test_to_input_pixels(self):
        # a line through two points of a 320 x 240 copy, mapped to the 1280 x 960 input
        p1, p2 = torch.tensor([10.0, 20.0]), torch.tensor([200.0, 150.0])
        line = pair_axes(torch.cat([p1, p2])[None, :2], torch.cat([p1, p2])[None, 2:])[0]
        res = build_result([line], [torch.tensor([0])], [1.0], torch.cat([p1, p2])[None], 240, 320, "test")
        big = to_input_pixels(res, 960, 1280)
        assert big.image_size == (960, 1280) and big.info["working_size"] == (240, 320)
        q1, q2 = (p1 + 0.5) * 4 - 0.5, (p2 + 0.5) * 4 - 0.5
        assert torch.allclose(big.pairs[0], torch.cat([q1, q2]))
        a, b, c = big.lines[0].double()
        assert abs(float(torch.hypot(a, b)) - 1) < 1e-6
        # the mapped line is the perpendicular bisector of the mapped pair
        mid = 0.5 * (q1 + q2).double()
        assert abs(float(a * mid[0] + b * mid[1] + c)) < 1e-3
        for end in big.axes[0].double().reshape(2, 2):
            assert abs(float(a * end[0] + b * end[1] + c)) < 1e-3

    @pytest.mark.parametrize("name", ["boundary_cliques", "ksymmetry"])
    def test_large_image_detected_on_a_copy(self, name):
        img, truth = mirrored_objects_image(1, height=240, width=320, generator=torch.Generator().manual_seed(2))
        big = torch.nn.functional.interpolate(img[None], size=(960, 1280), mode="bilinear", align_corners=False)[0]
        truth_big = (truth.double() + 0.5) * 4 - 0.5
        solver = torchsym.SOLVERS.get(name).cls
        res = solver(max_side=320)(big)
        assert res.image_size == (960, 1280) and res.info["working_size"] == (240, 320)
        assert float(axis_angle(res.axes[0].double(), truth_big[0])) < 3.0
        assert float(axis_center_distance(res.axes[0].double(), truth_big[0])) < 0.05 * 960
        # the same copy given by hand: the same detection, in the copy's pixels
        small = torch.nn.functional.interpolate(big[None], size=(240, 320), mode="bilinear", align_corners=False, antialias=True)[0]
        direct = solver(max_side=None)(small.clamp(0, 1))
        assert torch.allclose(res.axes.double(), (direct.axes.double() + 0.5) * 4 - 0.5, atol=1e-3)
        assert solver(max_side=2000)(img).info.get("working_size") is None  # smaller than max_side: untouched

    @pytest.mark.parametrize("name", ["boundary_cliques", "ksymmetry"])
    def test_small_image_detected_on_a_larger_copy(self, name):
        img, truth = mirrored_objects_image(1, height=120, width=160, generator=torch.Generator().manual_seed(2))
        solver = torchsym.SOLVERS.get(name).cls
        res = solver(min_side=320)(img)
        assert res.image_size == (120, 160) and res.info["working_size"] == (240, 320)
        assert bool((res.axes[:, [0, 2]] <= 159 + 1e-3).all() and (res.axes[:, [1, 3]] <= 119 + 1e-3).all())
        assert solver(min_side=100)(img).info.get("working_size") is None  # larger than min_side: untouched
        with pytest.raises(torchsym.errors.ConfigError, match="min_side: expected at most max_side"):
            solver(min_side=800, max_side=640)

    @pytest.mark.parametrize("name", ["boundary_cliques", "ksymmetry"])
    def test_strips_half_precision_and_small_images(self, name):
        solver = torchsym.SOLVERS.get(name).cls
        g = torch.Generator().manual_seed(0)
        strip = solver()(torch.rand(1, 400, 8000, generator=g))  # the copy's short side stays at SIFT's 32
        assert strip.image_size == (400, 8000) and strip.info["working_size"] == (32, 640)
        half = solver(max_side=64)(torch.rand(1, 100, 120, generator=g).half())
        assert half.image_size == (100, 120) and half.info["working_size"] == (53, 64)
        with pytest.raises(torchsym.errors.InputShapeError, match="image: expected height and width >= 32"):
            solver(max_side=None)(torch.rand(1, 20, 200, generator=g))

    @pytest.mark.parametrize("bad", [0, 8, 31, 2.5, "640"])
    def test_bad_max_side(self, bad):
        for name in ("boundary_cliques", "ksymmetry"):
            with pytest.raises(torchsym.errors.TorchsymError, match="max_side"):
                torchsym.SOLVERS.get(name).cls(max_side=bad)
