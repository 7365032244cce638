from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.mesh.synthetic import icosphere
from torchsym.metrics.mesh import correspondence_rate, mesh_rate, symmetry_threshold


@pytest.fixture(scope="module")
def sphere():
    s = icosphere(3)
    v = s.vertices.numpy()
    from scipy.spatial import cKDTree

    gt = cKDTree(v).query(v * np.array([-1.0, 1, 1]))[1]
    return s, gt


class TestCorrespondenceRate:
    def test_threshold(self, sphere):
        s, _ = sphere
        assert symmetry_threshold(s) == pytest.approx(math.sqrt(4 * math.pi / (20 * math.pi)), rel=0.01)

    def test_perfect_and_identity(self, sphere):
        s, gt = sphere
        assert correspondence_rate(s, gt, ground_truth=gt).rate == 1.0
        ident = correspondence_rate(s, np.arange(s.num_vertices), ground_truth=gt)
        # only vertices within the tolerance of the mirror plane are right under the identity
        x = np.abs(s.vertices.numpy()[:, 0])
        assert ident.rate == pytest.approx(float((2 * x < ident.threshold).mean()), abs=0.05)
        assert 0.0 < ident.rate < 0.5

    def test_landmarks_and_missing(self, sphere):
        s, gt = sphere
        lm = np.stack([np.arange(10), gt[:10]], axis=1)
        pred = torch.from_numpy(gt.copy())
        pred[3] = -1
        score = correspondence_rate(s, pred, landmarks=lm)
        assert score.num_evaluated == 10 and score.rate == pytest.approx(0.9)
        assert torch.isinf(score.errors[3])

    def test_exception(self, sphere):
        s, gt = sphere
        with pytest.raises(InputShapeError, match=r"predicted: expected \(642,\) to match the mesh's vertices, got \(3,\)"):
            correspondence_rate(s, [1, 2, 3], ground_truth=gt)
        with pytest.raises(InputShapeError, match="expected exactly one of them, got neither"):
            correspondence_rate(s, gt)
        with pytest.raises(InputShapeError, match=r"landmarks: expected \(L, 2\) vertex pairs"):
            correspondence_rate(s, gt, landmarks=np.zeros((4, 3), dtype=int))


def test_mesh_rate():
    assert mesh_rate([0.9, 0.8, 0.5, 0.75]) == 0.5
    assert math.isnan(mesh_rate([]))
