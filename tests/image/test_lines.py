"""Line geometry: axes of mirror pairs, their fit and their segments (torchsym.image.lines)."""

from __future__ import annotations

import numpy as np
import torch

from torchsym.image.lines import axis_segment, clip_line_to_image, fit_axis, pair_axes


class TestPairAxes:
    def test_bisector(self):
        line = pair_axes(torch.tensor([[2.0, 5.0]]), torch.tensor([[8.0, 5.0]]))[0]
        assert torch.allclose(line, torch.tensor([-1.0, 0.0, 5.0]))  # x = 5


class TestFitAxis:
    def test_exact_pairs(self):
        # pairs mirrored about x = 30 (a = 1, c = -30)
        pairs = np.array([[20.0, 5.0, 40.0, 5.0], [25.0, 50.0, 35.0, 50.0], [10.0, 70.0, 50.0, 70.0]])
        line = fit_axis(pairs, np.array([49.5, 39.5]), 50.0)
        line = line * np.sign(line[0])
        assert np.allclose(line, [1.0, 0.0, -30.0], atol=1e-9)


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
