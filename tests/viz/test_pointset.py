"""Pictures of PointSymm results (torchsym.viz.pointset)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

import torchsym
from torchsym.viz import write_artifacts
from torchsym.viz.pointset import symmetry_frame


def _png(path):
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


class TestPointSymmPicture:
    @pytest.mark.parametrize("d", [2, 3, 5])
    def test_smoke(self, tmp_path, d):
        s = torchsym.make_symmetric_pointset(40, d, generator=torch.Generator().manual_seed(d))
        res = torchsym.point_symm(s.points)
        paths = write_artifacts(res, s.points, tmp_path, "set")
        assert [p.name for p in paths] == ["set_pointsymm.png"]
        img = _png(paths[0])
        assert img.shape[0] > 300 and img.std() > 10  # a picture, not a blank page

    def test_symmetry_frame(self):
        # the first column is the signed distance to the plane; mirrors swap its sign and keep the rest
        s = torchsym.make_symmetric_pointset(30, 4, generator=torch.Generator().manual_seed(0))
        c = symmetry_frame(s.points.numpy(), s.normal.numpy(), float(s.offset))
        assert c.shape == (30, 3)
        np.testing.assert_allclose(c[s.correspondence.numpy(), 0], -c[:, 0], atol=1e-12)
        np.testing.assert_allclose(c[s.correspondence.numpy(), 1:], c[:, 1:], atol=1e-12)


class TestImageAxisPicture:
    def test_smoke(self, tmp_path):
        img = torch.zeros(1, 64, 64)
        img[0, 10:30, 8:20] = 1.0
        img[0, 36:50, 14:26] = 0.6
        img = torch.maximum(img, img.flip(-1))
        res = torchsym.point_symm_image(img, ransac={"n_iters": 3})
        paths = write_artifacts(res, img, tmp_path, "photo")
        assert [p.name for p in paths] == ["photo_axis.png"]
        assert _png(paths[0]).std() > 10
