import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.losses import closest_point_grid, grid_cell_index, occupancy_grid, prsnet_symmetry_loss


def _shape(b=2, n=200, seed=0, dtype=torch.float64):
    g = torch.Generator().manual_seed(seed)
    half = 0.35 * torch.rand(b, n // 2, 3, generator=g, dtype=dtype) * torch.tensor([1.0, 2.0, 2.0], dtype=dtype) - torch.tensor(
        [0.0, 0.35, 0.35], dtype=dtype
    )
    mirror = half * torch.tensor([-1.0, 1.0, 1.0], dtype=dtype)
    return torch.cat([half, mirror], 1)  # symmetric about x = 0, inside [-0.5, 0.5]^3


class _PRSNetDistance(torch.autograd.Function):
    """The custom Function of PRS-Net (IGLICT/PRS-Net models/network.py, calDistence),
    re-derived from its formula: forward mean_b sum_i |q - cp|^2 (1 - occ), backward 2 (q - cp)(1 - occ) / B."""

    @staticmethod
    def forward(ctx, q, cp_grid, occ, g):
        b = q.shape[0]
        idx = grid_cell_index(q, g)
        flat = idx[..., 0] * g * g + idx[..., 1] * g + idx[..., 2]
        free = 1 - torch.gather(occ.reshape(b, -1), 1, flat)
        cp = torch.gather(cp_grid.reshape(b, -1, 3), 1, flat.unsqueeze(-1).expand(-1, -1, 3))
        dist = (q - cp) * free.unsqueeze(-1)
        ctx.save_for_backward(dist)
        return (dist**2).sum((1, 2)).mean()

    @staticmethod
    def backward(ctx, grad):
        (dist,) = ctx.saved_tensors
        return 2 * dist / dist.shape[0], None, None, None


def _reflect(p, n, b):
    nn_ = n / n.norm(dim=-1, keepdim=True)
    return p - 2 * ((p * nn_.unsqueeze(1)).sum(-1, keepdim=True) + (b / n.norm(dim=-1)).view(-1, 1, 1)) * nn_.unsqueeze(1)


