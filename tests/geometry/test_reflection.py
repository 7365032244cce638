import math

import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.geometry import (
    angles_to_normal,
    normal_to_angles,
    pair_fit_errors,
    plane_angle,
    plane_distance,
    plane_from_pairs,
    plane_from_reflection,
    point_plane_distance,
    reflect_points,
    reflection_matrix,
    reflection_fit,
    reflection_matrix_from_angles,
    reflection_transform,
    spread_normals,
)


def _rand(*shape, seed=0):
    return torch.randn(*shape, generator=torch.Generator().manual_seed(seed), dtype=torch.float64)


class TestReflectPoints:
    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_involution(self, d):
        x, n, b = _rand(5, d), _rand(d, seed=1), _rand((), seed=2)
        assert torch.allclose(reflect_points(reflect_points(x, n, b), n, b), x, atol=1e-12)

    def test_fixes_plane_and_flips_distance(self):
        x, n, b = _rand(7, 3), _rand(3, seed=3), _rand((), seed=4)
        y = reflect_points(x, n, b)
        assert torch.allclose(point_plane_distance(y, n, b), -point_plane_distance(x, n, b), atol=1e-12)
        assert torch.allclose(0.5 * (x + y) @ (n / n.norm()) + b / n.norm(), torch.zeros(7, dtype=torch.float64), atol=1e-12)

    def test_batch_equals_loop(self):
        x, n, b = _rand(4, 6, 3), _rand(4, 3, seed=1), _rand(4, seed=2)
        batched = reflect_points(x, n, b)
        for i in range(4):
            assert torch.allclose(batched[i], reflect_points(x[i], n[i], b[i]))

    def test_matrix_forms(self):
        n, b = _rand(3), _rand((), seed=1)
        s = reflection_matrix(n)
        assert torch.allclose(s @ s.T, torch.eye(3, dtype=torch.float64), atol=1e-12)
        assert torch.allclose(torch.det(s), torch.tensor(-1.0, dtype=torch.float64))
        assert torch.allclose(s, s.T)
        x = _rand(5, 3, seed=2)
        h = reflection_transform(n, b)
        xh = torch.cat([x, torch.ones(5, 1, dtype=torch.float64)], 1) @ h.T
        assert torch.allclose(xh[:, :3], reflect_points(x, n, b))

    def test_gradcheck(self):
        x = _rand(4, 3).requires_grad_()
        n = _rand(3, seed=1).requires_grad_()
        b = _rand((), seed=2).requires_grad_()
        assert torch.autograd.gradcheck(reflect_points, (x, n, b))

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"points: expected \(\.\.\., N, 3\) to match normal"):
            reflect_points(torch.zeros(4, 2), torch.ones(3))
        with pytest.raises(InputValueError, match="normal: expected a non-zero vector"):
            reflect_points(torch.zeros(4, 3), torch.zeros(3))


class TestPlaneFromPairs:
    @pytest.mark.parametrize("d", [2, 3, 5])
    def test_exact_pairs(self, d):
        n = _rand(d)
        n = n / n.norm()
        b = _rand((), seed=1)
        p = _rand(30, d, seed=2)
        q = reflect_points(p, n, b)
        for constraint, lam in (("normal", 0.25), ("plane", 1.0)):
            n2, b2 = plane_from_pairs(p, q, constraint=constraint, lam=lam)
            sign = torch.sign((n2 * n).sum())
            assert torch.allclose(n2 * sign, n, atol=1e-9) and torch.allclose(b2 * sign, b, atol=1e-9)

    def test_least_squares_energy(self):
        # with lam = 1/4 the energy is exactly 1/4 sum |reflect(p) - q|^2: no plane does better
        p, q = _rand(40, 3), _rand(40, 3, seed=1)
        n, b = plane_from_pairs(p, q)
        best = (reflect_points(p, n, b) - q).pow(2).sum()
        for seed in range(20):
            m = n + 0.05 * _rand(3, seed=10 + seed)
            assert (reflect_points(p, m, b) - q).pow(2).sum() >= best - 1e-9

    def test_translation_invariant(self):
        p, q = _rand(20, 3), _rand(20, 3, seed=1)
        t = torch.tensor([5.0, -3.0, 2.0], dtype=torch.float64)
        n1, b1 = plane_from_pairs(p, q)
        n2, b2 = plane_from_pairs(p + t, q + t)
        assert torch.allclose(n1, n2, atol=1e-9) and torch.allclose(b2, b1 - (n1 * t).sum(), atol=1e-9)

    def test_weights_drop_pairs(self):
        n = torch.tensor([0.0, 1.0, 0.0], dtype=torch.float64)
        p = _rand(10, 3)
        q = reflect_points(p, n, torch.tensor(0.0, dtype=torch.float64))
        q[:3] = _rand(3, 3, seed=9)  # three wrong pairs
        w = torch.ones(10, dtype=torch.float64)
        w[:3] = 0
        n2, _ = plane_from_pairs(p, q, w)
        assert float(plane_angle(n2, n)) < 1e-9

    def test_gradcheck(self):
        p = _rand(6, 3).requires_grad_()
        q = (reflect_points(p.detach(), torch.tensor([1.0, 0.2, 0.1], dtype=torch.float64)) + 0.1 * _rand(6, 3, seed=5)).requires_grad_()
        assert torch.autograd.gradcheck(lambda a, c: plane_from_pairs(a, c)[0], (p, q))

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"mirrors: expected the same \(\.\.\., N, D\) shape as points"):
            plane_from_pairs(torch.zeros(4, 3), torch.zeros(5, 3))
        with pytest.raises(InputValueError, match="constraint: expected 'normal' or 'plane'"):
            plane_from_pairs(torch.zeros(4, 3), torch.zeros(4, 3), constraint="x")


