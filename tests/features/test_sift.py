"""SIFT through kornia and the mirrored descriptor (thesis Sec. 2.2.1)."""

from __future__ import annotations

import math

import kornia.feature as KF
import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.features import detect_sift, mirror_descriptors, mirror_permutation
from torchsym.image.synthetic import mirrored_objects_image


@pytest.fixture(scope="module")
def image() -> torch.Tensor:
    img, _ = mirrored_objects_image(1, height=160, width=200, generator=torch.Generator().manual_seed(3))
    return img


class TestDetectSift:
    def test_smoke(self, image):
        f = detect_sift(image, num_features=200)
        assert 0 < len(f) <= 200
        assert f.descriptors.shape == (len(f), 128)
        assert f.points.shape == (len(f), 2)
        assert bool((f.responses > 0).all())

    def test_padding_dropped(self):
        # a nearly blank image has few keypoints; kornia pads with zero responses
        img = torch.zeros(1, 64, 64)
        img[:, 30:34, 30:34] = 1.0
        f = detect_sift(img, num_features=500)
        assert len(f) < 40  # the budget is capped at one keypoint per 100 pixels: 40 here
        assert bool((f.responses > 0).all())

    def test_blank(self):
        f = detect_sift(torch.full((3, 64, 64), 0.3))
        assert len(f) == 0 and f.descriptors.shape == (0, 128)

    def test_exception(self):
        with pytest.raises(InputShapeError, match="image: expected a single image"):
            detect_sift(torch.rand(2, 1, 64, 64))
        with pytest.raises(InputValueError, match="backend: expected 'kornia' or 'opencv', got 'vlfeat'"):
            detect_sift(torch.rand(1, 64, 64), backend="vlfeat")

    def test_opencv_backend(self, image):
        f = detect_sift(image, num_features=200, backend="opencv")
        assert f.layout == "opencv" and 0 < len(f) <= 200
        assert f.descriptors.shape == (len(f), 128) and f.lafs.shape == (len(f), 2, 3)
        assert torch.allclose(f.descriptors.norm(dim=1), torch.ones(len(f)), atol=1e-4)  # RootSIFT: unit L2
        assert torch.equal(f.lafs[:, :, 2], f.points)
        assert len(detect_sift(torch.full((3, 64, 64), 0.3), backend="opencv")) == 0

    def test_opencv_mirror_against_flipped_image(self, image):
        """OpenCV's layout: the permuted descriptor is close to the one computed on the flipped image."""
        import cv2

        u8 = (image.mean(0) * 255).round().to(torch.uint8).numpy()
        sift = cv2.SIFT_create()
        kps, desc = sift.detectAndCompute(u8, None)
        w = u8.shape[1]
        flipped_kps = [cv2.KeyPoint(w - 1 - k.pt[0], k.pt[1], k.size, (180 - k.angle) % 360, k.response, k.octave)
                       for k in kps]
        flipped_kps, flipped = sift.compute(u8[:, ::-1].copy(), flipped_kps)
        assert len(flipped_kps) == len(kps)
        d, fd = torch.from_numpy(desc), torch.from_numpy(flipped)
        rel = lambda a: (a - fd).norm(dim=1) / d.norm(dim=1)  # noqa: E731
        assert float(rel(mirror_descriptors(d, layout="opencv")).median()) < 0.3
        assert float(rel(d).median()) > 0.5


class TestMirrorPermutation:
    def test_involution(self):
        p = mirror_permutation()
        assert sorted(p.tolist()) == list(range(128))
        assert torch.equal(p[p], torch.arange(128))

    def test_against_flipped_image(self, image):
        """The permuted descriptor equals the descriptor computed on the flipped image.

        On a horizontally flipped image the keypoint (x, y) moves to (W - 1 - x, y) and its
        orientation theta becomes 180 deg - theta.
        """
        f = detect_sift(image, num_features=150)
        gray = image.mean(0, keepdim=True)[None]  # (1, 1, H, W)
        w = gray.shape[-1]
        centre = f.points.clone()
        centre[:, 0] = w - 1 - centre[:, 0]
        ori = torch.rad2deg(math.pi - f.orientations)
        lafs = KF.laf_from_center_scale_ori(centre[None], f.scales[None, :, None, None], ori[None, :, None])
        flipped = KF.get_laf_descriptors(gray.flip(-1), lafs, KF.SIFTDescriptor(41, rootsift=True), patch_size=41)[0]
        direct = KF.get_laf_descriptors(gray, f.lafs[None], KF.SIFTDescriptor(41, rootsift=True), patch_size=41)[0]
        err = (mirror_descriptors(direct) - flipped).norm(dim=1).detach()
        assert float(err.median()) < 1e-4
        assert float(err.max()) < 1e-3
        # and the unpermuted descriptor does not match: the test can fail
        assert float((direct - flipped).norm(dim=1).median().detach()) > 0.1

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"descriptors: expected \(\.\.\., 128\)"):
            mirror_descriptors(torch.rand(3, 64))
