from __future__ import annotations

import numpy as np
import pytest

from torchsym.errors import InputShapeError, InputValueError
from torchsym.mesh import (
    edge_graph,
    geodesic_distances,
    shortest_paths,
    split_fans,
    surface_geodesic_lengths,
    thin_points,
)
from torchsym.mesh.synthetic import icosphere


def flat_grid(n: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """A unit square of (n + 1)^2 vertices, every cell cut by the same diagonal."""
    xs, ys = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
    v = np.stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)], axis=1)
    idx = np.arange(v.shape[0]).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return v, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


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


class TestSurfaceGeodesic:
    def test_flat_is_euclidean(self):
        v, f = flat_grid()
        g = edge_graph(v, f)
        pairs = np.array([[0, 13 * 5 + 2], [0, 13 * 2 + 5], [7, 13 * 11 + 2], [40, 40]])
        lengths = surface_geodesic_lengths(v, f, pairs)
        straight = np.linalg.norm(v[pairs[:, 0]] - v[pairs[:, 1]], axis=1)
        np.testing.assert_allclose(lengths, straight, atol=1e-9)
        edges = geodesic_distances(g, pairs[:, 0])[np.arange(4), pairs[:, 1]]
        # the pairs off the grid's directions are longer along edges
        assert (edges[:3] > straight[:3] * 1.05).all() and lengths[3] == 0.0

    def test_sphere_between_great_circle_and_edges(self, sphere):
        v, f, g = sphere
        rng = np.random.default_rng(0)
        pairs = rng.integers(0, v.shape[0], size=(30, 2))
        lengths = surface_geodesic_lengths(v, f, pairs)
        edges = geodesic_distances(g, pairs[:, 0])[np.arange(30), pairs[:, 1]]
        arc = np.arccos(np.clip((v[pairs[:, 0]] * v[pairs[:, 1]]).sum(1), -1, 1))
        assert (lengths <= edges + 1e-9).all()
        # the icosphere lies inside the unit sphere: its geodesics are a little shorter
        assert (lengths <= arc + 1e-9).all() and (lengths >= 0.97 * arc).all()
        assert np.median(edges / np.where(lengths > 0, lengths, 1)) > 1.02

    def test_components_and_exception(self):
        v, f = flat_grid(4)
        v2, f2 = np.concatenate([v, v + 5.0]), np.concatenate([f, f + v.shape[0]])
        out = surface_geodesic_lengths(v2, f2, np.array([[0, v.shape[0] + 3], [0, 6]]))
        assert np.isinf(out[0]) and out[1] == pytest.approx(np.linalg.norm(v[6] - v[0]))
        with pytest.raises(InputShapeError, match=r"pairs: expected \(P, 2\) vertex pairs, got \(3,\)"):
            surface_geodesic_lengths(v, f, np.array([0, 1, 2]))
        with pytest.raises(InputShapeError, match=r"pairs: expected vertex indices in \[0, 24\], got \[0, 25\]"):
            surface_geodesic_lengths(v, f, np.array([[0, 25]]))

    def test_bow_tie(self):
        # two squares of the grid touching at one vertex (an hourglass), and a loose vertex
        v, f = flat_grid(4)
        keep = [t for t in range(f.shape[0]) if max(v[f[t], 0].max(), v[f[t], 1].max()) <= 0.5
                or min(v[f[t], 0].min(), v[f[t], 1].min()) >= 0.5]
        f = f[keep]
        pinch = 2 * 5 + 2  # (0.5, 0.5)
        out = surface_geodesic_lengths(v, f, np.array([[0, 24], [0, pinch], [pinch, 24], [0, 4]]))
        # no path crosses the pinch: the pinched vertex belongs to its first fan (lower left)
        assert out[1] == pytest.approx(np.sqrt(0.5), abs=1e-9)
        assert np.isinf(out[0]) and np.isinf(out[2])
        assert np.isinf(out[3])  # vertex 4, (0, 1), lies in no kept triangle

    def test_split_fans(self):
        v, f = flat_grid(2)  # 9 vertices, the centre 4 shared by every cell
        faces, origin = split_fans(f, 9)
        np.testing.assert_array_equal(faces, f)
        np.testing.assert_array_equal(origin, np.arange(9))
        tie = f[[0, 7]]  # lower-left and upper-right triangles, touching at the centre only
        faces, origin = split_fans(tie, 9)
        assert origin.tolist() == sorted(origin.tolist()) and (origin == 4).sum() == 2
        np.testing.assert_array_equal(origin[faces], tie)
        assert len(set(faces[0]) & set(faces[1])) == 0
        with pytest.raises(InputValueError, match=r"faces: expected every edge in at most two triangles, got edge \[0, 4\] in 3"):
            split_fans(np.concatenate([f[[0, 4]], [[0, 4, 2]]]), 9)
        with pytest.raises(InputShapeError, match=r"faces: expected vertex indices in \[0, 7\], got \[0, 8\]"):
            split_fans(f, 8)