class TestAnglesAndConversions:
    def test_plane_angle_unoriented(self):
        a = torch.tensor([1.0, 0.0, 0.0])
        assert float(plane_angle(a, -a)) == 0.0
        assert math.isclose(float(plane_angle(a, torch.tensor([1.0, 1.0, 0.0]))), math.pi / 4, rel_tol=1e-6)
        assert math.isclose(float(plane_angle(a, -a, oriented=True)), math.pi, rel_tol=1e-6)

    def test_plane_angle_small_accurate(self):
        a = torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64)
        b = torch.tensor([1.0, 1e-9, 0.0], dtype=torch.float64)
        assert math.isclose(float(plane_angle(a, b)), 1e-9, rel_tol=1e-6)

    def test_plane_distance(self):
        x = torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64)
        # parallel planes x = 1 and x = 3 (one given with a flipped, scaled normal): 2 apart from anywhere
        d = plane_distance(x, torch.tensor(-1.0), -2 * x, torch.tensor(6.0), point=_rand(3))
        assert math.isclose(float(d), 2.0, rel_tol=1e-12)
        # planes crossing on the z axis: 0 on it, growing with the distance from it
        y = torch.tensor([math.sin(0.1), math.cos(0.1), 0.0], dtype=torch.float64)
        assert float(plane_distance(x, 0.0, y, 0.0, point=torch.tensor([0.0, 0.0, 5.0], dtype=torch.float64))) < 1e-12
        far = plane_distance(x, 0.0, y, 0.0, point=torch.tensor([0.0, 10.0, 0.0], dtype=torch.float64))
        # the point lies on plane a, 10 cos(0.1) from plane b; its foot on b is 10 cos(0.1) sin(0.1) from a
        assert math.isclose(float(far), 0.5 * (10 * math.cos(0.1) + 10 * math.cos(0.1) * math.sin(0.1)), rel_tol=1e-9)
        # batched, any dimension, differentiable
        na, nb = _rand(4, 5, seed=1).requires_grad_(), _rand(4, 5, seed=2)
        out = plane_distance(na, _rand(4, seed=3), nb, _rand(4, seed=4))
        assert out.shape == (4,)
        out.sum().backward()
        assert na.grad is not None and torch.isfinite(na.grad).all()
        with pytest.raises(InputShapeError, match="normal_b: expected"):
            plane_distance(x, 0.0, torch.ones(2), 0.0)
        with pytest.raises(InputShapeError, match="point: expected"):
            plane_distance(x, 0.0, x, 0.0, point=torch.ones(2))
        with pytest.raises(InputShapeError, match="point: expected"):
            plane_distance(x, 0.0, x, 0.0, point=[0.0, 0.0, 0.0])
        with pytest.raises(InputValueError, match="normal_b: expected non-zero normals"):
            plane_distance(x, 0.0, torch.zeros(3), 0.0)

    def test_eq_5_1_round_trip(self):
        tx, ty = torch.tensor([0.3, -1.2]), torch.tensor([-0.4, 0.9])
        n = angles_to_normal(tx, ty)
        assert torch.allclose(reflection_matrix_from_angles(tx, ty), reflection_matrix(n), atol=1e-6)
        tx2, ty2 = normal_to_angles(n)
        assert torch.allclose(tx2, tx, atol=1e-6) and torch.allclose(ty2, ty, atol=1e-6)

    def test_plane_from_reflection(self):
        n = torch.tensor([0.6, 0.0, 0.8], dtype=torch.float64)
        c = torch.tensor([1.0, 2.0, 3.0], dtype=torch.float64)
        n2, b2 = plane_from_reflection(reflection_matrix(n), c)
        assert torch.allclose(n2, n) and torch.allclose(b2, -(n * c).sum())


