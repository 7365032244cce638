from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.mesh import face_areas, validate_mesh
from torchsym.mesh.synthetic import icosphere, mirror_complete, punch_holes, twist


class TestMirrorComplete:
    def test_sphere(self):
        s = icosphere(2)
        s = type(s)(s.vertices * torch.tensor([1.0, 0.7, 0.5], dtype=s.vertices.dtype), s.faces)
        mesh, gt = mirror_complete(s, np.array([1.0, 0.2, 0.0]), 0.1)
        checked = validate_mesh(mesh, components="refuse")
        assert checked.num_components == 1
        g = gt.numpy()
        assert (g >= 0).all() and np.array_equal(g[g], np.arange(g.size))  # an involution
        v = mesh.vertices.numpy()
        n = np.array([1.0, 0.2, 0.0]) / np.linalg.norm([1.0, 0.2, 0.0])
        mirrored = v - 2 * ((v @ n) - 0.1)[:, None] * n
        np.testing.assert_allclose(mirrored, v[g], atol=1e-9)

    def test_real(self, shared_data):
        from torchsym.io import read_mesh

        mesh, gt = mirror_complete(read_mesh(shared_data / "meshes" / "pig.off", dtype=torch.float64))
        assert validate_mesh(mesh).mesh.num_faces == mesh.num_faces
        assert np.array_equal(gt.numpy()[gt.numpy()], np.arange(mesh.num_vertices))


def test_twist_keeps_edges_nearly():
    s = icosphere(2)
    t = twist(s, math.pi / 8)
    f = s.faces.numpy()
    e = f[:, [0, 1]]
    a = np.linalg.norm(s.vertices.numpy()[e[:, 0]] - s.vertices.numpy()[e[:, 1]], axis=1)
    b = np.linalg.norm(t.vertices.numpy()[e[:, 0]] - t.vertices.numpy()[e[:, 1]], axis=1)
    assert np.abs(b / a - 1).max() < 0.25 and not np.allclose(a, b)


class TestPunchHoles:
    def test_area(self):
        s = icosphere(3)
        gt = torch.arange(s.num_vertices)
        holed, g = punch_holes(s, gt, area_fraction=0.1, generator=torch.Generator().manual_seed(0))
        before = face_areas(s.vertices.numpy(), s.faces.numpy()).sum()
        after = face_areas(holed.vertices.numpy(), holed.faces.numpy()).sum()
        assert 0.85 < after / before < 0.92
        assert g.shape == (holed.num_vertices,) and (g >= 0).all()

    def test_exception(self):
        s = icosphere(1)
        with pytest.raises(InputValueError, match=r"area_fraction: expected a number in \(0, 0.5\), got 0.7"):
            punch_holes(s, torch.arange(s.num_vertices), area_fraction=0.7)
