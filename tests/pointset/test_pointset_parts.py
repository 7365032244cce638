"""Tests of the pieces of PointSymm: assignment, pair search, synthetic sets, metrics."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import torch
from scipy.spatial import cKDTree

from torchsym.errors import InputShapeError, InputValueError
from torchsym.metrics import (
    normal_angle_error,
    pointset_correspondence_rate,
    pointset_normal_precision,
    pointset_symmetry_errors,
)
from torchsym.pointset.assignment import mirror_assignment
from torchsym.pointset.initialization import normal_scan, pair_search, scan_normals
from torchsym.pointset.synthetic import make_symmetric_pointset

DT = torch.float64


def planted(n, d, seed, sigma2=0.0):
    return make_symmetric_pointset(n, d, sigma2, generator=torch.Generator().manual_seed(seed))


def reflect(x, normal, offset):
    return x - 2 * ((x @ normal) + offset)[:, None] * normal


class TestMirrorAssignment:
    @pytest.mark.parametrize("method", ["exact", "sparse"])
    def test_planted(self, method):
        s = planted(40, 3, 0)
        x = s.points.numpy()
        perm, d2 = mirror_assignment(x, reflect(x, s.normal.numpy(), float(s.offset)), method=method, n_neighbors=3)
        assert np.array_equal(perm, s.correspondence.numpy())
        assert d2.max() < 1e-20

    def test_cardinality_exact(self):
        x = np.array([[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]])
        moved = np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 9.0]])
        perm, d2 = mirror_assignment(x, moved, n_matches=2)
        assert perm.tolist() == [1, 0, -1] and math.isinf(d2[2])

    def test_exact_is_optimal(self):
        rng = np.random.default_rng(0)
        x, moved = rng.random((6, 2)), rng.random((6, 2))
        _, d2 = mirror_assignment(x, moved)
        import itertools

        best = min(sum(((moved[i] - x[p[i]]) ** 2).sum() for i in range(6)) for p in itertools.permutations(range(6)))
        assert abs(d2.sum() - best) < 1e-12

    def test_exception(self):
        with pytest.raises(ValueError, match="method"):
            mirror_assignment(np.zeros((2, 2)), np.zeros((2, 2)), method="lp")


class TestPairSearch:
    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_noise_free(self, d):
        s = planted(60, d, d)
        normal, point, normals, points, errors, found = pair_search(s.points.numpy(), np.random.default_rng(0))
        assert abs(abs(normal @ s.normal.numpy()) - 1) < 1e-10
        assert abs(point @ s.normal.numpy() + float(s.offset)) < 1e-10
        assert found > 0 and normals.shape[1] == d and points.shape == normals.shape
        assert errors.shape == (normals.shape[0],) and float(errors.min()) < 1e-20

    def test_seeded(self):
        x = planted(40, 3, 1, 0.001).points.numpy()
        a = pair_search(x, np.random.default_rng(5))
        b = pair_search(x, np.random.default_rng(5))
        assert all(np.array_equal(u, v) for u, v in zip(a[:5], b[:5]))


class TestNormalScan:
    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_directions(self, d):
        normals = scan_normals(d, 50, np.random.default_rng(0))
        assert normals.shape == (50, d)
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0)
        assert np.abs(normals @ normals.T - np.eye(50)).max() < 1.0 - 1e-9  # no two the same plane

    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_best_start_is_the_plane(self, d):
        # the centroid of a symmetric set lies on its plane and its normal is a principal
        # axis, so the best scanned start is the plane itself (up to round-off)
        s = planted(200, d, 7)
        x = s.points.numpy()
        starts = normal_scan(x, cKDTree(x), np.random.default_rng(0), n_normals=100, n_keep=3)
        normal, point = starts[0]
        assert abs(abs(normal @ s.normal.numpy()) - 1) < 1e-9
        assert abs(point @ s.normal.numpy() + float(s.offset)) < 1e-9
        assert 1 <= len(starts) <= 3
        kept = np.stack([n for n, _ in starts])
        off_diagonal = np.abs(kept @ kept.T)[~np.eye(len(starts), dtype=bool)]
        assert (off_diagonal < math.cos(math.radians(10.0))).all()

    def test_directions_beyond_the_principal_axes(self):
        # a set with the symmetries of a regular tetrahedron has an isotropic covariance, so
        # its principal axes are arbitrary (here 15 to 45 deg from every mirror plane); the
        # scanned directions find a mirror plane
        p = np.random.default_rng(0).uniform(-1.0, 1.0, (12, 3))
        signs = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]])
        x = np.concatenate([p[:, list(perm)] * sg for perm in itertools.permutations(range(3)) for sg in signs])
        x = x + np.array([0.3, -0.2, 0.5])
        mirrors = np.array([[1, -1, 0], [1, 1, 0], [1, 0, -1], [1, 0, 1], [0, 1, -1], [0, 1, 1]]) / math.sqrt(2.0)
        normal, _ = normal_scan(x, cKDTree(x), np.random.default_rng(0), n_normals=200, n_keep=3)[0]
        assert np.degrees(np.arccos(np.clip(np.abs(mirrors @ normal).max(), 0.0, 1.0))) < 5.0

    def test_flat_set_trivial_mirror_left_out(self):
        # every set lying in a hyperplane is its own mirror across it; that plane is no start
        x2 = planted(200, 2, 4, 3e-3).points.numpy()
        x = np.concatenate([x2, np.zeros((200, 1))], axis=1)
        starts = normal_scan(x, cKDTree(x), np.random.default_rng(0), n_normals=100, n_keep=4)
        assert starts and all(abs(n[2]) < 0.9 for n, _ in starts)

    def test_seeded(self):
        x = planted(120, 6, 2, 0.01).points.numpy()
        a = normal_scan(x, cKDTree(x), np.random.default_rng(3))
        b = normal_scan(x, cKDTree(x), np.random.default_rng(3))
        assert all(np.array_equal(u[0], v[0]) and np.array_equal(u[1], v[1]) for u, v in zip(a, b))


class TestMakeSymmetricPointset:
    @pytest.mark.parametrize("n, d", [(50, 2), (51, 3), (300, 6), (100, 8)])
    def test_symmetric(self, n, d):
        s = planted(n, d, 2)
        assert s.points.shape == (n, d)
        mirrored = reflect(s.clean, s.normal, s.offset)
        assert torch.allclose(mirrored, s.clean[s.correspondence], atol=1e-12)
        assert torch.equal(s.correspondence[s.correspondence], torch.arange(n))

    def test_noise(self):
        s = planted(2000, 3, 3, sigma2=0.01)
        assert abs(float((s.points - s.clean).std()) - 0.1) < 0.01

    def test_seeded(self):
        assert torch.equal(planted(30, 3, 4, 0.05).points, planted(30, 3, 4, 0.05).points)

    def test_exception(self):
        with pytest.raises(InputValueError, match="d: expected an integer >= 2"):
            make_symmetric_pointset(10, 1)
        with pytest.raises(InputShapeError, match="normal: expected a non-zero"):
            make_symmetric_pointset(10, 3, normal=torch.zeros(3))


class TestCorrespondenceRate:
    def test_values(self):
        s = planted(20, 2, 5)
        rate = pointset_correspondence_rate(s.points, s.correspondence, s.correspondence, torch.tensor([0.0, 0.01]))
        assert rate.tolist() == [0.0, 1.0]
        wrong = torch.roll(s.correspondence, 1)
        assert float(pointset_correspondence_rate(s.points, wrong, s.correspondence, [1e-9])[0]) < 0.2

    def test_unmatched_not_counted(self):
        s = planted(20, 2, 6)
        est = s.correspondence.clone()
        est[:5] = -1
        assert float(pointset_correspondence_rate(s.points, est, s.correspondence, [1e-9])[0]) == 1.0

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"permutation: expected \(4,\) integer indices"):
            pointset_correspondence_rate(torch.zeros(4, 2), torch.zeros(3, dtype=torch.long), torch.zeros(4, dtype=torch.long), [0.1])


class TestNormalPrecision:
    def test_values(self):
        true = torch.tensor([[1.0, 0.0], [1.0, 0.0]], dtype=DT)
        est = torch.tensor([[1.0, 0.0], [math.cos(0.05), math.sin(0.05)]], dtype=DT)
        assert pointset_normal_precision(est, true, [1.0, 5.0]).tolist() == [0.5, 1.0]
        assert abs(float(normal_angle_error(-est[1], true[1])) - math.degrees(0.05)) < 1e-9

    def test_exception(self):
        with pytest.raises(InputShapeError, match="true_normal"):
            normal_angle_error(torch.zeros(3), torch.zeros(2))


class TestSymmetryErrors:
    def test_perfect(self):
        s = planted(40, 3, 7)
        e_d, e_m = pointset_symmetry_errors(s.points, s.correspondence, s.normal, s.offset)
        assert abs(float(e_d) - 1) < 1e-12 and float(e_m) < 1e-12

    def test_wrong_plane(self):
        s = planted(40, 3, 8)
        _, e_m = pointset_symmetry_errors(s.points, s.correspondence, torch.tensor([0.0, 0.0, 1.0], dtype=DT), 0.0)
        assert float(e_m) > 0.01