class TestTangentBasis:
    def test_orthonormal_frame(self):
        from torchsym.geometry import tangent_basis

        n = torch.nn.functional.normalize(_rand(6, 3), dim=-1)
        n[0] = torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64)  # the helper axis switches here
        b = tangent_basis(n)  # (6, 3, 2)
        assert torch.allclose(b.transpose(-1, -2) @ b, torch.eye(2, dtype=torch.float64).expand(6, 2, 2), atol=1e-12)
        assert float((n.unsqueeze(-2) @ b).abs().max()) < 1e-12
        # right-handed: u x v = n
        assert torch.allclose(torch.linalg.cross(b[..., 0], b[..., 1]), n, atol=1e-12)

    def test_exception(self):
        from torchsym.geometry import tangent_basis

        with pytest.raises(InputShapeError, match=r"normal: expected \(\.\.\., 3\), got \(2,\)"):
            tangent_basis(torch.ones(2))


class TestSpreadNormals:
    def test_greedy_separation(self):
        normals = torch.tensor(
            [[1.0, 0.0, 0.0], [-0.999, 0.0447, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.1, 0.995, 0.0]],
            dtype=torch.float64,
        )
        normals = normals / normals.norm(dim=1, keepdim=True)
        order = torch.tensor([1, 0, 4, 2, 3])
        # 0 is a near-copy of 1 (n and -n are one plane, 2.6 deg apart), 2 of 4 (5.7 deg)
        assert spread_normals(normals, order, 5, 10.0) == [1, 4, 3]
        assert spread_normals(normals, order, 2, 10.0) == [1, 4]
        assert spread_normals(normals, order, 5, 1.0) == [1, 0, 4, 2, 3]


class TestPairFitErrors:
    def test_exact_pairs_have_no_error(self):
        p = torch.randn(200, 3, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
        n = torch.tensor([0.0, 0.6, 0.8], dtype=torch.float64)
        angle, offset = pair_fit_errors(p, reflect_points(p, n, 0.1))
        assert float(angle) < 1e-6 and float(offset) < 1e-6

    def test_matches_the_spread_of_repeated_fits(self):
        """The standard error predicts the spread of the fitted normal over noise draws."""
        g = torch.Generator().manual_seed(1)
        p = torch.randn(400, 3, generator=g, dtype=torch.float64)
        n = torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64)
        q0 = reflect_points(p, n, 0.0)
        angles, ses = [], []
        for _ in range(200):
            q = q0 + 0.02 * torch.randn(q0.shape, generator=g, dtype=torch.float64)
            fit, _ = plane_from_pairs(p, q)
            angles.append(float(plane_angle(fit, n)))
            ses.append(float(pair_fit_errors(p, q)[0]))
        rms = math.sqrt(sum(a * a for a in angles) / len(angles))  # two directions of error
        se = sum(ses) / len(ses)
        assert 0.8 * math.sqrt(2.0) * se < rms < 1.25 * math.sqrt(2.0) * se


class TestReflectionFit:
    def test_value(self):
        """One decomposition gives what plane_from_pairs and pair_fit_errors give apart."""
        g = torch.Generator().manual_seed(2)
        p = torch.randn(300, 3, generator=g, dtype=torch.float64)
        q = reflect_points(p, torch.tensor([0.0, 0.6, 0.8], dtype=torch.float64), 0.2)
        q = q + 0.01 * torch.randn(q.shape, generator=g, dtype=torch.float64)
        w = torch.rand(300, generator=g, dtype=torch.float64)
        n, b, se_n, se_b = reflection_fit(p, q, w)
        n_ref, b_ref = plane_from_pairs(p, q, w)
        se_ref = pair_fit_errors(p, q, w)
        assert torch.allclose(n, n_ref, atol=1e-12) and torch.allclose(b, b_ref, atol=1e-12)
        assert torch.allclose(se_n, se_ref[0], rtol=1e-9) and torch.allclose(se_b, se_ref[1], rtol=1e-9)

    def test_batched(self):
        p, q = _rand(2, 50, 3), _rand(2, 50, 3, seed=1)
        n, b, se_n, se_b = reflection_fit(p, q)
        assert n.shape == (2, 3) and b.shape == (2,) and se_n.shape == (2,) and se_b.shape == (2,)
        assert torch.allclose(n[1], reflection_fit(p[1], q[1])[0], atol=1e-12)

    def test_exception(self):
        with pytest.raises(InputShapeError, match="mirrors"):
            reflection_fit(_rand(5, 3), _rand(4, 3))
        with pytest.raises(InputShapeError, match="weights"):
            reflection_fit(_rand(5, 3), _rand(5, 3), torch.ones(4, dtype=torch.float64))
