"""Tests of the affine-hull reduction of flat point sets."""

from __future__ import annotations

import numpy as np
import torch

from torchsym.pointset.hull import hull_basis


def _centred(x):
    c = x - x.mean(0)
    return c - c.mean(0)


class TestHullBasis:
    def test_full_rank_is_none(self):
        x = np.random.default_rng(0).random((50, 4))
        assert hull_basis(x, _centred(x), torch.float64) is None

    def test_flat_set(self):
        rng = np.random.default_rng(1)
        q, _ = np.linalg.qr(rng.standard_normal((6, 3)))
        x = rng.random((40, 3)) @ q.T + 5.0  # a 3-D affine subspace of R^6
        basis = hull_basis(x, _centred(x), torch.float64)
        assert basis.shape == (6, 3)
        np.testing.assert_allclose(basis.T @ basis, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(q @ (q.T @ basis), basis, atol=1e-10)  # spans the same subspace

    def test_few_points_keep_two_directions(self):
        x = np.array([[0.0, 1.0, 2.0, 3.0], [2.0, 1.0, 0.0, 3.0]])
        assert hull_basis(x, _centred(x), torch.float64).shape == (4, 2)

    def test_plane_is_none(self):
        x = np.random.default_rng(2).random((10, 2))
        assert hull_basis(x, _centred(x), torch.float64) is None
