"""Tests of the soft-correspondence refinement (torchsym.pointset.soft_refinement)."""

from __future__ import annotations

import numpy as np
import torch

from torchsym.geometry import plane_angle
from torchsym.pointset import make_symmetric_pointset, point_symm
from torchsym.pointset.soft_refinement import SoftPlane, normal_standard_error, soft_refine_plane


def planted(n, d, sigma2, seed):
    return make_symmetric_pointset(n, d, sigma2, generator=torch.Generator().manual_seed(seed))


class TestSoftRefinePlane:
    def test_smoke(self):
        s = planted(60, 3, 1e-3, 0)
        r = soft_refine_plane(s.points.numpy(), s.normal.numpy(), float(s.offset), 1e-3)
        assert isinstance(r, SoftPlane) and r.normal.shape == (3,) and r.iterations >= 1
        assert abs(np.linalg.norm(r.normal) - 1.0) < 1e-12 and r.s2 > 0

    def test_exact_symmetry_untouched(self):
        s = planted(40, 3, 0.0, 1)
        r = soft_refine_plane(s.points.numpy(), s.normal.numpy(), float(s.offset), 0.0)
        assert r.iterations == 0 and np.array_equal(r.normal, s.normal.numpy())

    def test_recovers_plane_from_tilted_start(self):
        s = planted(200, 3, 1e-4, 2)
        n = s.normal.numpy() + np.array([0.03, -0.02, 0.01])
        n /= np.linalg.norm(n)
        r = soft_refine_plane(s.points.numpy(), n, float(s.offset), 1e-3)
        assert float(plane_angle(torch.from_numpy(r.normal), s.normal)) < np.radians(0.5)

    def test_noise_variance_estimated(self):
        s = planted(300, 3, 1e-3, 3)
        r = soft_refine_plane(s.points.numpy(), s.normal.numpy(), float(s.offset), 1e-4)
        assert 0.5 * 2e-3 < r.s2 < 2.0 * 2e-3  # the mirror residual has variance 2 sigma^2 per coordinate


    def test_stops_on_noise_scale_without_symmetry(self):
        x = np.random.default_rng(0).random((200, 3))
        r = soft_refine_plane(x, np.array([1.0, 0.0, 0.0]), -0.5, 1e-2, max_iters=100)
        assert r.converged and r.iterations < 100

    def test_tighter_tolerance_runs_longer(self):
        s = planted(200, 3, 3e-3, 6)
        loose = soft_refine_plane(s.points.numpy(), s.normal.numpy(), float(s.offset), 1e-3, tol_se=0.5)
        tight = soft_refine_plane(s.points.numpy(), s.normal.numpy(), float(s.offset), 1e-3, tol_se=1e-3)
        assert loose.iterations <= tight.iterations

    def test_standard_error_scales_with_noise(self):
        s = planted(100, 3, 0.0, 8)
        p, q = s.points.numpy(), s.points[s.correspondence].numpy()
        w = np.ones(p.shape[0])
        se1 = normal_standard_error(p, q, w, 1e-4)
        se4 = normal_standard_error(p, q, w, 4e-4)
        assert se1 > 0 and abs(se4 / se1 - 2.0) < 1e-9


class TestInPointSymm:
    def test_switch(self):
        s = planted(100, 3, 1e-3, 4)
        on, off = point_symm(s.points), point_symm(s.points, soft={"enabled": False})
        assert on.normal.shape == off.normal.shape == (3,)
        assert float(plane_angle(on.normal, s.normal)) < np.radians(3.0)
        assert not torch.equal(on.normal, off.normal)  # the switch reaches the solver

    def test_exact_symmetry_same_bits(self):
        s = planted(50, 3, 0.0, 5)
        on, off = point_symm(s.points), point_symm(s.points, soft={"enabled": False})
        assert torch.equal(on.normal, off.normal) and torch.equal(on.permutation, off.permutation)
