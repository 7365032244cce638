"""Bad and degenerate inputs to both Ch. 2 solvers: typed errors with the argument named."""

from __future__ import annotations

import pytest
import torch

from torchsym.errors import (
    ConfigError,
    InputFileError,
    InputShapeError,
    InputValueError,
    TorchsymError,
)
from torchsym.image import (
    BoundaryCliqueDetector,
    KSymmetryDetector,
    boundary_clique_axes,
    ksymmetry_axes,
)
from torchsym.io import read_image

SOLVERS = [boundary_clique_axes, ksymmetry_axes]


@pytest.mark.parametrize("fn", SOLVERS)
class TestBadInput:
    def test_blank_image_gives_no_axes(self, fn):
        for blank in (torch.zeros(3, 64, 80), torch.full((1, 64, 80), 0.5)):
            res = fn(blank)
            assert res.axes.shape == (0, 4) and res.scores.shape == (0,)
            assert res.image_size == (64, 80)

    def test_grayscale_and_colour(self, fn, single_objects):
        img = torch.nn.functional.interpolate(single_objects[1][0][None], size=(120, 100), mode="area")[0]
        gray = img.mean(0, keepdim=True)
        assert fn(gray).image_size == (120, 100)
        assert fn(img[None]).image_size == (120, 100)
        assert fn((img * 255).round().to(torch.uint8)).image_size == (120, 100)  # uint8 is scaled

    def test_tiny_image(self, fn):
        with pytest.raises(InputShapeError, match=r"image: expected height and width >= (16|32), got \(3, 8, 8\)"):
            fn(torch.rand(3, 8, 8))

    def test_wrong_shape(self, fn):
        with pytest.raises(InputShapeError, match=r"image: expected 1 or 3 channels in \(B, C, H, W\), got \(2, 32, 32\)"):
            fn(torch.rand(2, 32, 32))
        with pytest.raises(InputShapeError, match=r"image: expected \(H, W\), \(C, H, W\) or \(B, C, H, W\)"):
            fn(torch.rand(1, 1, 3, 32, 32))

    def test_wrong_dtype(self, fn):
        with pytest.raises(InputShapeError, match="image: expected real numbers, got dtype torch.complex64"):
            fn(torch.zeros(3, 32, 32, dtype=torch.complex64))
        with pytest.raises(InputShapeError, match="image: expected a tensor or array, got str"):
            fn("not an image")

    def test_nan(self, fn):
        img = torch.rand(3, 32, 32)
        img[0, 3, 4] = float("nan")
        with pytest.raises(InputValueError, match="image: expected finite values"):
            fn(img)


@pytest.mark.parametrize("module", [BoundaryCliqueDetector, KSymmetryDetector])
def test_module_rejects_bad_settings(module):
    with pytest.raises(ConfigError, match="max_axes: expected an int >= 1, got 0"):
        module(max_axes=0)
    with pytest.raises(ConfigError, match="settings: expected"):
        module(5)


def test_non_image_file(tmp_path):
    bad = tmp_path / "photo.jpg"
    bad.write_text("this is not a JPEG")
    with pytest.raises(InputFileError, match="path: cannot decode"):
        read_image(bad)
    with pytest.raises(TorchsymError):
        read_image(tmp_path / "missing.png")
