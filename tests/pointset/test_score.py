"""Tests of the chance-calibrated symmetry score (torchsym.pointset.score)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.pointset import make_symmetric_pointset, point_symm
from torchsym.pointset.score import chance_evidence, mirror_evidence, symmetry_score


def _reflect(x, normal, offset):
    return x - 2.0 * (x @ normal + offset)[:, None] * normal


class TestMirrorEvidence:
    def test_smoke(self):
        x = np.random.default_rng(0).random((20, 3))
        e = mirror_evidence(x, _reflect(x, np.array([1.0, 0, 0]), -0.5), np.arange(20))
        assert e.shape == (20,) and (e >= 0).all() and (e <= 1).all()

    def test_exact_mirrors_count_one(self):
        h = np.random.default_rng(1).random((10, 2))
        x = np.concatenate([h, h * [-1.0, 1.0]])
        mirror = np.r_[np.arange(10, 20), np.arange(10)]
        assert np.allclose(mirror_evidence(x, x * [-1.0, 1.0], mirror), 1.0)

    def test_self_mirror_and_unmatched_count_zero(self):
        x = np.random.default_rng(2).random((8, 3))
        y = _reflect(x, np.array([0.0, 0.0, 1.0]), 0.0)
        assert np.allclose(mirror_evidence(x, y, np.arange(8)), 0.0)  # each point its own mirror
        assert np.allclose(mirror_evidence(x, y, np.full(8, -1)), 0.0)


class TestSymmetryScore:
    def test_range_and_determinism(self):
        x = np.random.default_rng(3).random((50, 3))
        y = _reflect(x, np.array([1.0, 0, 0]), -0.5)
        a = symmetry_score(x, y, np.arange(50), np.random.default_rng(0))
        b = symmetry_score(x, y, np.arange(50), np.random.default_rng(0))
        assert a == b and 0.0 <= a <= 1.0

    def test_chance_level_of_evenly_spaced_points(self):
        # a jittered lattice: reflections land near some point by chance
        g = np.stack(np.meshgrid(np.arange(12.0), np.arange(12.0)), -1).reshape(-1, 2)
        x = g + 0.1 * np.random.default_rng(4).standard_normal(g.shape)
        assert chance_evidence(x, np.random.default_rng(0)) > 0.05


@pytest.mark.slow
class TestPointSymmScore:
    """Issue 31: random sets score low in any dimension, symmetric sets high."""

    @pytest.mark.parametrize("n,d", [(50, 300), (64, 64), (300, 3), (100, 10)])
    def test_random_sets_low(self, n, d):
        x = torch.randn(n, d, generator=torch.Generator().manual_seed(5), dtype=torch.float64)
        assert point_symm(x).score < 0.3

    def test_gaussian_mixture_low(self):
        g = torch.Generator().manual_seed(5)
        centres = torch.randn(5, 3, generator=g, dtype=torch.float64) * 2
        label = torch.randint(0, 5, (300,), generator=g)
        x = centres[label] + 0.5 * torch.randn(300, 3, generator=g, dtype=torch.float64)
        assert point_symm(x).score < 0.3

    @pytest.mark.parametrize("n,d,sigma2", [(300, 3, 0.0), (100, 10, 0.0), (200, 3, 1e-5), (200, 6, 1e-4)])
    def test_symmetric_sets_high(self, n, d, sigma2):
        s = make_symmetric_pointset(n, d, sigma2, generator=torch.Generator().manual_seed(1))
        assert point_symm(s.points).score > 0.7
