from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.mesh import Mesh
from torchsym.mesh.synthetic import icosphere
from torchsym.metrics.mesh import correspondence_rate, extremity_vertices, mesh_rate, symmetry_threshold


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

    def test_surface_against_edges(self):
        # a flat strip: vertex 0's true mirror is at 45 degrees to the grid, 0.30 away in
        # the plane (under the tolerance) but 0.42 along the edges (over it)
        n = 10
        xs, ys = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
        v = np.stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)], axis=1)
        idx = np.arange(v.shape[0]).reshape(n + 1, n + 1)
        a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
        mesh = Mesh(torch.from_numpy(v), torch.from_numpy(np.concatenate([np.stack([a, b, d], 1), np.stack([b, c, d], 1)])))
        thr = symmetry_threshold(mesh)  # sqrt(1 / 20 pi) = 0.126
        gt = np.full(v.shape[0], -1)
        gt[idx[5, 5]] = idx[5, 5]
        gt[idx[2, 2]] = idx[2, 2]
        pred = np.arange(v.shape[0])
        pred[idx[5, 5]] = idx[6, 6]  # 0.141 straight (over), 0.2 along edges
        pred[idx[2, 2]] = idx[3, 2]  # 0.1 straight and along an edge (under)
        surface = correspondence_rate(mesh, pred, ground_truth=gt)
        edges = correspondence_rate(mesh, pred, ground_truth=gt, geodesics="edges")
        assert edges.geodesics == "edges" and surface.geodesics == "surface"
        assert edges.rate == 0.5 and surface.rate == 0.5
        # with the tolerance between the straight 0.141 and the edge path 0.2, only the surface counts it
        surface = correspondence_rate(mesh, pred, ground_truth=gt, threshold=0.15)
        edges = correspondence_rate(mesh, pred, ground_truth=gt, threshold=0.15, geodesics="edges")
        assert edges.rate == 0.5 and surface.rate == 1.0
        assert float(surface.errors[1]) == pytest.approx(math.sqrt(0.02), abs=1e-9) and float(edges.errors[1]) == pytest.approx(0.2)
        assert thr == pytest.approx(math.sqrt(1 / (20 * math.pi)))

    def test_exception(self, sphere):
        s, gt = sphere
        with pytest.raises(InputShapeError, match=r"predicted: expected \(642,\) to match the mesh's vertices, got \(3,\)"):
            correspondence_rate(s, [1, 2, 3], ground_truth=gt)
        with pytest.raises(InputShapeError, match="expected exactly one of them, got neither"):
            correspondence_rate(s, gt)
        with pytest.raises(InputShapeError, match=r"landmarks: expected \(L, 2\) vertex pairs"):
            correspondence_rate(s, gt, landmarks=np.zeros((4, 3), dtype=int))
        with pytest.raises(InputValueError, match="geodesics: expected one of 'surface', 'edges', got 'exact'"):
            correspondence_rate(s, gt, ground_truth=gt, geodesics="exact")


def test_mesh_rate():
    assert mesh_rate([0.9, 0.8, 0.5, 0.75]) == 0.5
    assert math.isnan(mesh_rate([]))


@pytest.fixture(scope="module")
def dumbbell():
    # an ellipsoid stretched along x: its extremities are the two ends of the long axis
    s = icosphere(3)
    v = s.vertices.numpy() * np.array([3.0, 1.0, 1.0])
    return Mesh(torch.from_numpy(v), s.faces)


class TestExtremityVertices:
    def test_smoke(self, dumbbell):
        ext = extremity_vertices(dumbbell, share=0.05)
        assert ext.dtype == torch.int64 and ext.shape == (round(0.05 * dumbbell.num_vertices),)
        x = dumbbell.vertices.numpy()[ext.numpy(), 0]
        assert (np.abs(x) > 2.5).all()  # at the ends of the long axis
        assert (x > 0).any() and (x < 0).any()

    def test_candidates(self, dumbbell):
        cand = np.flatnonzero(dumbbell.vertices.numpy()[:, 0] > 0)
        ext = extremity_vertices(dumbbell, share=0.1, candidates=cand).numpy()
        assert np.isin(ext, cand).all() and ext.size == round(0.1 * cand.size)
        mask = torch.zeros(dumbbell.num_vertices, dtype=torch.bool)
        mask[cand] = True
        assert (extremity_vertices(dumbbell, share=0.1, candidates=mask).numpy() == ext).all()

    def test_deterministic(self, dumbbell):
        a = extremity_vertices(dumbbell, generator=torch.Generator().manual_seed(3))
        b = extremity_vertices(dumbbell, generator=torch.Generator().manual_seed(3))
        assert torch.equal(a, b)

    def test_exception(self, dumbbell):
        with pytest.raises(InputValueError, match="share"):
            extremity_vertices(dumbbell, share=0.0)
        with pytest.raises(InputValueError, match="n_sources"):
            extremity_vertices(dumbbell, n_sources=0)
        with pytest.raises(InputShapeError, match="candidates"):
            extremity_vertices(dumbbell, candidates=[dumbbell.num_vertices])
