"""Tests of Algorithm 7's alternation (steps 2-4)."""

from __future__ import annotations

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.pointset import make_symmetric_pointset
from torchsym.pointset.alternation import Alternation, alternate, best_run, mirror_score, start_variables
from torchsym.pointset.transform import rotation_manifold


def _problem(x, **kw):
    opts = dict(method="exact", n_matches=None, n_neighbors=10, max_iters=20)
    opts.update(kw)
    return Alternation(points=x, points_t=torch.from_numpy(x), tree=cKDTree(x), manifold=rotation_manifold(x.shape[1]), **opts)


class TestAlternate:
    def test_converges_from_a_near_plane(self):
        s = make_symmetric_pointset(60, 3, generator=torch.Generator().manual_seed(0))
        x = s.points.numpy()
        normal = s.normal.numpy() + np.array([0.03, -0.02, 0.01])
        point = -float(s.offset) * s.normal.numpy()
        run = alternate(_problem(x), start_variables(normal / np.linalg.norm(normal), point))
        assert run.converged and np.array_equal(run.perm, s.correspondence.numpy())
        assert run.total < 1e-20

    def test_best_run_keeps_least_error(self):
        s = make_symmetric_pointset(40, 2, generator=torch.Generator().manual_seed(1))
        x = s.points.numpy()
        good = (s.normal.numpy(), -float(s.offset) * s.normal.numpy())
        bad = (np.array([s.normal[1].item(), -s.normal[0].item()]), x.mean(0))
        run = best_run(_problem(x), [bad, good])
        assert run.total < 1e-20


class TestMirrorScore:
    def test_values(self):
        perm = np.array([1, 0, -1, 3])
        dist2 = np.array([0.0, 0.0, np.inf, 1.0])
        assert mirror_score(perm, dist2, 1.0) == (2.0 + np.exp(-0.5)) / 4
        assert mirror_score(np.full(3, -1), np.full(3, np.inf), 1.0) == 0.0


class TestClosedFormStep:
    """Above ``max_trust_region_dim`` step 3 is the closed-form least-squares reflection."""

    def test_same_plane_as_trust_region(self):
        import torch

        from torchsym.geometry import plane_angle
        from torchsym.pointset import make_symmetric_pointset, point_symm

        s = make_symmetric_pointset(60, 6, 1e-4, generator=torch.Generator().manual_seed(3))
        tr = point_symm(s.points, soft={"enabled": False})
        cf = point_symm(s.points, soft={"enabled": False}, max_trust_region_dim=2)
        assert float(plane_angle(tr.normal, cf.normal)) < 1e-6
        assert torch.equal(tr.permutation, cf.permutation)

    def test_high_dimension_exact(self):
        import torch

        from torchsym.geometry import plane_angle
        from torchsym.pointset import make_symmetric_pointset, point_symm

        s = make_symmetric_pointset(80, 30, 0.0, generator=torch.Generator().manual_seed(4))
        r = point_symm(s.points)
        assert float(plane_angle(r.normal, s.normal)) < 1e-9 and r.score > 0.99
