import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.geometry import cluster_planes, pair_planes, plane_vote_distance, reflect_points


class TestPairPlanes:
    def test_reflects_each_pair(self):
        g = torch.Generator().manual_seed(0)
        p, q = torch.randn(2, 7, 3, generator=g, dtype=torch.float64), torch.randn(2, 7, 3, generator=g, dtype=torch.float64)
        n, b = pair_planes(p, q)
        assert n.shape == (2, 7, 3) and b.shape == (2, 7)
        assert torch.allclose(reflect_points(p.unsqueeze(-2), n, b).squeeze(-2), q)

    def test_value_by_hand(self):
        # E3Sym: n = normalize(q - p), d = -n . (p + q) / 2; p = (1, 0), q = (3, 0) -> n = (1, 0), d = -2
        n, b = pair_planes(torch.tensor([[1.0, 0.0]]), torch.tensor([[3.0, 0.0]]))
        assert n.tolist() == [[1.0, 0.0]] and b.tolist() == [-2.0]

    def test_gradcheck(self):
        p = torch.randn(5, 3, dtype=torch.float64, requires_grad=True)
        q = torch.randn(5, 3, dtype=torch.float64, requires_grad=True)
        assert torch.autograd.gradcheck(pair_planes, (p, q))


class TestClusterPlanes:
    def test_sign_invariant(self):
        n = torch.tensor([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
        b = torch.tensor([0.3, -0.3])
        assert plane_vote_distance(n, b)[0, 1] < 1e-6

    def test_two_planes_from_noisy_votes(self):
        g = torch.Generator().manual_seed(1)
        true_n = torch.tensor([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
        true_b = torch.tensor([0.1, -0.2])
        which = torch.tensor([0] * 30 + [1] * 20)
        sign = torch.where(torch.rand(50, generator=g) < 0.5, -1.0, 1.0)
        n = true_n[which] + 0.01 * torch.randn(50, 3, generator=g)
        n = n / n.norm(dim=-1, keepdim=True) * sign.unsqueeze(-1)
        b = (true_b[which] + 0.005 * torch.randn(50, generator=g)) * sign
        out = cluster_planes(n, b, radius=0.1)
        assert out.normal.shape == (2, 3) and out.size.tolist() == [30, 20]
        for k in range(2):
            s = torch.sign(out.normal[k] @ true_n[k])
            assert torch.allclose(out.normal[k] * s, true_n[k], atol=0.01)
            assert abs(float(out.offset[k] * s - true_b[k])) < 0.01
        assert (out.labels[:30] == 0).all() and (out.labels[30:] == 1).all()

    def test_min_size(self):
        n = torch.tensor([[1.0, 0.0], [0.0, 1.0], [0.0, 1.0]])
        out = cluster_planes(n, torch.zeros(3), min_size=2)
        assert out.size.tolist() == [2] and out.labels.tolist() == [-1, 0, 0]

    def test_exception(self):
        with pytest.raises(InputValueError, match="radius: expected"):
            cluster_planes(torch.ones(2, 2), torch.zeros(2), radius=0)
