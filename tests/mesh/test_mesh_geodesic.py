from __future__ import annotations

import numpy as np
import pytest

from torchsym.mesh import edge_graph, geodesic_distances, shortest_paths, thin_points
from torchsym.mesh.synthetic import icosphere


@pytest.fixture(scope="module")
def sphere():
    s = icosphere(3)
    v, f = s.vertices.numpy(), s.faces.numpy()
    return v, f, edge_graph(v, f)


class TestGeodesic:
    def test_antipodal_distance(self, sphere):
        v, f, g = sphere
        d = geodesic_distances(g, [0])[0]
        anti = int(np.argmin(v @ v[0]))
        # edge paths over-estimate the great-circle distance pi by a few percent
        assert np.pi <= d[anti] <= np.pi * 1.15
        assert d[0] == 0

    def test_limit(self, sphere):
        _, _, g = sphere
        d = geodesic_distances(g, [0, 1], limit=0.3)
        assert d.shape == (2, g.shape[0]) and np.isinf(d).any() and (d[np.isfinite(d)] <= 0.3).all()

    def test_paths(self, sphere):
        v, _, g = sphere
        anti = int(np.argmin(v @ v[0]))
        (path,) = shortest_paths(g, np.array([[0, anti]]))
        assert path[0] == 0 and path[-1] == anti
        steps = np.linalg.norm(np.diff(v[path], axis=0), axis=1)
        assert steps.sum() == pytest.approx(geodesic_distances(g, [0])[0, anti])
        assert shortest_paths(g, np.zeros((0, 2))) == []

    def test_thin_points(self, sphere):
        v, _, g = sphere
        anti = int(np.argmin(v @ v[0]))
        near = int(np.argsort(np.linalg.norm(v - v[0], axis=1))[1])
        assert thin_points(g, np.array([0, near, anti]), 0.5).tolist() == [0, anti]
        assert thin_points(g, np.array([0, near]), 0.0).tolist() == [0, near]
