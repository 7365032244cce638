import math

import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.metrics import dense_symmetry_error, symmetry_distance_error, symmetrynet_pr_curve


class TestDenseSymmetryError:
    def test_value_by_hand(self):
        # points (1, 0), (0, 2); true plane x = 0, predicted y = 0.
        # true reflections (-1, 0), (0, 2): chords 2 and 0 -> max 2.
        # predicted reflections (1, 0), (0, -2): distances to the true ones 2 and 4 -> mean 3 -> error 1.5
        p = torch.tensor([[[1.0, 0.0], [0.0, 2.0]]], dtype=torch.float64)
        e = dense_symmetry_error(
            p,
            torch.tensor([[[0.0, 1.0]]], dtype=torch.float64),
            torch.zeros(1, 1, dtype=torch.float64),
            torch.tensor([[[1.0, 0.0]]], dtype=torch.float64),
            torch.zeros(1, 1, dtype=torch.float64),
        )
        assert e.shape == (1, 1, 1) and e.item() == pytest.approx(1.5)

    def test_zero_for_same_plane_and_scale_free(self):
        p = torch.randn(2, 50, 3, dtype=torch.float64)
        n, b = torch.randn(2, 2, 3, dtype=torch.float64), torch.randn(2, 2, dtype=torch.float64)
        e = dense_symmetry_error(p, n, b, n, b)
        assert torch.diagonal(e, dim1=1, dim2=2).abs().max() < 1e-12
        scaled = dense_symmetry_error(3 * p, n, 3 * b, n.flip(1), 3 * b.flip(1))
        assert torch.allclose(scaled, dense_symmetry_error(p, n, b, n.flip(1), b.flip(1)))

    def test_gradcheck(self):
        p = torch.randn(1, 6, 3, dtype=torch.float64)
        n = torch.randn(1, 2, 3, dtype=torch.float64, requires_grad=True)
        b = torch.randn(1, 2, dtype=torch.float64, requires_grad=True)
        tn, tb = torch.randn(1, 1, 3, dtype=torch.float64), torch.randn(1, 1, dtype=torch.float64)
        assert torch.autograd.gradcheck(lambda n, b: dense_symmetry_error(p, n, b, tn, tb), (n, b))


class TestSymmetryNetPR:
    def test_by_hand(self):
        thr = math.tan(math.radians(15))
        # shape 0: two true planes, three predictions: pred 0 finds true 0; pred 1 finds true 0 and 1
        # (true 1's first finder is pred 1); pred 2 finds nothing -> false positive
        e = torch.tensor([[[0.1, 0.9], [0.2, 0.1], [0.9, 0.9]]])
        s = torch.tensor([[0.9, 0.6, 0.8]])
        curve = symmetrynet_pr_curve(e, s, threshold=thr)
        # scores: tp 0.9 (true 0), tp 0.6 (true 1), fp 0.8 -> at 0.9: P 1 R 0.5; 0.8: P 0.5 R 0.5; 0.6: P 2/3 R 1
        assert curve.thresholds.tolist() == pytest.approx([0.9, 0.8, 0.6])
        assert curve.precision.tolist() == pytest.approx([1.0, 0.5, 2 / 3])
        assert curve.recall.tolist() == pytest.approx([0.5, 0.5, 1.0])

    def test_masks(self):
        e = torch.tensor([[[0.1, 0.9], [0.9, 0.9]]])
        curve = symmetrynet_pr_curve(e, torch.tensor([[0.9, 0.5]]), pred_mask=torch.tensor([[1, 0]]), true_mask=torch.tensor([[1, 0]]))
        assert curve.max_f == pytest.approx(1.0)

    def test_exception(self):
        with pytest.raises(InputShapeError, match="scores: expected"):
            symmetrynet_pr_curve(torch.zeros(1, 2, 2), torch.zeros(1, 3))


class TestSymmetryDistanceError:
    def test_value_by_hand(self):
        # points (0,0), (2,0), (0,3); plane x = 0.5: each reflection is 1 from the cloud; diagonal sqrt(13)
        p = torch.tensor([[[0.0, 0.0], [2.0, 0.0], [0.0, 3.0]]], dtype=torch.float64)
        n, b = torch.tensor([[[1.0, 0.0]]], dtype=torch.float64), torch.tensor([[-0.5]], dtype=torch.float64)
        assert symmetry_distance_error(p, n, b, scale="none").item() == pytest.approx(1.0)
        assert symmetry_distance_error(p, n, b).item() == pytest.approx(1 / 13**0.5)
