import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.geometry import check_planes, planes_from_nerd, planes_from_prsnet, planes_to_nerd, planes_to_prsnet, reflect_points


def _planes(seed=0):
    g = torch.Generator().manual_seed(seed)
    n = torch.randn(4, 2, 3, generator=g, dtype=torch.float64)
    return n / n.norm(dim=-1, keepdim=True), torch.randn(4, 2, generator=g, dtype=torch.float64)


class TestConventions:
    def test_prsnet_round_trip(self):
        n, b = _planes()
        v = planes_to_prsnet(n, b)
        assert v.shape == (4, 2, 4)
        n2, b2 = planes_from_prsnet(3.0 * v)  # any scale of the 4-vector is the same plane
        assert torch.allclose(n2, n) and torch.allclose(b2, b)

    def test_prsnet_reflection_by_hand(self):
        # PRS-Net's planesymTransform: x - 2 (a.x + d) / |a| * a / |a|; plane (0, 0, 2, -1) is z = 0.5
        n, b = planes_from_prsnet(torch.tensor([0.0, 0.0, 2.0, -1.0], dtype=torch.float64))
        x = torch.tensor([[1.0, 2.0, 3.0]], dtype=torch.float64)
        assert torch.allclose(reflect_points(x, n, b), torch.tensor([[1.0, 2.0, -2.0]], dtype=torch.float64))

    def test_nerd_round_trip(self):
        n, b = _planes(1)
        w = planes_to_nerd(n, b)
        n2, b2 = planes_from_nerd(w)
        sign = torch.sign(b).unsqueeze(-1)  # NeRD's form has offset > 0: the plane is the same up to sign
        assert torch.allclose(n2, n * sign) and torch.allclose(b2, b.abs())

    def test_nerd_reflection_matches_w2S(self):
        # NeRD's w2S: x - 2 w (w.x + 1) / |w|^2 (zhou13/nerd sym/datasets.py)
        w = torch.tensor([0.3, -0.2, 0.5], dtype=torch.float64)
        x = torch.randn(5, 3, dtype=torch.float64)
        theirs = x - 2 * ((x @ w) + 1).unsqueeze(-1) * w / (w @ w)
        n, b = planes_from_nerd(w)
        assert torch.allclose(reflect_points(x, n, b), theirs)

    def test_gradcheck(self):
        v = torch.randn(3, 4, dtype=torch.float64, requires_grad=True)
        assert torch.autograd.gradcheck(planes_from_prsnet, (v,))
        w = torch.randn(3, 3, dtype=torch.float64, requires_grad=True)
        assert torch.autograd.gradcheck(planes_from_nerd, (w,))
        n = torch.randn(3, 3, dtype=torch.float64, requires_grad=True)
        b = torch.rand(3, dtype=torch.float64).add(0.5).requires_grad_()
        assert torch.autograd.gradcheck(planes_to_nerd, (n, b))
        assert torch.autograd.gradcheck(planes_to_prsnet, (n, b))

    def test_exception(self):
        with pytest.raises(InputShapeError, match="plane: expected"):
            planes_from_prsnet(torch.ones(1))
        with pytest.raises(InputShapeError, match="offset: expected"):
            check_planes(torch.ones(2, 3, 3), torch.ones(2, 2))
        with pytest.raises(InputShapeError, match="normal: expected \\(B, K, 2\\)"):
            check_planes(torch.ones(2, 3, 3), torch.ones(2, 3), 2)
