import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.losses import orthogonality_loss


class TestOrthogonality:
    def test_zero_for_orthonormal(self):
        n = torch.eye(3).expand(2, 3, 3) * 5.0
        assert orthogonality_loss(n).abs().max() < 1e-12

    def test_value_by_hand(self):
        # two normals at 60 degrees: Gram off-diagonal 0.5 twice -> 0.5
        n = torch.tensor([[[1.0, 0.0], [0.5, 3**0.5 / 2]]], dtype=torch.float64)
        assert torch.allclose(orthogonality_loss(n), torch.tensor([0.5], dtype=torch.float64))

    def test_prsnet_form_for_three(self):
        # PRS-Net's |M M^T - I|_F^2 with the normals as columns equals the Gram form for K = D
        n = torch.randn(4, 3, 3, dtype=torch.float64)
        m = (n / n.norm(dim=-1, keepdim=True)).transpose(1, 2)
        theirs = ((m @ m.transpose(1, 2) - torch.eye(3, dtype=torch.float64)) ** 2).sum((1, 2))
        assert torch.allclose(orthogonality_loss(n), theirs)

    def test_plane_mask(self):
        n = torch.tensor([[[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]], dtype=torch.float64)
        assert orthogonality_loss(n, torch.tensor([[1, 1, 0]])).item() == pytest.approx(0.0)

    def test_gradcheck(self):
        n = torch.randn(2, 3, 4, dtype=torch.float64, requires_grad=True)
        assert torch.autograd.gradcheck(orthogonality_loss, (n,))

    def test_exception(self):
        with pytest.raises(InputShapeError, match="normal: expected a \\(B, K, D\\)"):
            orthogonality_loss(torch.ones(3, 3))