class TestPRSNetLoss:
    def test_smoke(self):
        p = _shape()
        cp, occ = closest_point_grid(p, 16), occupancy_grid(p, 16)
        assert cp.shape == (2, 16, 16, 16, 3) and occ.shape == (2, 16, 16, 16)
        n = torch.randn(2, 3, 3, dtype=p.dtype)
        out = prsnet_symmetry_loss(p, n, torch.zeros(2, 3, dtype=p.dtype), cp, occ)
        assert out.shape == (2, 3) and (out >= 0).all()

    def test_zero_at_true_plane(self):
        p = _shape()
        cp, occ = closest_point_grid(p, 16), occupancy_grid(p, 16)
        n = torch.tensor([1.0, 0.0, 0.0], dtype=p.dtype).expand(2, 1, 3)
        assert prsnet_symmetry_loss(p, n, torch.zeros(2, 1, dtype=p.dtype), cp, occ).abs().max() < 1e-12

    def test_cell_index_by_hand(self):
        # G = 4, bound 0.5: centres -0.375, -0.125, 0.125, 0.375; 0.2 -> cell 2, -0.9 clamps to 0, 0.49 -> 3
        idx = grid_cell_index(torch.tensor([[0.2, -0.9, 0.49]]), 4)
        assert idx.tolist() == [[2, 0, 3]]

    def test_value_by_hand(self):
        # one point (0.3, 0, 0), plane x = 0: q = (-0.3, 0, 0); G = 2 cells per axis, centres +-0.25;
        # q falls in cell (0, 1, 1) [round(clamp((q + 0.25) * 2, 0, 1))]: (-0.05*2 -> 0, 0.5 -> round half even 0)
        p = torch.tensor([[[0.3, 0.0, 0.0]]], dtype=torch.float64)
        cp = torch.zeros(1, 2, 2, 2, 3, dtype=torch.float64)
        cp[0, 0, 0, 0] = torch.tensor([-0.25, 0.1, 0.0], dtype=torch.float64)
        occ = torch.zeros(1, 2, 2, 2, dtype=torch.float64)
        n = torch.tensor([[[1.0, 0.0, 0.0]]], dtype=torch.float64)
        out = prsnet_symmetry_loss(p, n, torch.zeros(1, 1, dtype=torch.float64), cp, occ)
        assert torch.allclose(out, torch.tensor([[0.05**2 + 0.1**2]], dtype=torch.float64))
        occ[0, 0, 0, 0] = 1.0  # an occupied cell costs nothing
        assert prsnet_symmetry_loss(p, n, torch.zeros(1, 1, dtype=torch.float64), cp, occ).item() == 0.0

    def test_custom_backward_equals_autograd(self):
        p = _shape(2, 100, seed=1)
        cp, occ = closest_point_grid(p, 8), occupancy_grid(p, 8)
        g = torch.Generator().manual_seed(2)
        n = torch.randn(2, 1, 3, generator=g, dtype=p.dtype, requires_grad=True)
        b = (0.05 * torch.randn(2, 1, generator=g, dtype=p.dtype)).requires_grad_()
        ours = prsnet_symmetry_loss(p, n, b, cp, occ).sum(-1).mean()
        theirs = _PRSNetDistance.apply(_reflect(p, n[:, 0], b[:, 0]), cp, occ, 8)
        assert torch.allclose(ours, theirs)
        g_ours = torch.autograd.grad(ours, (n, b))
        g_theirs = torch.autograd.grad(theirs, (n, b))
        for a, c in zip(g_ours, g_theirs):
            assert torch.allclose(a, c, atol=1e-12)

    def test_gradcheck(self):
        p = _shape(1, 20, seed=3)
        cp, occ = closest_point_grid(p, 6), occupancy_grid(p, 6)
        n = torch.tensor([[[0.9, 0.3, 0.1]]], dtype=p.dtype, requires_grad=True)
        b = torch.tensor([[0.03]], dtype=p.dtype, requires_grad=True)
        assert torch.autograd.gradcheck(lambda p, n, b: prsnet_symmetry_loss(p, n, b, cp, occ), (p.requires_grad_(), n, b))

    def test_mask(self):
        p = _shape(1, 40, seed=4)
        pad = torch.cat([p, torch.zeros(1, 5, 3, dtype=p.dtype)], 1)
        mask = torch.cat([torch.ones(1, 40), torch.zeros(1, 5)], 1)
        cp, occ = closest_point_grid(pad, 8, mask=mask), occupancy_grid(pad, 8, mask=mask)
        assert torch.equal(cp, closest_point_grid(p, 8)) and torch.equal(occ, occupancy_grid(p, 8))
        n = torch.randn(1, 2, 3, dtype=p.dtype)
        b = torch.zeros(1, 2, dtype=p.dtype)
        assert torch.allclose(prsnet_symmetry_loss(pad, n, b, cp, occ, mask), prsnet_symmetry_loss(p, n, b, cp, occ))

    def test_exception(self):
        p = _shape()
        cp, occ = closest_point_grid(p, 4), occupancy_grid(p, 4)
        n, b = torch.randn(2, 1, 3, dtype=p.dtype), torch.zeros(2, 1, dtype=p.dtype)
        with pytest.raises(InputShapeError, match="occupancy: expected"):
            prsnet_symmetry_loss(p, n, b, cp, occ[:, 0])
        with pytest.raises(InputShapeError, match="closest_points: expected"):
            prsnet_symmetry_loss(p, n, b, cp[..., :2], occ)


def test_bfloat16():
    p = _shape(2, 100, dtype=torch.float32)
    cp, occ = closest_point_grid(p, 8), occupancy_grid(p, 8)
    n, b = torch.randn(2, 2, 3), torch.zeros(2, 2)
    ref = prsnet_symmetry_loss(p, n, b, cp, occ)
    bf = torch.bfloat16
    out = prsnet_symmetry_loss(p.to(bf), n.to(bf), b.to(bf), cp.to(bf), occ.to(bf))
    assert out.dtype == bf and torch.allclose(out.float(), ref, rtol=0.1, atol=0.05)
