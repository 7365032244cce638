from __future__ import annotations

import math

import pytest
import torch

from torchsym.features.sift import mirror_permutation
from torchsym.image.symmetry_map.clustering import agreement_matrix, cover_exact, cover_greedy, ransacov
from torchsym.image.symmetry_map.descriptors import dense_axis_descriptors, mirror_eigenbases
from torchsym.image.symmetry_map.patchmatch import reflect_through_pairs


def _smooth_random(h: int, w: int, seed: int) -> torch.Tensor:
    img = torch.rand(1, 3, h, w, generator=torch.Generator().manual_seed(seed))
    return torch.nn.functional.avg_pool2d(img, 3, 1, 1)


class TestDenseDescriptors:
    @pytest.mark.parametrize("n_dims", [128, 32])
    def test_mirror_is_exact(self, n_dims):
        """About a vertical axis (normal (1, 0)) the descriptor of the flipped image is the mirrored descriptor."""
        img = _smooth_random(40, 50, 0)
        a = dense_axis_descriptors(img, torch.tensor([1.0, 0.0]), n_dims=n_dims)
        b = dense_axis_descriptors(img.flip(-1), torch.tensor([1.0, 0.0]), n_dims=n_dims)
        da, db = a.values.view(40, 50, -1), b.values.view(40, 50, -1)
        assert torch.allclose(db.flip(1)[8:-8, 8:-8], (da * a.signs)[8:-8, 8:-8], atol=1e-5)

    def test_mirror_at_an_angle(self):
        """A transpose is the reflection about the diagonal: normal (1, -1) / sqrt 2."""
        img = _smooth_random(48, 48, 1)
        n = torch.tensor([1.0, -1.0]) / math.sqrt(2)
        a = dense_axis_descriptors(img, n, n_dims=128)
        b = dense_axis_descriptors(img.transpose(-1, -2), n, n_dims=128)
        da, db = a.values.view(48, 48, -1), b.values.view(48, 48, -1)
        err = (db.transpose(0, 1) - da * a.signs)[12:-12, 12:-12].abs().max()
        assert float(err) < 0.05  # bilinear sampling at the rotated cells

    def test_eigenbases(self):
        plus, minus = mirror_eigenbases(mirror_permutation())
        basis = torch.cat([plus, minus], 1)
        assert torch.allclose(basis.T @ basis, torch.eye(128, dtype=torch.float64))
        d = torch.rand(128, dtype=torch.float64)
        assert torch.allclose(d[mirror_permutation()], d @ plus @ plus.T - d @ minus @ minus.T)

    def test_stride(self):
        d = dense_axis_descriptors(_smooth_random(21, 30, 2), torch.tensor([0.6, 0.8]), n_dims=16, stride=2)
        assert d.grid_shape == (11, 15) and d.values.shape == (165, 16)


def _pairs_about(normal, offset, n, seed, spread=60.0):
    g = torch.Generator().manual_seed(seed)
    nrm = torch.tensor(normal) / torch.tensor(normal).norm()
    p = 100 + spread * (torch.rand(n, 2, generator=g) - 0.5) * 2
    s = p @ nrm + offset
    p = p + (1 + torch.rand(n, 1, generator=g) * 10 - s[:, None]) * nrm  # on the positive side
    q = p - 2 * (p @ nrm + offset)[:, None] * nrm
    return torch.cat([p, q], 1)


class TestRansaCov:
    def test_two_axes(self):
        a = _pairs_about([1.0, 0.0], -100.0, 30, 0)
        b = _pairs_about([0.6, 0.8], -150.0, 20, 1)
        noise = torch.rand(25, 4, generator=torch.Generator().manual_seed(3)) * 200
        pairs = torch.cat([a, b, noise])
        out = ransacov(pairs, 2)
        assert len(out.members) == 2
        assert set(out.members[0].tolist()) >= set(range(30))
        assert set(out.members[1].tolist()) >= set(range(30, 50))

    def test_exact_matches_greedy(self):
        pairs = torch.cat([_pairs_about([1.0, 0.0], -100.0, 20, 0), _pairs_about([0.0, 1.0], -90.0, 12, 2)])
        agree = agreement_matrix(pairs, eps_d=0.03, eps_theta=2.0, tol_px=1.5)
        g, e = cover_greedy(agree, 2), cover_exact(agree, 2)
        assert int(agree[g].any(0).sum()) == int(agree[e].any(0).sum()) == 32

    def test_k_larger_than_clusters(self):
        out = ransacov(_pairs_about([1.0, 0.0], -100.0, 20, 0), 5)
        assert len(out.members) == 1 and out.covered == 20

    def test_empty(self):
        out = ransacov(torch.zeros(0, 4), 2)
        assert out.members == [] and out.lines.shape == (0, 3)


def test_reflect_through_pairs():
    left = torch.tensor([[10.0, 5.0]])
    right = torch.tensor([[30.0, 5.0]])  # axis x = 20
    out = reflect_through_pairs(torch.tensor([[12.0, 7.0]]), left, right)
    assert torch.allclose(out, torch.tensor([[28.0, 7.0]]))
