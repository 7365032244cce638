from __future__ import annotations

import numpy as np
import pytest

from torchsym.errors import InputShapeError
from torchsym.mesh import (
    edge_graph,
    eigenfunction_signs,
    laplacian_eigen,
    pair_affinity,
    symmetric_pairs,
)


class TestSymmetricPairs:
    def test_pairs_planted(self):
        # four points: 0 <-> 2 and 1 <-> 3 have equal descriptors and opposite signs somewhere
        hks = np.array([[1.0, 2.0], [5.0, 1.0], [1.0, 2.01], [5.0, 1.02]])
        evecs_at = np.array([[1.0, 0.5, 1.0], [1.0, -0.5, 1.0], [1.0, -0.5, -1.0], [1.0, 0.5, -1.0]])
        pairs, cost = symmetric_pairs(np.array([10, 11, 12, 13]), hks, evecs_at, max_pairs=5)
        assert sorted(map(tuple, pairs.tolist())) == [(10, 12), (11, 13)]
        assert (cost < 0.5).all()

    def test_equal_signs_never_paired(self):
        hks = np.array([[1.0, 2.0], [1.0, 2.0]])
        evecs_at = np.array([[1.0, 0.5], [1.0, 0.5]])  # same sign vector: neighbours
        pairs, _ = symmetric_pairs(np.array([0, 1]), hks, evecs_at)
        assert pairs.shape == (0, 2)
        _, _, cost = pair_affinity(hks, evecs_at, penalty=1e6)
        assert cost[0] >= 1e6

    def test_isometry_check(self):
        hks = np.ones((4, 2))
        evecs_at = np.array([[1.0, 1.0], [1.0, -1.0], [1.0, 1.0], [1.0, -1.0]])
        # 0-1 and 2-3 pair up, but d(0, 2) != d(1, 3): no isometry maps one pair onto the other
        dist = np.array([[0, 1, 1, 3], [1, 0, 3, 5], [1, 3, 0, 1], [3, 5, 1, 0]], dtype=float)
        pairs, _ = symmetric_pairs(np.arange(4), hks, evecs_at, distances=dist)
        assert pairs.shape[0] == 1

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"evecs_at: expected \(3, k\)"):
            pair_affinity(np.ones((3, 2)), np.ones((2, 4)))


class TestEigenfunctionSigns:
    def test_blob(self, blob):
        mesh, gt = blob
        v, f = mesh.vertices.numpy(), mesh.faces.numpy()
        evals, evecs = laplacian_eigen(v, f, 13)
        truth = np.sign((evecs * evecs[gt]).sum(axis=0))
        # two symmetric vertices far from the plane x = 0
        a = int(np.argmax(v[:, 0]))
        signs, conf = eigenfunction_signs(evecs, v, edge_graph(v, f), np.array([[a, gt[a]]]))
        used = signs != 0
        assert used.sum() >= 10
        assert (signs[used] == truth[used]).all()
        assert (np.abs(conf) <= 1 + 1e-9).all()

    def test_no_pairs(self, blob):
        mesh, _ = blob
        v, f = mesh.vertices.numpy(), mesh.faces.numpy()
        evecs = np.random.default_rng(0).standard_normal((v.shape[0], 4))
        signs, _ = eigenfunction_signs(evecs, v, edge_graph(v, f), np.zeros((0, 2), dtype=np.int64))
        assert (signs == 0).all()
