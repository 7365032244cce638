import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.metrics import axis_pixel_counts, axis_pixel_f1, pixel_f1_from_counts


def _gt():
    gt = torch.zeros(1, 1, 20, 20)
    gt[0, 0, 10, 5:15] = 1
    return gt


class TestPixelF1:
    def test_perfect(self):
        out = axis_pixel_f1(_gt(), _gt(), max_dist=0)
        assert out.max_f1 == pytest.approx(1.0)

    def test_value_by_hand(self):
        # gt: 10 px on row 10; dilated by radius 1 -> 10 x 3 + 2 end pixels = 32 px.
        # prediction 0.7 on row 11, columns 5..14 (10 px, inside the dilation) and on (0, 0) (outside)
        pred = torch.zeros(1, 1, 20, 20)
        pred[0, 0, 11, 5:15] = 0.7
        pred[0, 0, 0, 0] = 0.7
        th, counts = axis_pixel_counts(pred, _gt(), n_thresholds=3, max_dist=1)
        assert th.tolist() == pytest.approx([0.25, 0.5, 0.75])
        assert counts[:, 0].tolist() == [10, 11, 32] and counts[:, 2].tolist() == [0, 0, 32]
        out = pixel_f1_from_counts(th, counts)
        p, r = 10 / 11, 10 / 32
        assert out.f1[0].item() == pytest.approx(2 * p * r / (p + r))
        assert out.precision[2].item() == 0.0  # nothing predicted: precision 0 (Funk and Liu)
        assert out.best_threshold == pytest.approx(0.25)

    def test_counts_add_over_batches(self):
        g = torch.Generator().manual_seed(0)
        pred = torch.rand(2, 1, 20, 20, generator=g)
        gt = torch.cat([_gt(), _gt().flip(-1).transpose(-1, -2)])
        th, both = axis_pixel_counts(pred, gt)
        _, a = axis_pixel_counts(pred[:1], gt[:1])
        _, b = axis_pixel_counts(pred[1:], gt[1:])
        assert torch.equal(both, a + b)

    def test_exception(self):
        with pytest.raises(InputShapeError, match="gt: expected"):
            axis_pixel_f1(torch.zeros(1, 1, 4, 4), torch.zeros(1, 1, 4, 5))
