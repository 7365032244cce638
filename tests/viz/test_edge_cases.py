"""Every picture writer on what was not found: a picture that says so, never a crash.

The ``texts`` fixture records every text drawn (matplotlib's figure texts and titles when a
figure is saved, OpenCV's ``putText``), so a test can check what the picture says.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

import torchsym
from torchsym.geometry.mesh import Mesh
from torchsym.viz import write_artifacts


@pytest.fixture
def texts(monkeypatch):
    import cv2
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    seen: list[str] = []
    save, put = Figure.savefig, cv2.putText

    def savefig(fig, *args, **kwargs):
        seen.extend(t.get_text() for t in fig.texts)
        seen.extend(t.get_text() for ax in fig.axes for t in (ax.title, *ax.texts))
        return save(fig, *args, **kwargs)

    def put_text(img, text, *args, **kwargs):
        seen.append(text)
        return put(img, text, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    monkeypatch.setattr(cv2, "putText", put_text)
    return seen


def _is_png(path) -> bool:
    from PIL import Image

    with Image.open(path) as im:
        return im.format == "PNG" and min(im.size) > 8


def _said(texts: list[str], words: str) -> bool:
    return any(words in t for t in texts)


# ---------------------------------------------------------------- point clouds


@pytest.fixture(scope="module")
def plane_result():
    cloud = torchsym.pointcloud.planted_symmetric_cloud(300, generator=0)
    return cloud.points, torchsym.pointcloud.detect_reflection_plane(cloud.points, n_starts=2, seed=0)


class TestReflectionPlane:
    def test_no_pairs(self, tmp_path, texts, plane_result):
        points, res = plane_result
        res = dataclasses.replace(res, pairs=res.pairs[:0], inliers=torch.zeros_like(res.inliers))
        paths = write_artifacts(res, points, tmp_path, "c")
        assert all(p.is_file() for p in paths) and _is_png(paths[-1])
        assert _said(texts, "no mirror pairs")

    def test_one_point(self, tmp_path, texts, plane_result):
        _, res = plane_result
        res = dataclasses.replace(res, pairs=res.pairs[:0], inliers=torch.zeros(1, dtype=torch.bool))
        paths = write_artifacts(res, torch.zeros(1, 3), tmp_path, "one")
        assert _is_png(paths[-1])
        assert _said(texts, "1 point")

    def test_all_points_equal(self, tmp_path, plane_result):
        _, res = plane_result
        res = dataclasses.replace(res, pairs=torch.zeros(0, 2, dtype=torch.long), inliers=torch.zeros(5, dtype=torch.bool))
        assert _is_png(write_artifacts(res, torch.ones(5, 3), tmp_path, "same")[-1])


class TestPointSymm:
    @pytest.mark.parametrize("d", [2, 3])
    def test_nothing_matched(self, tmp_path, texts, d):
        s = torchsym.make_symmetric_pointset(20, d, generator=torch.Generator().manual_seed(0))
        res = torchsym.point_symm(s.points)
        res = dataclasses.replace(res, permutation=torch.full_like(res.permutation, -1))
        assert _is_png(write_artifacts(res, s.points, tmp_path, "s")[0])
        assert _said(texts, "0 matched")

    def test_one_point(self, tmp_path, texts):
        s = torchsym.make_symmetric_pointset(20, 3, generator=torch.Generator().manual_seed(0))
        res = dataclasses.replace(torchsym.point_symm(s.points), permutation=torch.tensor([-1]))
        assert _is_png(write_artifacts(res, s.points[:1], tmp_path, "one")[0])
        assert _said(texts, "1 points") or _said(texts, "1 point")

    def test_image_axis_without_corners(self, tmp_path, texts):
        img = torch.zeros(1, 48, 48)
        img[0, 10:30, 8:20] = 1.0
        img = torch.maximum(img, img.flip(-1))
        res = torchsym.point_symm_image(img, ransac={"n_iters": 3})
        res = dataclasses.replace(
            res, corners=torch.zeros(0, 2), inliers=torch.zeros(0, dtype=torch.bool),
            permutation=torch.zeros(0, dtype=torch.long), segment=torch.full((2, 2), float("nan")),
        )
        assert _is_png(write_artifacts(res, img, tmp_path, "p")[0])
        assert _said(texts, "no symmetry axis")


# ---------------------------------------------------------------- meshes


@pytest.fixture(scope="module")
def egg() -> Mesh:
    from torchsym.mesh.synthetic import icosphere

    s = icosphere(2)
    v = s.vertices.numpy()
    return Mesh(torch.from_numpy(v * (1 + 0.5 * v[:, 1:2])), s.faces)


class TestMesh:
    def _result(self, mesh: Mesh, vmap: torch.Tensor):
        from torchsym.mesh.intrinsic.result import IntrinsicSymmetryResult

        k = torch.zeros(0, 0)
        return IntrinsicSymmetryResult(
            map=vmap, functional_map=k, rotation=k, map_before_refine=vmap, refined_functional_map=k,
            eigenvalues=torch.zeros(0), pairs=torch.zeros(0, 2, dtype=torch.long), feature_points=torch.zeros(0, dtype=torch.long),
            timings={}, num_components=1, dropped_vertices=0, correction_converged=False,
        )

    def test_empty_map(self, tmp_path, texts, egg):
        res = self._result(egg, torch.full((egg.vertices.shape[0],), -1))
        paths = write_artifacts(res, egg, tmp_path, "egg")
        assert [p.name for p in paths] == ["egg_symmetry.ply", "egg_symmetry.png", "egg_map.npy"]
        assert _is_png(paths[1])
        assert _said(texts, "no vertex has a mirror partner")

    def test_identity_map(self, tmp_path, texts, egg):
        # every vertex its own partner: consistent, but nothing is joined across a symmetry
        res = self._result(egg, torch.arange(egg.vertices.shape[0]))
        assert _is_png(write_artifacts(res, egg, tmp_path, "egg")[1])
        assert not any("partners joined" in t for t in texts)

    def test_one_triangle(self, tmp_path, texts):
        tri = Mesh(torch.tensor([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), torch.tensor([[0, 1, 2]]))
        res = self._result(tri, torch.tensor([1, 0, 2]))
        assert _is_png(write_artifacts(res, tri, tmp_path, "tri")[1])

    def test_map_of_another_mesh(self, tmp_path, texts, egg):
        res = self._result(egg, torch.tensor([0, 1]))
        assert _is_png(write_artifacts(res, egg, tmp_path, "egg")[1])
        assert _said(texts, "no vertex has a mirror partner")

    def test_partners_joined_and_poor_ones_marked(self, tmp_path, texts, egg):
        from scipy.spatial import cKDTree

        from torchsym.viz.mesh import partner_residual

        v = egg.vertices.numpy()
        gt = cKDTree(v).query(v * np.array([-1.0, 1.0, 1.0]))[1]
        res = self._result(egg, torch.from_numpy(gt))
        write_artifacts(res, egg, tmp_path, "egg")
        assert _said(texts, "partners joined") and _said(texts, "100 % of vertices with a consistent partner")
        bad = gt.copy()
        bad[:20] = bad[20:40]  # T(T(v)) != v and neighbours torn apart
        r = partner_residual(v, bad, egg.faces.numpy())
        assert (r[:20] > 0.1).all() and np.isfinite(r).all()


# ---------------------------------------------------------------- photos (maps, superpixels)


class TestPhotoMaps:
    def test_symmetry_map_without_axis(self, tmp_path, texts):
        from torchsym.image.symmetry_map import symmetry_map

        r = symmetry_map(torch.full((3, 40, 40), 0.2))
        paths = write_artifacts(r, None, tmp_path, "e")
        assert all(_is_png(p) for p in paths)
        assert _said(texts, "no symmetry axis")

    def test_superpixels_without_pairs(self, tmp_path, texts):
        from torchsym.image.symmslic import symm_slic

        img = torch.rand(3, 40, 48, generator=torch.Generator().manual_seed(0))
        r = symm_slic(img, n_superpixels=20)
        r = dataclasses.replace(r, pairs=r.pairs[:0], normals=r.normals[:0], offsets=r.offsets[:0])
        paths = write_artifacts(r, img, tmp_path, "s")
        assert _is_png(paths[0])
        assert _said(texts, "no mirror superpixel pairs")


# ---------------------------------------------------------------- multi-view


class TestMultiview:
    def _empty(self):
        from torchsym.multiview.result import Cameras, MultiviewPlaneResult

        cams = Cameras(image_names=[], intrinsics=torch.zeros(0, 3, 3), rotations=torch.zeros(0, 3, 3),
                       translations=torch.zeros(0, 3), sizes=torch.zeros(0, 2))
        return MultiviewPlaneResult(
            normal=torch.tensor([1.0, 0, 0]), offset=torch.tensor(0.0), found=False, confidence=0.0, score=0.0,
            points=torch.zeros(0, 3), colors=torch.zeros(0, 3, dtype=torch.uint8), pairs=torch.zeros(0, 2, dtype=torch.long),
            inliers=torch.zeros(0, dtype=torch.bool), cameras=cams, n_photos=0, notes=["no photo could be matched"], timings={},
        )

    def test_empty_result(self, tmp_path, texts):
        paths = write_artifacts(self._empty(), [], tmp_path, "scene")
        names = sorted(p.name for p in paths)
        assert names == ["scene_plane3d.png", "scene_views.png"]
        assert all(_is_png(p) for p in paths)
        assert _said(texts, "no symmetry found")
