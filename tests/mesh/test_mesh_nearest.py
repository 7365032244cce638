"""Nearest-row searches (torchsym.mesh.nearest)."""

from __future__ import annotations

import numpy as np



class TestNearest:
    def test_nearest_is_exact_by_tree_and_by_brute_force(self, monkeypatch):
        # queries near the points go to the kd-tree, far ones to brute force (float32: its
        # rounding could only pick a near tie, and there is none here)
        from scipy.spatial import cKDTree

        from torchsym.mesh import nearest

        rng = np.random.default_rng(0)
        points = rng.standard_normal((3000, 16))
        near = points[rng.choice(3000, size=600)] + 1e-3 * rng.standard_normal((600, 16))
        far = 3.0 * rng.standard_normal((600, 16))
        truth = cKDTree(points)
        used = []
        original = nearest.Nearest.brute
        monkeypatch.setattr(nearest.Nearest, "brute", lambda self, q, *a, **k: used.append(q.shape[0]) or original(self, q, *a, **k))
        search = nearest.Nearest(points)
        assert np.array_equal(search.query(near), truth.query(near)[1])
        assert used == []  # the kd-tree only (after the probe of every 32nd query)
        assert np.array_equal(search.query(far), truth.query(far)[1])
        assert used == [far.shape[0]]  # all by brute force
        assert np.allclose(search.distances(far[:50]), truth.query(far[:50])[0], rtol=1e-10)


class TestNearestProfiles:
    def test_nearest_profiles_is_exact(self):
        from scipy.spatial import cKDTree

        from torchsym.mesh.nearest import nearest_profiles

        rng = np.random.default_rng(0)
        data = rng.standard_normal((700, 64))
        queries = data[rng.choice(700, 300)] + 0.05 * rng.standard_normal((300, 64))
        np.testing.assert_array_equal(nearest_profiles(queries, data, chunk=128), cKDTree(data).query(queries)[1])
        # distance profiles: non-negative, with a common offset of the order of their spread
        profiles = np.abs(rng.standard_normal((700, 64))) + 1.0
        near = profiles[rng.choice(700, 300)] + 0.05 * rng.standard_normal((300, 64))
        np.testing.assert_array_equal(nearest_profiles(near, profiles), cKDTree(profiles).query(near)[1])
