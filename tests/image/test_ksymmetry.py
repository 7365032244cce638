"""k-symmetry clustering (thesis Sec. 2.2)."""

from __future__ import annotations

import pytest
import torch

from torchsym.errors import ConfigError
from torchsym.image import KSymmetryDetector, ksymmetry_axes
from torchsym.image.ksymmetry import ksymmetry_clustering
from torchsym.metrics.axes import match_axes


def _mirror_pairs(normal, offset, n, generator):
    normal = torch.tensor(normal, dtype=torch.float64)
    normal = normal / normal.norm()
    left = torch.rand(n, 2, generator=generator, dtype=torch.float64) * 2 - 1
    right = left - 2 * ((left @ normal) + offset)[:, None] * normal
    return left, right


class TestKSymmetryClustering:
    def test_two_planted_axes(self):
        g = torch.Generator().manual_seed(0)
        l1, r1 = _mirror_pairs([1.0, 0.2], 0.3, 40, g)
        l2, r2 = _mirror_pairs([0.1, 1.0], -0.2, 40, g)
        left, right = torch.cat([l1, l2]), torch.cat([r1, r2])
        init = torch.tensor([[1.0, 0.0, 0.2], [0.0, 1.0, -0.1]], dtype=torch.float64)
        u, labels, cost, converged, _ = ksymmetry_clustering(left, right, init)
        assert converged and cost < 1e-12
        assert labels[:40].unique().numel() == 1 and labels[40:].unique().numel() == 1
        n = u[:, :2] / u[:, :2].norm(dim=1, keepdim=True)
        want = torch.nn.functional.normalize(torch.tensor([[1.0, 0.2], [0.1, 1.0]], dtype=torch.float64), dim=1)
        assert torch.allclose((n * want[labels[[0, 40]]]).sum(1).abs(), torch.ones(2, dtype=torch.float64), atol=1e-9)

    def test_matches_per_cluster_loop(self):
        """The batched update (scatter-add + batched eigh) equals Algorithm 1 written per cluster."""
        g = torch.Generator().manual_seed(1)
        l1, r1 = _mirror_pairs([1.0, 0.2], 0.3, 40, g)
        l2, r2 = _mirror_pairs([0.1, 1.0], -0.2, 40, g)
        noise = torch.rand(30, 4, generator=g, dtype=torch.float64) * 2 - 1
        left, right = torch.cat([l1, l2, noise[:, :2]]), torch.cat([r1, r2, noise[:, 2:]])
        init = torch.tensor([[1.0, 0.1, 0.1], [0.2, 1.0, 0.0], [1.0, -1.0, 0.5]], dtype=torch.float64)
        for outlier in (None, 0.01):
            u, labels, _, _, _ = ksymmetry_clustering(left, right, init, outlier_cost=outlier)
            mid = 0.5 * (left + right)
            x = torch.cat([mid, torch.ones(mid.shape[0], 1, dtype=torch.float64)], 1)
            y = torch.stack([right[:, 1] - left[:, 1], left[:, 0] - right[:, 0], torch.zeros_like(mid[:, 0])], 1)
            ref = init / init.norm(dim=1, keepdim=True)
            lab = torch.full((left.shape[0],), -2)
            for _ in range(50):
                c = (x @ ref.T) ** 2 + (y @ ref.T) ** 2
                best, new = c.min(1)
                if outlier is not None:
                    new = torch.where(best > outlier, torch.full_like(new, -1), new)
                if torch.equal(new, lab):
                    break
                lab = new
                for i in range(ref.shape[0]):
                    m = lab == i
                    if int(m.sum()) >= 2:
                        ref[i] = torch.linalg.eigh(x[m].T @ x[m] + y[m].T @ y[m])[1][:, 0]
            assert torch.equal(labels, lab)
            assert torch.allclose((u * ref).sum(1).abs(), torch.ones(3, dtype=torch.float64), atol=1e-9)


class TestKSymmetryAxes:
    def test_smoke(self, single_objects):
        img, _ = single_objects[0]
        res = ksymmetry_axes(img)
        assert res.method == "ksymmetry" and res.axes.shape[1] == 4
        assert res.info["k1"] >= 1 and len(res.info["cost_curve"]) >= 1

    def test_planted_axes_random_angles(self, single_objects):
        hits = 0
        for img, gt in single_objects:
            res = ksymmetry_axes(img, pairs={"max_keypoints": 400})
            hits += bool(match_axes(res.axes[:3], gt, image_size=(240, 240), criterion="challenge").any())
        assert hits >= 4

    def test_module(self):
        m = KSymmetryDetector(pairs={"k1": 2}, max_axes=3)
        assert "pairs.k1=2" in repr(m) and "max_axes=3" in repr(m)

    def test_exception(self):
        with pytest.raises(ConfigError, match="eps_theta: expected a finite number > 0.0"):
            KSymmetryDetector(eps_theta=0.0)
        with pytest.raises(ConfigError, match="pairs.k1: expected an int >= 1 and <= 1000 or null, got 0"):
            ksymmetry_axes(torch.rand(1, 32, 32), pairs={"k1": 0})
