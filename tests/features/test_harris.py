"""Tests of the Harris corner points (thesis Sec. 7.4.4)."""

from __future__ import annotations

import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.features import harris_corners


class TestHarrisCorners:
    def test_smoke(self):
        img = torch.zeros(40, 40)
        img[10:30, 10:30] = 1.0
        c = harris_corners(img, n_corners=10)
        assert c.shape[1] == 2 and 4 <= c.shape[0] <= 10 and c.dtype == img.dtype
        assert bool(((c - 19.5).abs() > 5).all())  # every corner sits near a corner of the square

    def test_cardinality(self):
        img = torch.zeros(64, 64)
        for k in range(4):
            img[4 + 15 * k : 12 + 15 * k, 6:14] = 1.0
        assert harris_corners(img, n_corners=3).shape == (3, 2)

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"image: expected a single image \(B = 1\)"):
            harris_corners(torch.zeros(2, 1, 10, 10))
        with pytest.raises(InputShapeError, match="image: expected height and width >= 4"):
            harris_corners(torch.rand(3, 3))  # kornia's padding error, untyped, before the check
