import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.losses import field_symmetry_loss


def _sdf_sphere(x):  # symmetric about every plane through the origin
    return x.norm(dim=-1) - 0.5


def _sdf_shifted(x):  # sphere centred at (0.2, 0, 0)
    return (x - torch.tensor([0.2, 0.0, 0.0], dtype=x.dtype)).norm(dim=-1) - 0.5


class TestFieldSymmetry:
    def test_zero_for_symmetric_field(self):
        x = torch.randn(2, 30, 3, dtype=torch.float64)
        n, b = torch.randn(2, 3, 3, dtype=torch.float64), torch.zeros(2, 3, dtype=torch.float64)
        assert field_symmetry_loss(_sdf_sphere, x, n, b).abs().max() < 1e-12

    def test_value_by_hand(self):
        # f(x) = x_1 (linear), plane x_1 = 0: f(Sx) = -x_1, |f(x) - f(Sx)|^2 = 4 x_1^2
        x = torch.tensor([[[1.0, 0.0], [2.0, 5.0]]], dtype=torch.float64)
        n, b = torch.tensor([[[1.0, 0.0]]], dtype=torch.float64), torch.zeros(1, 1, dtype=torch.float64)
        out = field_symmetry_loss(lambda p: p[..., 0], x, n, b)
        assert torch.allclose(out, torch.tensor([[(4 + 16) / 2]], dtype=torch.float64))
        assert torch.allclose(field_symmetry_loss(lambda p: p[..., 0], x, n, b, kind="l1"), torch.tensor([[3.0]], dtype=torch.float64))

    def test_channels_and_mask(self):
        x = torch.randn(1, 10, 3, dtype=torch.float64)
        mask = torch.zeros(1, 10)
        mask[0, :4] = 1
        n, b = torch.randn(1, 2, 3, dtype=torch.float64), torch.zeros(1, 2, dtype=torch.float64)
        two = field_symmetry_loss(lambda p: torch.stack([_sdf_shifted(p), p[..., 1]], -1), x, n, b, mask)
        ref = field_symmetry_loss(lambda p: torch.stack([_sdf_shifted(p), p[..., 1]], -1), x[:, :4], n, b)
        assert torch.allclose(two, ref)

    def test_stop_gradient(self):
        x = torch.randn(1, 5, 3, dtype=torch.float64)
        n = torch.randn(1, 1, 3, dtype=torch.float64, requires_grad=True)
        b = torch.zeros(1, 1, dtype=torch.float64)
        # the plane only enters through the mirrored value: with that as a target, no gradient reaches it
        assert not field_symmetry_loss(_sdf_shifted, x, n, b, stop_gradient="mirror").requires_grad
        assert field_symmetry_loss(_sdf_shifted, x, n, b, stop_gradient="source").requires_grad

    def test_gradcheck(self):
        x = torch.randn(1, 6, 3, dtype=torch.float64, requires_grad=True)
        n = torch.randn(1, 2, 3, dtype=torch.float64, requires_grad=True)
        b = torch.randn(1, 2, dtype=torch.float64, requires_grad=True)
        assert torch.autograd.gradcheck(lambda x, n, b: field_symmetry_loss(_sdf_shifted, x, n, b), (x, n, b))

    def test_exception(self):
        x = torch.randn(1, 5, 3)
        n, b = torch.randn(1, 1, 3), torch.zeros(1, 1)
        with pytest.raises(InputValueError, match="stop_gradient: expected"):
            field_symmetry_loss(_sdf_sphere, x, n, b, stop_gradient="both")
        with pytest.raises(InputShapeError, match="field: expected outputs"):
            field_symmetry_loss(lambda p: p.sum(), x, n, b)
