from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.geometry.mesh import Mesh
from torchsym.mesh.intrinsic import intrinsic_symmetry
from torchsym.mesh.synthetic import icosphere
from torchsym.viz import write_artifacts
from torchsym.viz.mesh import plot_mesh_symmetry, symmetry_colors


@pytest.fixture(scope="module")
def blob() -> tuple[Mesh, np.ndarray]:
    """An egg mirror symmetric across x = 0, and its mirror map."""
    from scipy.spatial import cKDTree

    s = icosphere(3)
    v = s.vertices.numpy()
    w = v * (1 + 0.5 * v[:, 1:2] + 0.3 * v[:, 2:3] ** 2)
    return Mesh(torch.from_numpy(w), s.faces), cKDTree(w).query(w * np.array([-1.0, 1.0, 1.0]))[1]


@pytest.fixture(scope="module")
def solved(blob):
    mesh, _ = blob
    return intrinsic_symmetry(mesh), mesh


class TestSymmetryColors:
    def test_partners_share_a_colour(self, blob):
        mesh, gt = blob
        v = mesh.vertices.numpy()
        vmap = gt.copy()
        vmap[:5] = -1
        rgb = symmetry_colors(v, vmap)
        assert rgb.shape == (v.shape[0], 3) and rgb.min() >= 0.0 and rgb.max() <= 1.0
        ok = vmap >= 0
        ok &= vmap[np.where(ok, vmap, 0)] >= 0  # both ends have a partner
        np.testing.assert_allclose(rgb[ok], rgb[vmap[ok]])
        assert np.all(rgb[:5] == 0.5)  # no partner: grey


class TestWriteArtifacts:
    def test_smoke(self, solved, tmp_path):
        result, mesh = solved
        paths = write_artifacts(result, mesh, tmp_path, "blob")
        assert [p.name for p in paths] == ["blob_symmetry.ply", "blob_symmetry.png", "blob_map.npy"]
        assert paths[0].read_bytes().startswith(b"ply")
        assert paths[1].read_bytes().startswith(b"\x89PNG")
        assert np.array_equal(np.load(paths[2]), result.map.numpy())

    def test_without_a_mesh_only_the_map(self, solved, tmp_path):
        result, mesh = solved
        paths = write_artifacts(result, mesh.vertices, tmp_path, "blob")
        assert [p.name for p in paths] == ["blob_map.npy"]

    def test_plot(self, solved, tmp_path):
        import matplotlib.image

        result, mesh = solved
        path = plot_mesh_symmetry(mesh, result.map.numpy(), tmp_path / "x.png", title="blob")
        img = matplotlib.image.imread(path)
        assert img.ndim == 3 and img.shape[1] > img.shape[0]  # two views side by side
        assert float(np.std(img[..., :3])) > 0.05  # something drawn
