from __future__ import annotations

import math

import numpy as np
import pytest

from torchsym.errors import InputShapeError
from torchsym.mesh import (
    heat_kernel_signature,
    hks_feature_points,
    hks_times,
    laplacian_eigen,
    ring_neighbourhood,
)


def _hks(v, f):
    evals, evecs = laplacian_eigen(v, f, 13)
    t = hks_times(evals, 50)
    h = heat_kernel_signature(evals, evecs, t)
    th = heat_kernel_signature(evals, evecs, np.array([4 * math.log(10) / evals[1]]))[:, 0]
    return h, hks_feature_points(th, ring_neighbourhood(f, v.shape[0], 2))


class TestHeatKernelSignature:
    def test_rigid_invariance(self, blob, rigid_motion):
        mesh, _ = blob
        v, f = mesh.vertices.numpy(), mesh.faces.numpy()
        rot, shift = rigid_motion
        h1, p1 = _hks(v, f)
        h2, p2 = _hks(v @ rot.T + shift, f)
        assert h1.shape == (v.shape[0], 50)
        np.testing.assert_allclose(h1, h2, rtol=1e-6, atol=1e-9)
        assert sorted(p1.tolist()) == sorted(p2.tolist())  # mirror pairs tie in value

    def test_feature_points_symmetric(self, blob):
        mesh, gt = blob
        _, points = _hks(mesh.vertices.numpy(), mesh.faces.numpy())
        assert set(gt[points].tolist()) == set(points.tolist())  # maxima come in mirror pairs

    def test_local_maxima(self):
        # a path graph 0-1-2-3-4 with values peaking at 1 and 4
        import scipy.sparse as sp

        adj = sp.diags([np.ones(4), np.ones(4)], [-1, 1]).tocsr()
        vals = np.array([0.0, 2.0, 1.0, 0.5, 3.0])
        assert hks_feature_points(vals, adj).tolist() == [4, 1]

    def test_times_exception(self):
        with pytest.raises(InputShapeError, match=r"evals: expected \(k,\) ascending with k >= 2 and evals\[1\] > 0"):
            hks_times(np.array([0.0, 0.0, 1.0]))
