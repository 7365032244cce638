import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.losses import flip_consistency_loss, orientation_flip_permutation


class TestFlipConsistency:
    def test_zero_for_equivariant_net(self):
        img = torch.randn(2, 1, 8, 9)
        net = lambda x: x**2  # noqa: E731  pointwise: commutes with flips
        assert flip_consistency_loss(net(img), net(img.flip(-1))).abs().max() == 0

    def test_value_by_hand(self):
        out = torch.tensor([[[[1.0, 2.0]]]])
        flipped = torch.tensor([[[[0.0, 0.0]]]])  # unflipped: (0, 0)
        assert torch.allclose(flip_consistency_loss(out, flipped), torch.tensor([1.5]))
        assert torch.allclose(flip_consistency_loss(out, flipped, kind="l2"), torch.tensor([2.5]))

    def test_orientation_permutation(self):
        assert orientation_flip_permutation(8).tolist() == [0, 7, 6, 5, 4, 3, 2, 1]
        labels = torch.zeros(1, 8, 1, 3)
        labels[0, 2, 0, 0] = 1.0  # 45 degrees at the left
        flipped = torch.zeros(1, 8, 1, 3)
        flipped[0, 6, 0, 2] = 1.0  # 135 degrees at the right
        assert flip_consistency_loss(labels, flipped, channel_permutation=orientation_flip_permutation(8)).item() == 0

    def test_gradcheck(self):
        a = torch.randn(2, 2, 3, 4, dtype=torch.float64, requires_grad=True)
        b = torch.randn(2, 2, 3, 4, dtype=torch.float64, requires_grad=True)
        assert torch.autograd.gradcheck(lambda a, b: flip_consistency_loss(a, b, kind="l2"), (a, b))

    def test_exception(self):
        with pytest.raises(InputShapeError, match="output_flipped: expected"):
            flip_consistency_loss(torch.ones(1, 1, 2, 2), torch.ones(1, 1, 2, 3))
