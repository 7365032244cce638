from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.mesh import (
    cotangent_laplacian,
    laplacian_eigen,
    mass_matrix,
    ring_neighbourhood,
)
from torchsym.mesh.synthetic import icosphere


@pytest.fixture(scope="module")
def sphere():
    s = icosphere(3)
    return s.vertices.numpy(), s.faces.numpy()


class TestCotangentLaplacian:
    def test_properties(self, sphere):
        v, f = sphere
        w = cotangent_laplacian(v, f)
        assert w.shape == (v.shape[0], v.shape[0])
        assert abs(w - w.T).max() < 1e-12
        assert np.abs(np.asarray(w.sum(axis=1))).max() < 1e-10
        x = np.random.default_rng(0).standard_normal(v.shape[0])
        assert x @ (w @ x) > 0

    def test_mass_is_area(self, sphere):
        v, f = sphere
        assert mass_matrix(v, f).diagonal().sum() == pytest.approx(4 * np.pi, rel=0.02)

    def test_degenerate_guard(self):
        v = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]])
        f = np.array([[0, 1, 2], [0, 1, 3]])
        w = cotangent_laplacian(v, f)
        assert np.isfinite(w.toarray()).all()


class TestLaplacianEigen:
    def test_sphere_spectrum(self, sphere):
        v, f = sphere
        # unit sphere: l (l + 1) with multiplicity 2 l + 1 (Lanczos may miss a copy of a
        # degenerate eigenvalue beyond the requested ones, so only whole clusters are checked)
        evals, evecs = laplacian_eigen(v, f, 12)
        expected = np.array([0] + [2] * 3 + [6] * 5 + [12] * 3, dtype=float)
        assert evals[0] == pytest.approx(0, abs=1e-6)
        np.testing.assert_allclose(evals[1:], expected[1:], rtol=0.03)
        m = mass_matrix(v, f)
        np.testing.assert_allclose(evecs.T @ (m @ evecs), np.eye(12), atol=1e-8)

    def test_seeded(self, sphere):
        v, f = sphere
        a = laplacian_eigen(v, f, 6, generator=torch.Generator().manual_seed(3))
        b = laplacian_eigen(v, f, 6, generator=torch.Generator().manual_seed(3))
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])

    def test_exception(self, sphere):
        v, f = sphere
        with pytest.raises(InputShapeError, match=r"k: expected 1 <= k < V = 642 \(number of vertices\), got 700"):
            laplacian_eigen(v, f, 700)


def test_ring_neighbourhood():
    s = icosphere(0)
    one = ring_neighbourhood(s.faces.numpy(), 12, rings=1)
    two = ring_neighbourhood(s.faces.numpy(), 12, rings=2)
    assert (np.diff(one.indptr) == 5).all()  # icosahedron: every vertex has 5 neighbours
    assert (np.diff(two.indptr) == 10).all()  # all but itself and the antipode
