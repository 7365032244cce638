from __future__ import annotations

import numpy as np
import torch

from torchsym.image.symmetry_map import stylize, symmetry_map
from torchsym.image.synthetic import mirrored_photo
from torchsym.viz import write_artifacts
from torchsym.viz.symmetry_map import nmrf_hsv


def test_symmetry_map_pictures(tmp_path):
    d = mirrored_photo(height=160, width=200, generator=torch.Generator().manual_seed(1))
    r = symmetry_map(d["image"], n_axes=1, patchmatch={"max_iters": 1})
    paths = write_artifacts(r, d["image"], tmp_path, "x")
    names = {p.name for p in paths}
    assert {"x_pairs.png", "x_nmrf0.png", "x_ssm0.png", "x_im0.png", "x_nmrf0.npy"} <= names
    assert np.load(tmp_path / "x_nmrf0.npy").shape == (160, 200, 2)
    out = write_artifacts(stylize(r, region_px=8), d["image"], tmp_path, "x")
    assert [p.name for p in out] == ["x_stylized.png"]


def test_empty_map_pictures(tmp_path):
    r = symmetry_map(torch.full((3, 40, 40), 0.2))
    names = {p.name for p in write_artifacts(r, None, tmp_path, "e")}
    assert names == {"e_pairs.png", "e_ssm.png"}


def test_nmrf_hsv():
    h, w = 4, 6
    ys, xs = torch.meshgrid(torch.arange(h), torch.arange(w), indexing="ij")
    f = torch.stack([xs, ys], -1).float()
    f[..., 0] = 5 - f[..., 0]
    pic = nmrf_hsv(f, torch.ones(h, w))
    assert pic.shape == (h, w, 3) and pic.dtype == np.uint8
    assert pic.max() == 255  # value = score 1 on the pixels farthest from their mirror
