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


@pytest.fixture(scope="module")
def tall() -> tuple[Mesh, np.ndarray]:
    """An egg longest along y (height 2, depth 1 along z, width 1 along x) mirrored across x = 0."""
    from scipy.spatial import cKDTree

    s = icosphere(3)
    v = s.vertices.numpy() * np.array([0.5, 1.0, 0.5])
    v = v * (1 + 0.3 * v[:, 1:2])
    return Mesh(torch.from_numpy(v), s.faces), cKDTree(v).query(v * np.array([-1.0, 1.0, 1.0]))[1]


class TestMeshFrame:
    def test_the_file_up_axis(self, tall):
        # longest along y and mirrored across x = 0: y points up, the view along +-z
        from torchsym.viz.mesh import mesh_frame

        mesh, gt = tall
        up, view, name = mesh_frame(mesh.vertices.numpy(), gt)
        np.testing.assert_allclose(up, [0.0, 1.0, 0.0], atol=1e-6)
        assert abs(view[2]) > 0.99 and name == "seen from +z"

    def test_the_same_shape_looks_the_same(self, tall):
        from torchsym.viz.mesh import mesh_frame

        mesh, gt = tall
        v = mesh.vertices.numpy()
        perm = np.random.default_rng(0).permutation(len(v))
        inv = np.argsort(perm)
        up, view, _ = mesh_frame(v, gt)
        up2, view2, _ = mesh_frame(v[perm], inv[gt[perm]])  # the same shape, vertices reordered
        np.testing.assert_allclose(up2, up, atol=1e-9)
        np.testing.assert_allclose(view2, view, atol=1e-9)

    def test_sign_rule_off_the_file_axes(self, tall):
        # the mirror normal turned to (1, 1, 1) / sqrt(3): no file axis lies within 30 degrees of its plane
        from scipy.spatial.transform import Rotation

        from torchsym.viz.mesh import mesh_frame

        mesh, gt = tall
        rot = Rotation.align_vectors([[1.0, 1.0, 1.0]], [[1.0, 0.0, 0.0]])[0].as_matrix()
        v = mesh.vertices.numpy() @ rot.T
        up, view, _ = mesh_frame(v, gt)
        assert up[np.argmax(np.abs(up))] > 0 and view[np.argmax(np.abs(view))] > 0
        np.testing.assert_allclose(abs(up @ (rot @ [0.0, 1.0, 0.0])), 1.0, atol=0.01)  # still the egg's long axis
        up2, _, _ = mesh_frame(-v, gt)  # the same rule whatever the singular vectors' signs
        assert up2[np.argmax(np.abs(up2))] > 0

    def test_human_upright(self, shared_data):
        from scipy.spatial import cKDTree

        from torchsym.io.read import read_mesh
        from torchsym.viz.mesh import mesh_frame

        v = read_mesh(shared_data / "meshes_shrec07" / "human_1.off").vertices.double().numpy()
        mid = 0.5 * (v.max(0) + v.min(0))
        mirrored = v.copy()
        mirrored[:, 0] = 2 * mid[0] - v[:, 0]
        up, _, _ = mesh_frame(v, cKDTree(v).query(mirrored)[1])
        np.testing.assert_allclose(up, [0.0, 0.0, 1.0], atol=0.02)  # the file's +z: head up


class TestPartnerResidual:
    def test_a_mirror_is_consistent(self, blob):
        from torchsym.viz.mesh import partner_residual

        mesh, gt = blob
        v = mesh.vertices.numpy()
        r = partner_residual(v, gt, mesh.faces.numpy())
        edge = np.linalg.norm(v[mesh.faces[:, 0]] - v[mesh.faces[:, 1]], axis=1).max()
        assert r.max() <= 2 * edge  # mirror of a mirror, to a vertex's snapping
        missing = gt.copy()
        missing[0] = -1
        assert np.isinf(partner_residual(v, missing)[[0, gt[0]]]).all()
