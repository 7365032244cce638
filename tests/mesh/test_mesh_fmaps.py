"""Functional-map building blocks (torchsym.mesh.fmaps)."""

from __future__ import annotations

import numpy as np
import torch

from torchsym.mesh import laplacian_eigen


class TestZoomout:
    def test_zoomout_round_uses_the_inverse_map(self, blob):
        """One round from a corrupted map: the average of the forward and inverse fits, projected; closer to the truth."""
        from scipy.spatial import cKDTree

        from torchsym.mesh import laplacian_eigen
        from torchsym.mesh.fmaps import fit_functional
        from torchsym.mesh.fmaps import nearest_involution
        from torchsym.mesh.fmaps import zoomout
        from torchsym.mesh.nearest import SampledSearch
        from torchsym.mesh.operators import mass_matrix

        mesh, gt = blob
        v, f = mesh.vertices.double().numpy(), mesh.faces.numpy()
        _, phi = laplacian_eigen(v, f, 13)
        area = mass_matrix(v, f).diagonal()
        rng = np.random.default_rng(0)
        rows = np.sort(rng.choice(v.shape[0], 300, replace=False))
        image = gt[rows].copy()
        bad = rng.random(rows.size) < 0.4
        image[bad] = rng.integers(0, v.shape[0], int(bad.sum()))  # 40 % of the map wrong
        trees = SampledSearch(phi, None)
        out, c = zoomout(phi, area, rows, image, np.array([13]), trees, involution=True)
        fwd = fit_functional(phi[rows], phi[image], area[rows])
        pre = cKDTree(phi @ fwd).query(phi[rows], k=1)[1]
        want = nearest_involution(0.5 * (fwd + fit_functional(phi[rows], phi[pre], area[rows])))
        assert np.allclose(c, want)
        truth = fit_functional(phi[rows], phi[gt[rows]], area[rows])
        forward_only = nearest_involution(fwd)
        assert np.linalg.norm(c - truth) < np.linalg.norm(forward_only - truth)
        assert (out == gt[rows]).mean() >= (cKDTree(phi).query(phi[rows] @ forward_only, k=1)[1] == gt[rows]).mean()
        # among an even subset that holds the sample: the images are subset vertices
        subset = np.union1d(rows, np.arange(0, v.shape[0], 3))
        sub_out, _ = zoomout(phi, area, rows, image, np.array([13]), SampledSearch(phi, subset), involution=True)
        assert np.isin(sub_out, subset).all() and (sub_out == gt[rows]).mean() >= 0.5 * (out == gt[rows]).mean()


class TestNearestInvolution:
    def test_nearest_involution(self):
        from scipy.stats import ortho_group

        from torchsym.mesh.fmaps import nearest_involution

        q = ortho_group.rvs(6, random_state=0)
        s = q @ np.diag([1.0, 1, -1, 1, -1, -1]) @ q.T  # an orthogonal involution
        assert np.allclose(nearest_involution(s), s)
        noisy = s + 0.05 * np.random.default_rng(0).standard_normal((6, 6))
        out = nearest_involution(noisy)
        assert np.allclose(out, s, atol=0.2) and np.allclose(out @ out, np.eye(6)) and np.allclose(out, out.T)
        # it is the nearest symmetric orthogonal matrix: no random one (any signs, any basis) is closer
        rng = np.random.default_rng(1)
        best = min(
            np.linalg.norm(noisy - (r * rng.choice([-1.0, 1.0], 6)) @ r.T)
            for r in (ortho_group.rvs(6, random_state=i) for i in range(300))
        )
        assert np.linalg.norm(noisy - out) <= best


class TestMapConsistency:
    def test_true_signs_are_most_consistent(self, spectral):
        from scipy.spatial import cKDTree

        from torchsym.mesh import map_consistency

        evecs, signs = spectral
        tree = cKDTree(evecs)
        rows = np.arange(0, evecs.shape[0], 3)
        true_q = map_consistency(tree, evecs, signs, rows)
        assert true_q < 0.3
        for k in range(1, 13):
            wrong = signs.copy()
            wrong[k] *= -1
            assert map_consistency(tree, evecs, wrong, rows) > 2.0 * true_q


class TestMapQuality:
    def test_map_quality(self, blob):
        from torchsym.mesh import map_quality
        from torchsym.mesh.operators import laplacian_eigen, mass_matrix

        mesh, gt = blob
        v, f = mesh.vertices.numpy(), mesh.faces.numpy()
        _, evecs = laplacian_eigen(v, f, 13, generator=torch.Generator().manual_seed(0))
        area = mass_matrix(v, f).diagonal()
        true_q = map_quality(evecs, area, gt)
        assert true_q < 0.5
        assert map_quality(evecs, area, np.arange(len(gt))) < 1e-8  # the identity: callers rule it out
        shuffled = np.random.default_rng(0).permutation(len(gt))
        assert map_quality(evecs, area, shuffled) > 5 * true_q
