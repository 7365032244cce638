import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.losses import nearest_neighbours, robust_kernel, symmetry_distance


def _cloud(b=2, n=40, d=3, seed=0, dtype=torch.float64):
    g = torch.Generator().manual_seed(seed)
    half = torch.randn(b, n // 2, d, generator=g, dtype=dtype)
    mirror = half.clone()
    mirror[..., 0] = -mirror[..., 0]
    return torch.cat([half, mirror], 1)  # symmetric about x = 0


def _planes(b=2, k=3, d=3, seed=1, dtype=torch.float64):
    g = torch.Generator().manual_seed(seed)
    return torch.randn(b, k, d, generator=g, dtype=dtype), 0.1 * torch.randn(b, k, generator=g, dtype=dtype)


class TestSymmetryDistance:
    def test_smoke(self):
        p = _cloud()
        n, b = _planes()
        out = symmetry_distance(p, n, b)
        assert out.shape == (2, 3) and (out >= 0).all()

    def test_zero_at_true_plane(self):
        p = _cloud()
        n = torch.tensor([1.0, 0.0, 0.0], dtype=p.dtype).expand(2, 1, 3)
        assert symmetry_distance(p, n, torch.zeros(2, 1, dtype=p.dtype)).abs().max() < 1e-12

    def test_value_by_hand(self):
        # points (0,0), (2,0), (0,3); plane x = 0.5 (n = (1,0), b = -0.5):
        # reflections (1,0) -> nearest (0,0) or (2,0): 1; (-1,0) -> (0,0): 1; (1,3) -> (0,3): 1
        p = torch.tensor([[[0.0, 0.0], [2.0, 0.0], [0.0, 3.0]]], dtype=torch.float64)
        n = torch.tensor([[[2.0, 0.0]]], dtype=torch.float64)  # any length
        b = torch.tensor([[-1.0]], dtype=torch.float64)  # 2x - 1 = 0
        assert torch.allclose(symmetry_distance(p, n, b), torch.tensor([[1.0]], dtype=torch.float64))
        assert torch.allclose(symmetry_distance(p, n, b, kind="truncated", threshold=0.5), torch.tensor([[0.25]], dtype=torch.float64))
        assert torch.allclose(symmetry_distance(p, n, b, kind="robust", threshold=1.0), torch.tensor([[0.5]], dtype=torch.float64))

    def test_e3sym_chamfer_is_twice(self):
        # E3Sym: pytorch3d chamfer_distance(S P, P) = mean_i min_j |S p_i - p_j|^2 + mean_j min_i |p_j - S p_i|^2
        p = _cloud(1, 30, 3, seed=3)
        n, b = _planes(1, 1, 3, seed=4)
        nn_ = n / n.norm(dim=-1, keepdim=True)
        bb = b / n.norm(dim=-1)
        q = p - 2 * ((p * nn_).sum(-1, keepdim=True) + bb.unsqueeze(-1)) * nn_
        d2 = torch.cdist(q[0], p[0]) ** 2
        chamfer = d2.min(1).values.mean() + d2.min(0).values.mean()
        assert torch.allclose(2 * symmetry_distance(p, n, b)[0, 0], chamfer)

    def test_mask_equals_unpadded(self):
        p = _cloud(1, 20)
        n, b = _planes(1, 2)
        pad = torch.cat([p, 100 + torch.randn(1, 7, 3, dtype=p.dtype)], 1)
        mask = torch.cat([torch.ones(1, 20), torch.zeros(1, 7)], 1)
        for method in ("tree", "brute"):
            assert torch.allclose(symmetry_distance(pad, n, b, mask, method=method), symmetry_distance(p, n, b))

    def test_tree_equals_brute(self):
        p = _cloud(3, 60, 4, seed=5)
        n, b = _planes(3, 2, 4, seed=6)
        assert torch.allclose(symmetry_distance(p, n, b, method="tree"), symmetry_distance(p, n, b, method="brute"))

    def test_gradient_equals_dense(self):
        # the gradient with the index found without gradient equals that of a dense cdist + min
        p = _cloud(1, 30, 3, seed=7).requires_grad_()
        n, b = _planes(1, 2, 3, seed=8)
        n.requires_grad_(), b.requires_grad_()
        g1 = torch.autograd.grad(symmetry_distance(p, n, b).sum(), (p, n, b))
        nn_ = n / n.norm(dim=-1, keepdim=True)
        bb = b / n.norm(dim=-1)
        q = p.unsqueeze(1) - 2 * (torch.einsum("bnd,bkd->bkn", p, nn_) + bb.unsqueeze(-1)).unsqueeze(-1) * nn_.unsqueeze(2)
        dense = (torch.cdist(q[0], p[0].expand(2, -1, -1)) ** 2).min(-1).values.mean(-1).sum()
        g2 = torch.autograd.grad(dense, (p, n, b))
        for a, c in zip(g1, g2):
            assert torch.allclose(a, c, atol=1e-10)

    @pytest.mark.parametrize("kind", ["l2", "truncated", "robust"])
    def test_gradcheck(self, kind):
        p = _cloud(1, 10, 3, seed=9).requires_grad_()
        n, b = _planes(1, 2, 3, seed=10)
        n.requires_grad_(), b.requires_grad_()
        assert torch.autograd.gradcheck(lambda p, n, b: symmetry_distance(p, n, b, kind=kind, threshold=0.7), (p, n, b))

    def test_bfloat16(self):
        p = _cloud(2, 40, 3, dtype=torch.float32)
        n, b = _planes(2, 3, dtype=torch.float32)
        ref = symmetry_distance(p, n, b)
        out = symmetry_distance(p.bfloat16(), n.bfloat16(), b.bfloat16())
        assert out.dtype == torch.bfloat16
        assert torch.allclose(out.float(), ref, rtol=0.1, atol=0.02)

    def test_any_dimension(self):
        p = _cloud(1, 30, 2)
        n = torch.tensor([[[1.0, 0.0]]], dtype=p.dtype)
        assert symmetry_distance(p, n, torch.zeros(1, 1, dtype=p.dtype)).abs().max() < 1e-12

    def test_reduction(self):
        p = _cloud()
        n, b = _planes()
        full = symmetry_distance(p, n, b)
        assert torch.allclose(symmetry_distance(p, n, b, reduction="mean"), full.mean())
        assert torch.allclose(symmetry_distance(p, n, b, reduction="sum"), full.sum())

    @pytest.mark.slow
    def test_compiled(self):
        # one graph, no break: under torch.compile the search is brute force on the device
        p = _cloud(2, 40, 3, dtype=torch.float32)
        n, b = _planes(2, 3, dtype=torch.float32)
        n.requires_grad_()
        fn = torch.compile(symmetry_distance, backend="eager", fullgraph=True)
        out = fn(p, n, b)
        out.sum().backward()
        assert torch.allclose(out, symmetry_distance(p, n, b), atol=1e-6)
        assert n.grad is not None and torch.isfinite(n.grad).all()

    def test_exception(self):
        p = _cloud()
        n, b = _planes()
        with pytest.raises(InputShapeError, match="points: expected a floating"):
            symmetry_distance(p[0], n, b)
        with pytest.raises(InputShapeError, match="offset: expected"):
            symmetry_distance(p, n, b[:, :1])
        with pytest.raises(InputShapeError, match="mask: expected"):
            symmetry_distance(p, n, b, torch.ones(2, 3))
        with pytest.raises(InputValueError, match="kind: expected"):
            symmetry_distance(p, n, b, kind="l3")
        with pytest.raises(InputValueError, match="reduction: expected"):
            symmetry_distance(p, n, b, reduction="avg")
        with pytest.raises(InputValueError, match="method: expected"):
            nearest_neighbours(p, p, method="x")
        with pytest.raises(InputValueError, match="kind: expected"):
            robust_kernel(torch.ones(1), "x", 1.0)
