"""Tests of PointSymm on images (Harris corners + RANSAC, thesis Sec. 7.4.4)."""

from __future__ import annotations

import math

import pytest
import torch

from torchsym.core.registry import SOLVERS
from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.image import ImageAxisResult, PointSymmImage, PointSymmImageSettings, point_symm_image


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


class TestPointSymmImage:
    def test_axis(self):
        res = point_symm_image(symmetric_image(0))
        assert isinstance(res, ImageAxisResult)
        assert math.degrees(math.acos(min(1.0, abs(float(res.normal[0]))))) < 0.5
        assert abs(abs(float(res.offset)) - 47.5) < 1.0
        assert res.score > 0.7 and res.segment.shape == (2, 2)

    @pytest.mark.slow
    def test_seeded(self):
        a, b = point_symm_image(symmetric_image(1)), point_symm_image(symmetric_image(1))
        assert torch.equal(a.normal, b.normal) and torch.equal(a.inliers, b.inliers)

    def test_exception(self):
        with pytest.raises(InputValueError, match="image: expected at least 4 Harris corners, found 0"):
            point_symm_image(torch.zeros(32, 32))
        with pytest.raises(ConfigError, match="ransac.sample_fraction: expected a finite number > 0.0 and <= 1.0"):
            point_symm_image(symmetric_image(0), ransac={"sample_fraction": 2.0})

    @pytest.mark.parametrize("size", [(3, 3), (16, 16), (31, 64)])
    def test_small_image_refused(self, size):
        # like the other image solvers: a side under 32 px is refused (noise of 16 x 16 scored 1.0)
        noise = torch.rand(1, *size, generator=torch.Generator().manual_seed(0))
        with pytest.raises(InputShapeError, match=r"image: expected height and width >= 32"):
            point_symm_image(noise)

    def test_module_registered(self):
        entry = SOLVERS.get("pointsymm_image")
        assert entry.cls is PointSymmImage and entry.kind == "image"
        assert SOLVERS.default_for("image").name != "pointsymm_image"
        module = PointSymmImage(ransac={"n_iters": 5})
        res = module(symmetric_image(2))
        assert abs(abs(float(res.normal[0])) - 1) < 1e-3 and res.iterations == 5
        assert torch.equal(res.normal, point_symm_image(symmetric_image(2), ransac={"n_iters": 5}).normal)
        assert module.settings == PointSymmImageSettings(ransac={"n_iters": 5}) and "ransac.n_iters=5" in repr(module)

    def test_config_builds(self):
        from pathlib import Path

        import torchsym

        pipe = torchsym.build_pipeline(Path(__file__).resolve().parents[2] / "configs" / "image_pointsymm.yaml")
        assert isinstance(pipe(symmetric_image(0)), ImageAxisResult)


@pytest.mark.slow
class TestPointSymmImageScore:
    """Issue 31: noise and smoothed noise score low, a mirrored image high."""

    @pytest.mark.slow
    def test_noise_low(self):
        g = torch.Generator().manual_seed(3)
        assert point_symm_image(torch.rand(1, 64, 64, generator=g)).score < 0.3

    @pytest.mark.slow
    def test_smoothed_noise_low(self):
        g = torch.Generator().manual_seed(3)
        noise = torch.rand(1, 1, 100, 100, generator=g)
        smooth = torch.nn.functional.avg_pool2d(noise, 5, stride=1, padding=2)[0]
        assert point_symm_image(smooth).score < 0.3

    def test_symmetric_high(self):
        assert point_symm_image(symmetric_image(0, clutter=False)).score > 0.7

    def test_small_image_refused(self):
        with pytest.raises(InputShapeError, match="image"):
            point_symm_image(torch.rand(1, 16, 16))
