"""Solving a large mesh on a decimated copy (torchsym.mesh.intrinsic.coarsen and its use in the solver)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.errors import ConfigError
from torchsym.mesh import intrinsic_symmetry
from torchsym.mesh.intrinsic import IntrinsicSymmetrySettings
from torchsym.mesh.intrinsic.coarsen import carry_map, coarse_copy
from torchsym.mesh.operators import edge_face_counts, face_areas
from torchsym.metrics.mesh import correspondence_rate


class TestCoarseCopy:
    def test_smoke(self, blob):
        mesh, _ = blob
        v, f = mesh.vertices.double().numpy(), mesh.faces.numpy()
        copy = coarse_copy(v, f, 300, np.random.default_rng(0))
        assert 0.7 * 300 <= copy.vertices.shape[0] <= 300
        assert copy.faces.min() >= 0 and copy.faces.max() < copy.vertices.shape[0]
        assert copy.to_input.shape == (copy.vertices.shape[0],) and copy.nearest.shape == (v.shape[0],)
        _, counts = edge_face_counts(copy.faces)
        assert counts.max() <= 2  # manifold edges

    def test_carry_identity(self, blob):
        mesh, _ = blob
        v, f = mesh.vertices.double().numpy(), mesh.faces.numpy()
        copy = coarse_copy(v, f, 300, np.random.default_rng(0))
        carried = carry_map(copy, v, np.arange(copy.vertices.shape[0]))
        # the identity of the copy carries to a map that moves each vertex by about one copy spacing
        moved = np.linalg.norm(v[carried] - v, axis=1)
        assert np.median(moved) < 2.0 * np.sqrt(face_areas(v, f).sum() / 300)
        assert (carry_map(copy, v, np.full(copy.vertices.shape[0], -1)) == -1).all()


class TestSolveOnCopy:
    def test_value(self, blob):
        mesh, gt = blob
        result = intrinsic_symmetry(mesh, coarse={"max_vertices": 600, "n_vertices": 400})
        assert result.map.shape == (mesh.num_vertices,)
        assert result.notes[0].startswith("solved on a copy decimated to")
        assert {"coarsen", "carry"} <= set(result.timings)
        assert result.pairs.max() < mesh.num_vertices and result.map_before_refine.shape == (mesh.num_vertices,)
        assert correspondence_rate(mesh, result.map, ground_truth=gt).rate > 0.95

    def test_the_input_s_boundary(self, blob, monkeypatch):
        """The copy's own small holes are no holes of a closed input: step 9's limit is the closed meshes' (and step 10 off)."""
        from torchsym.mesh.intrinsic import solver

        inner = []
        real = solver.intrinsic_symmetry

        def spy(mesh, settings=None, **kwargs):
            inner.append(settings)
            return real(mesh, settings, **kwargs)

        monkeypatch.setattr(solver, "intrinsic_symmetry", spy)
        mesh, _ = blob
        real(mesh, coarse={"max_vertices": 600, "n_vertices": 400}, select={"max_distortion": 0.2})
        assert inner[0].select.max_distortion_open == inner[0].select.max_distortion == 0.2
        assert not inner[0].extrinsic.enabled

    def test_small_mesh_untouched(self, blob, solved):
        mesh, _ = blob
        result, _, _ = solved
        assert not any(n.startswith("solved on a copy") for n in result.notes)

    def test_exception(self):
        with pytest.raises(ConfigError, match="coarse.n_vertices"):
            IntrinsicSymmetrySettings(coarse={"max_vertices": 100, "n_vertices": 200})
