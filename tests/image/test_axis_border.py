"""The axis stage leaves the image's border and a constant frame out of every score (issue 56)."""

from __future__ import annotations

import kornia
import pytest
import torch

from torchsym.image.axes import AxisStageSettings, image_axes
from torchsym.image.axes.border import content_box
from torchsym.image.axes.stage import shift_result
from torchsym.metrics.axes import match_axes

BORDER = AxisStageSettings().border


def _box(img: torch.Tensor) -> tuple[int, int, int, int]:
    return content_box(img, tolerance=BORDER.tolerance, margin=BORDER.margin, min_margin=BORDER.min_band)


def _smooth(img: torch.Tensor, sigma: float) -> torch.Tensor:
    if sigma == 0:
        return img
    k = 2 * int(3 * sigma) + 1
    return kornia.filters.gaussian_blur2d(img[None], (k, k), (sigma, sigma), border_type="reflect")[0]


def framed_noise(seed: int, colour: float, pad: int = 20, sigma: float = 0.0, h: int = 240, w: int = 320) -> torch.Tensor:
    """Uniform noise inside a constant ``pad``-px frame of ``colour``, then smoothed by ``sigma``."""
    img = torch.full((3, h, w), colour)
    img[:, pad:-pad, pad:-pad] = torch.rand(3, h - 2 * pad, w - 2 * pad, generator=torch.Generator().manual_seed(seed))
    return _smooth(img, sigma)


class TestContentBox:
    def test_no_frame_leaves_the_band(self):
        img = torch.rand(3, 200, 300, generator=torch.Generator().manual_seed(0))
        band = round(BORDER.margin * 200)
        assert _box(img) == (band, 200 - band, band, 300 - band)

    @pytest.mark.parametrize("colour", [0.0, 1.0])
    def test_constant_frame_stripped(self, colour):  # root cause 1: the frame's inner edges pair up
        y0, y1, x0, x1 = _box(framed_noise(0, colour))
        assert y0 >= 20 and x0 >= 20 and y1 <= 220 and x1 <= 300

    @pytest.mark.parametrize("sigma", [2.0, 4.0])
    def test_smoothed_frame_edge_stripped(self, sigma):  # root cause 2: the smoothed frame's ramp
        y0, y1, x0, x1 = _box(framed_noise(0, 0.0, sigma=sigma))
        assert min(y0, x0, 240 - y1, 320 - x1) >= 20 + 2 * sigma

    def test_blank_image_kept_whole(self):
        assert _box(torch.zeros(3, 64, 64)) == (0, 64, 0, 64)


class TestNoFrameAxis:
    @pytest.mark.parametrize("colour", [0.0, 1.0])
    @pytest.mark.parametrize("sigma", [0.0, 2.0, 4.0])
    def test_framed_noise_accepts_nothing(self, colour, sigma):
        for seed in range(2):
            res = image_axes(framed_noise(seed, colour, sigma=sigma))
            assert int(res.accepted.sum()) == 0, (colour, sigma, seed, res.scores[:3])

    def test_zero_padded_box_filter_accepts_nothing(self):  # root cause 3: avg_pool's zero padding fades every side
        for seed in range(2):
            noise = torch.rand(1, 3, 240, 320, generator=torch.Generator().manual_seed(2100 + seed))
            res = image_axes(torch.nn.functional.avg_pool2d(noise, 9, 1, 4)[0])
            assert int(res.accepted.sum()) == 0, res.scores[:3]


class TestFramedObject:
    def test_axis_in_image_pixels(self, single_objects):
        img, gt = single_objects[0]
        framed = torch.ones(3, 300, 300)
        framed[:, 30:270, 30:270] = img
        res = image_axes(framed)
        assert bool(res.accepted[0])
        assert res.image_size == (300, 300)
        shifted = gt + torch.tensor([30.0, 30.0, 30.0, 30.0])
        assert bool(match_axes(res.axes[:1], shifted, image_size=(300, 300), criterion="challenge").any())

    def test_shift_result_moves_lines_with_segments(self, single_objects):
        img, _ = single_objects[1]
        res = image_axes(img)
        moved = shift_result(res, 7, 11, (300, 320))
        mid = (moved.axes[:, :2] + moved.axes[:, 2:]) / 2
        on_line = moved.lines[:, 0] * mid[:, 0] + moved.lines[:, 1] * mid[:, 1] + moved.lines[:, 2]
        assert torch.allclose(on_line, torch.zeros_like(on_line), atol=1e-2)
        assert torch.allclose(moved.axes - res.axes, torch.tensor([7.0, 11.0, 7.0, 11.0]).expand_as(res.axes))
