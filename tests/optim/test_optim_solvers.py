"""Solver tests with known answers: Procrustes on SO(3), eigenspaces on Stiefel, Rayleigh quotient."""

from __future__ import annotations

import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.manifolds import (
    Euclidean,
    PlaneRotations,
    ProductManifold,
    SpecialOrthogonal,
    Stiefel,
)
from torchsym.optim import OptimResult, gradient_descent, trust_region

DT = torch.float64


def gen(seed: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


def procrustes(seed: int = 0, n: int = 3):
    g = gen(seed)
    q = SpecialOrthogonal(n).random_point(generator=g)
    a = torch.randn(n, 40, generator=g, dtype=DT)
    b = q @ a + 0.01 * torch.randn(n, 40, generator=g, dtype=DT)
    # closed form: R = U diag(1, .., det) V^T from the SVD of B A^T
    u, _, vh = torch.linalg.svd(b @ a.T)
    s = torch.ones(n, dtype=DT)
    s[-1] = torch.sign(torch.linalg.det(u @ vh))
    return a, b, u @ torch.diag(s) @ vh


def sym_matrix(seed: int, n: int) -> torch.Tensor:
    m = torch.randn(n, n, generator=gen(seed), dtype=DT)
    return m + m.T


SOLVERS = pytest.mark.parametrize("solver", [trust_region, gradient_descent], ids=["tr", "gd"])


class TestTrustRegion:
    def test_smoke(self):
        m = SpecialOrthogonal(3)
        res = trust_region(m, lambda r: (r**2).sum(), m.random_point(generator=gen(0)))
        assert isinstance(res, OptimResult)
        assert res.to_dict()["type"] == "OptimResult"

    @pytest.mark.parametrize("retraction", ["qr", "cayley", "polar", "exp"])
    def test_procrustes_so3(self, retraction):
        a, b, r_star = procrustes(1)
        m = SpecialOrthogonal(3, retraction)
        res = trust_region(m, lambda r: ((r @ a - b) ** 2).sum(), m.random_point(generator=gen(2)))
        assert res.converged and res.stop_reason == "grad_norm"
        assert (res.x - r_star).abs().max() < 1e-7

    def test_analytic_equals_autograd(self):
        a, b, r_star = procrustes(3)
        m = SpecialOrthogonal(3)
        x0 = m.random_point(generator=gen(4))
        cost = lambda r: ((r @ a - b) ** 2).sum()
        auto = trust_region(m, cost, x0)
        grad_only = trust_region(m, cost, x0, egrad=lambda r: 2 * (r @ a - b) @ a.T)
        full = trust_region(m, cost, x0, egrad=lambda r: 2 * (r @ a - b) @ a.T, ehess=lambda r, u: 2 * u @ a @ a.T)
        for res in (auto, grad_only, full):
            assert (res.x - r_star).abs().max() < 1e-7
        assert auto.iterations == full.iterations

    def test_leading_eigenspace_stiefel(self):
        mat = sym_matrix(5, 8)
        m = Stiefel(8, 3)
        res = trust_region(m, lambda x: -(x * (mat @ x)).sum(), m.random_point(generator=gen(6)))
        vals, vecs = torch.linalg.eigh(mat)
        assert abs(res.cost + vals[-3:].sum()) < 1e-9
        top = vecs[:, -3:]
        # same subspace: the projector onto span(x) equals the projector onto the top eigenvectors
        assert (res.x @ res.x.T - top @ top.T).abs().max() < 1e-6

    def test_rayleigh_quotient(self):
        mat = sym_matrix(7, 10)
        m = Stiefel(10, 1)
        res = trust_region(m, lambda x: (x * (mat @ x)).sum(), m.random_point(generator=gen(8)))
        vals, vecs = torch.linalg.eigh(mat)
        assert abs(res.cost - vals[0]) < 1e-10
        assert abs(abs(float(res.x[:, 0] @ vecs[:, 0])) - 1) < 1e-8

    def test_product_manifold(self):
        # rotate-then-translate fit on SO(2, 3) x SO(2, 3) x R^3
        m = ProductManifold(PlaneRotations(3, (0, 2)), PlaneRotations(3, (1, 2)), Euclidean(3))
        truth = m.random_point(generator=gen(9))
        pts = torch.randn(30, 3, generator=gen(10), dtype=DT)

        def apply(x):
            r1, r2, t = x
            return pts @ (r1 @ r2).T + t

        target = apply(truth)
        x0 = (m.manifolds[0].from_angle(m.manifolds[0].angle(truth[0]) + 0.3), truth[1], torch.zeros(3, dtype=DT))
        res = trust_region(m, lambda x: ((apply(x) - target) ** 2).sum(), x0)
        assert res.converged
        assert max(float((a - b).abs().max()) for a, b in zip(res.x, truth)) < 1e-7

    def test_batched_point(self):
        # three independent Procrustes problems solved as one point of SO(3)^3
        problems = [procrustes(s) for s in (11, 12, 13)]
        a = torch.stack([p[0] for p in problems])
        b = torch.stack([p[1] for p in problems])
        m = SpecialOrthogonal(3)
        res = trust_region(m, lambda r: ((r @ a - b) ** 2).sum(), m.random_point(3, generator=gen(14)))
        for i, p in enumerate(problems):
            assert (res.x[i] - p[2]).abs().max() < 1e-7

    def test_keeps_dtype_float32(self):
        a, b, r_star = procrustes(15)
        m = SpecialOrthogonal(3)
        res = trust_region(m, lambda r: ((r @ a.float() - b.float()) ** 2).sum(), m.random_point(generator=gen(16), dtype=torch.float32), min_grad_norm=1e-3)
        assert res.x.dtype == torch.float32 and (res.x.double() - r_star).abs().max() < 1e-3

    def test_max_iter(self):
        a, b, _ = procrustes(17)
        m = SpecialOrthogonal(3)
        res = trust_region(m, lambda r: ((r @ a - b) ** 2).sum(), m.random_point(generator=gen(18)), max_iter=1)
        assert res.stop_reason == "max_iter" and res.iterations == 1 and not res.converged

    def test_deterministic(self):
        a, b, _ = procrustes(19)
        m = SpecialOrthogonal(3)
        runs = [trust_region(m, lambda r: ((r @ a - b) ** 2).sum(), m.random_point(generator=gen(20))) for _ in range(2)]
        assert torch.equal(runs[0].x, runs[1].x)

    def test_exception_wrong_shape(self):
        m = SpecialOrthogonal(3)
        with pytest.raises(InputShapeError, match=r"x0: expected shape \(\.\.\., 3, 3\) for a point of SpecialOrthogonal\(n=3.*got \(2, 2\)"):
            trust_region(m, lambda r: (r**2).sum(), torch.eye(2, dtype=DT))

    def test_exception_off_manifold(self):
        m = SpecialOrthogonal(3)
        with pytest.raises(InputValueError, match="x0: not a point of SpecialOrthogonal.*orthogonal"):
            trust_region(m, lambda r: (r**2).sum(), 2 * torch.eye(3, dtype=DT))

    def test_exception_product_tuple(self):
        m = ProductManifold(Euclidean(2), Euclidean(3))
        with pytest.raises(InputShapeError, match="x0: component 1: expected shape"):
            trust_region(m, lambda x: (x[0] ** 2).sum(), (torch.zeros(2, dtype=DT), torch.zeros(2, dtype=DT)))

    def test_exception_settings(self):
        m = SpecialOrthogonal(3)
        x0 = torch.eye(3, dtype=DT)
        with pytest.raises(InputValueError, match="rho_prime"):
            trust_region(m, lambda r: (r**2).sum(), x0, rho_prime=0.5)
        with pytest.raises(InputValueError, match="max_iter"):
            trust_region(m, lambda r: (r**2).sum(), x0, max_iter=-1)
        with pytest.raises(InputShapeError, match="cost: expected a scalar tensor"):
            trust_region(m, lambda r: r, x0)


class TestGradientDescent:
    def test_procrustes(self):
        a, b, r_star = procrustes(21)
        m = SpecialOrthogonal(3)
        res = gradient_descent(m, lambda r: ((r @ a - b) ** 2).sum(), m.random_point(generator=gen(22)), min_grad_norm=1e-8)
        assert res.converged and (res.x - r_star).abs().max() < 1e-7

    def test_rayleigh_quotient(self):
        mat = sym_matrix(23, 6)
        m = Stiefel(6, 1)
        res = gradient_descent(m, lambda x: (x * (mat @ x)).sum(), m.random_point(generator=gen(24)), min_grad_norm=1e-8)
        assert abs(res.cost - float(torch.linalg.eigvalsh(mat)[0])) < 1e-9

    def test_egrad(self):
        a, b, r_star = procrustes(25)
        m = SpecialOrthogonal(3)
        res = gradient_descent(
            m, lambda r: ((r @ a - b) ** 2).sum(), m.random_point(generator=gen(26)), egrad=lambda r: 2 * (r @ a - b) @ a.T, min_grad_norm=1e-8
        )
        assert (res.x - r_star).abs().max() < 1e-7

    def test_exception(self):
        with pytest.raises(InputShapeError, match="x0: expected shape"):
            gradient_descent(Stiefel(4, 2), lambda x: (x**2).sum(), torch.zeros(4, 3, dtype=DT))
