"""Pictures of photo methods carry a title and a legend above the picture."""

import cv2
import numpy as np
import torch

import torchsym
from torchsym.viz import write_artifacts
from torchsym.viz.annotate import titled


def test_titled_adds_a_band_and_keeps_the_picture():
    img = np.full((40, 300, 3), 7, np.uint8)
    out = titled(img, "a title " * 20, "a legend")
    assert out.shape[1] == 300 and out.shape[0] > 40 + 3 * 12  # the long title wraps
    assert (out[-40:] == img).all() and (out[:5] == 255).all()
    assert titled(np.zeros((10, 200), np.uint8), "grey").shape[2] == 3


def test_symmslic_and_symmetry_map_pictures_are_titled(tmp_path):
    g = torch.Generator().manual_seed(0)
    half = torch.rand(3, 96, 48, generator=g)
    image = torch.cat([half, half.flip(-1)], dim=-1)
    for result, name in ((torchsym.symm_slic(image, known_axes=[[1.0, 0.0, -48.0]], n_superpixels=60), "superpixels"),
                         (torchsym.symmetry_map(image), "pairs")):
        paths = write_artifacts(result, image, tmp_path, "x")
        picture = cv2.imread(str(next(p for p in paths if p.name == f"x_{name}.png")))
        assert picture.shape[1] == 96 and picture.shape[0] > 96 + 20
        assert (picture[:4] == 255).all()  # the white title band
