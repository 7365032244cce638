"""The (R, t) sub-problem of PointSymm: Eqs. 7.10-7.15 against autograd."""

from __future__ import annotations

import pytest
import torch

from torchsym.manifolds import SpecialOrthogonal
from torchsym.optim import trust_region
from torchsym.pointset import transform as tf

DT = torch.float64


def setup(d: int, seed: int = 0):
    g = torch.Generator().manual_seed(seed)
    m = tf.rotation_manifold(d)
    x = m.random_point(generator=g)
    pts = torch.randn(25, d, generator=g, dtype=DT)
    mirrors = torch.randn(25, d, generator=g, dtype=DT)
    weights = (torch.rand(25, generator=g, dtype=DT) > 0.3).to(DT)
    return m, x, pts, mirrors, weights, g


def _max(a, b) -> float:
    return max(float((u - v).abs().max()) for u, v in zip(a, b))


class TestReflectionCost:
    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_equals_pointwise(self, d):
        _, x, pts, mirrors, w, _ = setup(d)
        st = tf.pair_statistics(pts, mirrors, w)
        assert abs(float(tf.reflection_cost(x, st) - tf.symmetry_error(pts, mirrors, w, x))) < 1e-10


class TestEgrad:
    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_matches_autograd(self, d):
        _, x, pts, mirrors, w, _ = setup(d, 1)
        st = tf.pair_statistics(pts, mirrors, w)
        leaf = tuple(v.clone().requires_grad_(True) for v in x)
        auto = torch.autograd.grad(tf.reflection_cost(leaf, st), leaf)
        assert _max(auto, tf.egrad(x, st)) < 1e-10

    @pytest.mark.parametrize("d", [2, 3, 5])
    def test_riemannian_matches_pointwise_autograd(self, d):
        # the Riemannian gradient is intrinsic: it must agree with autograd of the point-by-point cost
        m, x, pts, mirrors, w, _ = setup(d, 2)
        st = tf.pair_statistics(pts, mirrors, w)
        leaf = tuple(v.clone().requires_grad_(True) for v in x)
        auto = torch.autograd.grad(tf.symmetry_error(pts, mirrors, w, leaf), leaf)
        assert _max(m.egrad2rgrad(x, auto), m.egrad2rgrad(x, tf.egrad(x, st))) < 1e-10

    @pytest.mark.parametrize("d", [2, 3, 4])
    def test_thesis_eq_7_13(self, d):
        # Eq. 7.13 is the projection of Eq. 7.11 onto the tangent space of SO(d) at R_j
        _, x, pts, mirrors, w, _ = setup(d, 3)
        st = tf.pair_statistics(pts, mirrors, w)
        so = SpecialOrthogonal(d)
        ours = tf.egrad(x, st)
        thesis = tf.thesis_rgrad(x, st)
        assert _max([so.proju(r, g) for r, g in zip(x[:-1], ours[:-1])], thesis[:-1]) < 1e-10
        assert float((ours[-1] - thesis[-1]).abs().max()) < 1e-12


class TestEhess:
    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_matches_autograd(self, d):
        _, x, pts, mirrors, w, g = setup(d, 4)
        st = tf.pair_statistics(pts, mirrors, w)
        u = tuple(torch.randn(v.shape, generator=g, dtype=DT) for v in x)
        leaf = tuple(v.clone().requires_grad_(True) for v in x)
        grad = torch.autograd.grad(tf.reflection_cost(leaf, st), leaf, create_graph=True)
        auto = torch.autograd.grad(grad, leaf, grad_outputs=u)
        assert _max(auto, tf.ehess(x, u, st)) < 1e-9

    @pytest.mark.parametrize("d", [2, 3])
    def test_riemannian_matches_pointwise_autograd(self, d):
        m, x, pts, mirrors, w, g = setup(d, 5)
        st = tf.pair_statistics(pts, mirrors, w)
        u = m.random_tangent(x, generator=g)
        leaf = tuple(v.clone().requires_grad_(True) for v in x)
        grad = torch.autograd.grad(tf.symmetry_error(pts, mirrors, w, leaf), leaf, create_graph=True)
        auto_h = torch.autograd.grad(grad, leaf, grad_outputs=u)
        auto = m.ehess2rhess(x, tuple(v.detach() for v in grad), auto_h, u)
        ours = m.ehess2rhess(x, tf.egrad(x, st), tf.ehess(x, u, st), u)
        assert _max(auto, ours) < 1e-9

    @pytest.mark.parametrize("d, j", [(2, 0), (3, 0), (3, 1), (5, 2)])
    def test_thesis_eq_7_14(self, d, j):
        # each rotation's diagonal block on SO(d) is the thesis's Eq. 7.14
        _, x, pts, mirrors, w, g = setup(d, 7)
        st = tf.pair_statistics(pts, mirrors, w)
        so = SpecialOrthogonal(d)
        omega = torch.randn(d, d, generator=g, dtype=DT)
        omega = omega - omega.T
        u = tuple(x[k] @ omega if k == j else torch.zeros_like(x[k]) for k in range(d - 1)) + (torch.zeros(d, dtype=DT),)
        ours = so.ehess2rhess(x[j], tf.egrad(x, st)[j], tf.ehess(x, u, st)[j], u[j])
        assert float((ours - tf.thesis_rhess(x, j, omega, st)).abs().max()) < 1e-10

    def test_translation_block_eq_7_15(self):
        # with the rotations fixed, the t-block of the Hessian is 4 n (I - T E T^T) (Eq. 7.15)
        _, x, pts, mirrors, w, g = setup(3, 6)
        st = tf.pair_statistics(pts, mirrors, w)
        dt = torch.randn(3, generator=g, dtype=DT)
        u = (*(torch.zeros_like(r) for r in x[:-1]), dt)
        s = tf.reflection_from_rotations(x[:-1])
        expected = 4 * st.w * (torch.eye(3, dtype=DT) - s) @ dt
        assert float((tf.ehess(x, u, st)[-1] - expected).abs().max()) < 1e-10


class TestRotations:
    @pytest.mark.parametrize("d", [2, 3, 6, 8])
    def test_normal_roundtrip(self, d):
        n = torch.randn(d, generator=torch.Generator().manual_seed(d), dtype=DT)
        n = n / n.norm()
        rots = tf.rotations_from_normal(n)
        assert tf.rotation_manifold(d).check_point((*rots, torch.zeros(d, dtype=DT)))[0]
        assert abs(abs(float(tf.normal_from_rotations(rots) @ n)) - 1) < 1e-12


class TestSubproblem:
    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_trust_region_recovers_reflection(self, d):
        # exact mirrors: the trust region must find the planted plane from a nearby start
        g = torch.Generator().manual_seed(d)
        n = torch.randn(d, generator=g, dtype=DT)
        n = n / n.norm()
        pts = torch.randn(30, d, generator=g, dtype=DT)
        mirrors = pts - 2 * ((pts @ n) - 0.3)[:, None] * n
        st = tf.pair_statistics(pts, mirrors, torch.ones(30, dtype=DT))
        start = n + 0.1 * torch.randn(d, generator=g, dtype=DT)
        x0 = (*tf.rotations_from_normal(start), torch.zeros(d, dtype=DT))
        m = tf.rotation_manifold(d)
        res = trust_region(m, lambda v: tf.reflection_cost(v, st), x0, egrad=lambda v: tf.egrad(v, st), ehess=lambda v, u: tf.ehess(v, u, st))
        assert res.converged and res.cost < 1e-12
        assert abs(abs(float(tf.normal_from_rotations(res.x[:-1]) @ n)) - 1) < 1e-12
