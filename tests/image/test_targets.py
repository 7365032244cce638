import cv2
import numpy as np
import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.image import axis_heatmap, orientation_bins, orientation_labels, segment_distance

SEGS = torch.tensor([[[2.0, 5.0, 12.0, 5.0], [4.0, 1.0, 4.0, 10.0]]])  # one horizontal, one vertical (crossing)


def _drawn():
    img = np.zeros((12, 16), np.float32)
    img[5, 2:13] = 1
    img[1:11, 4] = 1
    return img


class TestAxisHeatmap:
    def test_smoke(self):
        for mode in ("gaussian", "pmcnet", "equisym"):
            h = axis_heatmap(SEGS, (12, 16), mode=mode)
            assert h.shape == (1, 1, 12, 16) and 0 <= float(h.min()) and float(h.max()) <= 1

    def test_pmcnet_equals_authors_recipe(self):
        # PMCNet: cv2.GaussianBlur(axis, (5, 5), cv2.BORDER_DEFAULT) / (max + 1e-5) of the drawn axes
        ref = cv2.GaussianBlur(_drawn(), (5, 5), cv2.BORDER_DEFAULT)
        ref = ref / (ref.max() + 1e-5)
        assert np.abs(axis_heatmap(SEGS, (12, 16), mode="pmcnet")[0, 0].numpy() - ref).max() < 1e-6

    def test_equisym_equals_authors_recipe(self):
        # EquiSym: the same blur, clipped at 0.21260943, / (max + 1e-5)
        ref = np.clip(cv2.GaussianBlur(_drawn(), (5, 5), cv2.BORDER_DEFAULT), 0, 0.21260943)
        ref = ref / (ref.max() + 1e-5)
        assert np.abs(axis_heatmap(SEGS, (12, 16), mode="equisym")[0, 0].numpy() - ref).max() < 1e-6

    def test_equisym_clip_is_line_value(self):
        # the clip constant is the blurred value on a long straight line: the kernel's centre tap
        img = np.zeros((11, 30), np.float32)
        img[5] = 1
        assert abs(cv2.GaussianBlur(img, (5, 5), cv2.BORDER_DEFAULT)[5, 15] - 0.21260943) < 1e-7

    def test_gaussian_by_hand(self):
        h = axis_heatmap(torch.tensor([[[0.0, 0.0, 0.0, 4.0]]]), (5, 3), mode="gaussian", sigma=1.0)
        assert torch.allclose(h[0, 0, 2], torch.tensor([1.0, np.exp(-0.5), np.exp(-2.0)]).float())

    def test_mask(self):
        h = axis_heatmap(SEGS, (12, 16), torch.tensor([[True, False]]))
        assert torch.allclose(h, axis_heatmap(SEGS[:, :1], (12, 16)))
        assert axis_heatmap(SEGS, (12, 16), torch.tensor([[False, False]])).abs().max() == 0

    @pytest.mark.parametrize("mode", ["gaussian", "pmcnet", "equisym"])
    def test_gradcheck(self, mode):
        s = torch.tensor([[[1.3, 2.2, 5.6, 4.1], [4.7, 0.4, 1.9, 5.3]]], dtype=torch.float64, requires_grad=True)
        assert torch.autograd.gradcheck(lambda s: axis_heatmap(s, (6, 7), mode=mode, sigma=1.5), (s,))

    def test_distance_by_hand(self):
        d = segment_distance(torch.tensor([[[0.0, 0.0, 2.0, 0.0]]]), (2, 4))
        assert torch.allclose(d[0, 0], torch.tensor([[0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 1.0, 2**0.5]]))

    def test_exception(self):
        with pytest.raises(InputShapeError, match="segments: expected a floating \\(B, S, 4\\)"):
            axis_heatmap(torch.ones(2, 4), (4, 4))
        with pytest.raises(InputValueError, match="mode: expected"):
            axis_heatmap(SEGS, (4, 4), mode="x")


class TestOrientationLabels:
    def test_bins_by_hand(self):
        # EquiSym: theta = atan(-dy / dx) deg, d = 180 / n, k = floor(theta / d), a = k + 1 - theta / d
        s = torch.tensor([[[0.0, 0.0, 10.0, -10.0], [0.0, 0.0, 0.0, 5.0], [0.0, 0.0, 10.0, 0.0], [0.0, 0.0, 10.0, 10.0]]])
        bins = orientation_bins(s, 8)
        assert bins[0, 0, 2] == 1 and bins[0, 1, 4] == 1 and bins[0, 2, 0] == 1  # 45, 90, 0 degrees
        assert bins[0, 3, 6] == pytest.approx(1.0)  # -45 degrees: k = -2 -> bin 6
        t = float(np.degrees(np.arctan(0.3)))
        b = orientation_bins(torch.tensor([[[0.0, 0.0, 10.0, -3.0]]]), 8)[0, 0]
        assert b[0] == pytest.approx(1 - t / 22.5) and b[1] == pytest.approx(t / 22.5)

    def test_labels_on_axes_only(self):
        lab = orientation_labels(SEGS, (12, 16))
        assert lab.shape == (1, 8, 12, 16)
        assert torch.allclose(lab.sum(1), (lab.sum(1) > 0).float())  # one or zero per pixel
        assert lab[0, 0, 5, 8] == 1 and lab[0, 4, 8, 4] == 1  # horizontal and vertical axes
        assert lab[0, :, 0, 15].sum() == 0

    def test_exception(self):
        with pytest.raises(InputValueError, match="width: expected"):
            orientation_labels(SEGS, (4, 4), width=0.0)


@pytest.mark.parametrize("mode", ["gaussian", "pmcnet", "equisym"])
def test_bfloat16(mode):
    out = axis_heatmap(SEGS.bfloat16(), (12, 16), mode=mode)
    assert out.dtype == torch.bfloat16
    assert torch.allclose(out.float(), axis_heatmap(SEGS, (12, 16), mode=mode), atol=0.02)
