"""Tests of PointSymm on images (Harris corners + RANSAC, thesis Sec. 7.4.4)."""

from __future__ import annotations

import math

import pytest
import torch

from torchsym.core.registry import SOLVERS
from torchsym.errors import InputShapeError, InputValueError
from torchsym.pointset import (
    ImageAxisResult,
    PointSymmImage,
    harris_corners,
    pointsymm_image,
)


def symmetric_image(seed: int = 0, size: int = 96, clutter: bool = True) -> torch.Tensor:
    g = torch.Generator().manual_seed(seed)
    img = torch.zeros(1, size, size)
    for _ in range(8):
        x0 = int(torch.randint(2, size // 2 - 4, (1,), generator=g))
        y0 = int(torch.randint(2, size - 16, (1,), generator=g))
        w, h = int(torch.randint(4, 12, (1,), generator=g)), int(torch.randint(4, 14, (1,), generator=g))
        img[0, y0 : y0 + h, x0 : x0 + w] = float(torch.rand(1, generator=g)) * 0.7 + 0.3
    img = torch.maximum(img, img.flip(-1))  # mirror about the column x = (size - 1) / 2
    if clutter:
        img[0, 5:12, size - 16 : size - 6] = 0.5
    return img


class TestHarrisCorners:
    def test_corners_of_square(self):
        img = torch.zeros(40, 40)
        img[10:30, 10:30] = 1.0
        c = harris_corners(img, n_corners=10)
        assert c.shape[1] == 2 and 4 <= c.shape[0] <= 10
        assert bool(((c - 19.5).abs() > 5).all())  # every corner sits near a corner of the square

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"image: expected a single image \(B = 1\)"):
            harris_corners(torch.zeros(2, 1, 10, 10))


class TestPointSymmImage:
    def test_axis(self):
        res = pointsymm_image(symmetric_image(0))
        assert isinstance(res, ImageAxisResult)
        assert math.degrees(math.acos(min(1.0, abs(float(res.normal[0]))))) < 0.5
        assert abs(abs(float(res.offset)) - 47.5) < 1.0
        assert res.score > 0.7 and res.segment.shape == (2, 2)

    def test_seeded(self):
        a, b = pointsymm_image(symmetric_image(1)), pointsymm_image(symmetric_image(1))
        assert torch.equal(a.normal, b.normal) and torch.equal(a.inliers, b.inliers)

    def test_exception(self):
        with pytest.raises(InputValueError, match="image: expected at least 4 Harris corners, found 0"):
            pointsymm_image(torch.zeros(32, 32))
        with pytest.raises(InputValueError, match="sample_fraction"):
            pointsymm_image(symmetric_image(0), sample_fraction=2.0)

    def test_module_registered(self):
        entry = SOLVERS.get("pointsymm_image")
        assert entry.cls is PointSymmImage and entry.kind == "image"
        assert SOLVERS.default_for("image").name != "pointsymm_image"
        res = PointSymmImage(ransac_iters=5)(symmetric_image(2))
        assert abs(abs(float(res.normal[0])) - 1) < 1e-3
