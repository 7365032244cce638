from __future__ import annotations

import math

import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.metrics.symmetry_map import nmrf_correspondence_rate, reconstruct_mirror, reconstruction_quality, ssm_scores


def _identity(h, w):
    ys, xs = torch.meshgrid(torch.arange(h), torch.arange(w), indexing="ij")
    return torch.stack([xs, ys], -1).float()


class TestCorrespondenceRate:
    def test_values(self):
        truth = _identity(2, 2)
        est = truth.clone()
        est[0, 0] += torch.tensor([3.0, 4.0])  # error 5
        est[0, 1] += torch.tensor([1.0, 0.0])  # error 1
        mask = torch.tensor([[True, True], [True, False]])
        rate = nmrf_correspondence_rate(est, truth, mask, (0.5, 1.0, 1.5, 5.0, 5.5))
        assert rate.tolist() == pytest.approx([1 / 3, 1 / 3, 2 / 3, 2 / 3, 1.0])

    def test_empty_mask(self):
        f = _identity(2, 2)
        assert nmrf_correspondence_rate(f, f, torch.zeros(2, 2, dtype=torch.bool), (1,)).tolist() == [0.0]

    def test_exception(self):
        with pytest.raises(InputShapeError, match="nmrf"):
            nmrf_correspondence_rate(torch.zeros(2, 2), torch.zeros(2, 2, 2), torch.ones(2, 2, dtype=torch.bool))
        with pytest.raises(InputValueError, match="mask"):
            nmrf_correspondence_rate(torch.zeros(2, 2, 2), torch.zeros(2, 2, 2), torch.ones(2, 2))


class TestReconstruction:
    def test_identity(self):
        img = torch.rand(3, 20, 20, generator=torch.Generator().manual_seed(0))
        assert torch.equal(reconstruct_mirror(img, _identity(20, 20)), img)
        s, p = reconstruction_quality(img, _identity(20, 20))
        assert s == pytest.approx(1.0) and math.isinf(p)

    def test_flip(self):
        img = torch.rand(1, 4, 6, generator=torch.Generator().manual_seed(1))
        f = _identity(4, 6)
        f[..., 0] = 5 - f[..., 0]
        assert torch.equal(reconstruct_mirror(img, f), img.flip(-1))
        half = reconstruct_mirror(img, f, torch.full((4, 6), 0.5))
        assert torch.allclose(half, 0.5 * img.flip(-1))

    def test_psnr_value(self):
        img = torch.zeros(1, 16, 16)
        f = _identity(16, 16)
        s, p = reconstruction_quality(img + 0.1, f, torch.zeros(16, 16))  # Im = 0, MSE = 0.01
        assert p == pytest.approx(20.0, abs=1e-4)


class TestSSMScores:
    def test_perfect(self):
        truth = torch.zeros(10, 10, dtype=torch.bool)
        truth[:, :4] = True
        out = ssm_scores(truth.float(), truth)
        assert out.precision == 1.0 and out.recall == 1.0 and out.auc == 1.0
        assert out.f_beta_0_09 == 1.0 and out.f_beta_0_3 == 1.0
        assert out.thresholds.shape == (21,) and out.thresholds[1] == pytest.approx(12.8 / 255)

    def test_values(self):
        truth = torch.tensor([[True, True, False, False]])
        ssm = torch.tensor([[0.9, 0.1, 0.8, 0.0]])  # claimed at 100/255: pixels 0 and 2
        out = ssm_scores(ssm, truth)
        assert out.precision == 0.5 and out.recall == 0.5
        assert out.f_beta_0_09 == pytest.approx(0.5) and out.f_beta_0_3 == pytest.approx(0.5)
        # positives 0.9, 0.1 against negatives 0.8, 0.0: 3 of 4 orderings right
        assert out.auc == pytest.approx(0.75)

    def test_f_beta(self):
        truth = torch.tensor([[True, True, True, True, False]])
        ssm = torch.tensor([[1.0, 0.0, 0.0, 0.0, 0.0]])  # P = 1, R = 0.25
        out = ssm_scores(ssm, truth)
        assert out.f_beta_0_09 == pytest.approx(1.09 * 0.25 / (0.09 + 0.25))
        assert out.f_beta_0_3 == pytest.approx(1.3 * 0.25 / (0.3 + 0.25))

    def test_constant_auc(self):
        truth = torch.tensor([[True, False, True, False]])
        assert ssm_scores(torch.full((1, 4), 0.5), truth).auc == pytest.approx(0.5)

    def test_exception(self):
        with pytest.raises(InputShapeError, match="truth"):
            ssm_scores(torch.zeros(3, 3), torch.zeros(3, 4, dtype=torch.bool))
