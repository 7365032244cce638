from __future__ import annotations

import json

import numpy as np
import pytest
import torch

import torchsym
from torchsym.errors import ConfigError, InputFileError, InputShapeError, InputValueError, SolverError
from torchsym.features.sift import mirror_descriptors, mirror_permutation
from torchsym.geometry.reflection import reflect_points
from torchsym.metrics.multiview import align_cameras, camera_centers, plane_errors, transform_plane
from torchsym.multiview import (
    MultiviewPlaneSettings,
    best_buddy_pairs,
    consensus_plane,
    detect_multiview_plane,
    inlier_table,
    pair_planes,
)
from torchsym.multiview.synthetic import symmetric_scene

pycolmap = pytest.importorskip("pycolmap")


@pytest.fixture(scope="module")
def scene():
    return symmetric_scene(6, height=360, width=480, generator=torch.Generator().manual_seed(2))


@pytest.fixture(scope="module")
def result(scene):
    return detect_multiview_plane(scene.images)


def _errors(result, scene):
    idx = [int(n.split("_")[1].split(".")[0]) for n in result.cameras.image_names]
    src = camera_centers(result.cameras.rotations, result.cameras.translations)
    dst = camera_centers(scene.rotations[idx], scene.translations[idx])
    n, b = transform_plane(result.normal, result.offset, *align_cameras(src, dst))
    return plane_errors(n, b, scene.normal, scene.offset, torch.tensor([0.0, 0.0, 0.4], dtype=torch.float64))


class TestMirrorPermutation:
    def test_opencv_layout_matches_colmap_on_a_flipped_photo(self):
        from torchsym.multiview.synthetic import _texture

        img = np.ascontiguousarray(_texture(np.random.default_rng(0), 240, 320)[:, :, 1])
        options = pycolmap.FeatureExtractionOptions(num_threads=1)
        sift = pycolmap.Sift(options)
        k1, d1 = sift.extract(img)
        k2, d2 = sift.extract(np.ascontiguousarray(img[:, ::-1]))
        from scipy.spatial import cKDTree

        p2 = k2[:, :2].copy()
        p2[:, 0] = img.shape[1] - p2[:, 0]
        dist, j = cKDTree(p2).query(k1[:, :2])
        ok = dist < 0.3
        assert ok.sum() > 50
        a, b = torch.from_numpy(d1[ok]), torch.from_numpy(d2[j[ok]])
        err = (mirror_descriptors(a, layout="opencv") - b).abs().sum(1) / b.abs().sum(1)
        assert float(err.median()) < 0.02
        err_kornia = (mirror_descriptors(a, layout="kornia") - b).abs().sum(1) / b.abs().sum(1)
        assert float(err_kornia.median()) > 0.3

    def test_involution(self):
        p = mirror_permutation(layout="opencv")
        assert torch.equal(p[p], torch.arange(128))

    def test_exception(self):
        with pytest.raises(InputValueError, match="layout"):
            mirror_permutation(layout="vlfeat")


class TestPairs:
    def test_best_buddies_found_and_duplicates_dropped(self):
        g = torch.Generator().manual_seed(0)
        d = torch.rand(40, 128, generator=g)
        pts = torch.randn(40, 3, generator=g, dtype=torch.float64)
        d[20:] = mirror_descriptors(d[:20], layout="opencv")  # point j + 20 mirrors point j
        pairs = best_buddy_pairs(pts, d)
        assert sorted(map(tuple, pairs.tolist())) == [(j, j + 20) for j in range(20)]
        pts[25] = pts[5]  # a duplicate point: zero-length pair
        pairs = best_buddy_pairs(pts, d, min_chord=1e-9)
        assert (5, 25) not in set(map(tuple, pairs.tolist())) and len(pairs) == 19


class TestPlane:
    def test_pair_planes_bisect(self):
        left = torch.tensor([[1.0, 2.0, 3.0]], dtype=torch.float64)
        right = torch.tensor([[3.0, 2.0, 3.0]], dtype=torch.float64)
        n, b = pair_planes(left, right)
        assert torch.allclose(n, torch.tensor([[1.0, 0.0, 0.0]], dtype=torch.float64)) and float(b) == -2.0

    def test_inlier_table_by_hand(self):
        n = torch.tensor([[1.0, 0.0, 0.0]], dtype=torch.float64)
        b = torch.zeros(1, dtype=torch.float64)
        left = torch.tensor([[-1.0, 0, 0], [-1.0, 0, 0], [-1.0, 0, 0], [-1.0, 0, 0], [1.0, 0, 0]], dtype=torch.float64)
        right = torch.tensor(
            [[1.0, 0, 0], [1.03, 0, 0], [1.05, 0, 0], [1.0, 0.03, 0], [2.0, 0, 0]], dtype=torch.float64
        )  # exact; ratio 1/1.03 ok; 1/1.05 out; chord 0.86 deg off ok; same side
        table = inlier_table(left, right, n, b, eps_d=0.04, eps_theta=1.0)
        assert table.tolist() == [[True, True, False, True, False]]

    def test_consensus_with_outliers(self):
        g = torch.Generator().manual_seed(1)
        normal = torch.nn.functional.normalize(torch.randn(3, generator=g, dtype=torch.float64), dim=0)
        left = torch.randn(60, 3, generator=g, dtype=torch.float64)
        right = reflect_points(left, normal, torch.tensor(0.3, dtype=torch.float64))
        right = right + 1e-4 * torch.randn(60, 3, generator=g, dtype=torch.float64)
        bad_l, bad_r = torch.randn(140, 3, generator=g, dtype=torch.float64), torch.randn(140, 3, generator=g, dtype=torch.float64)
        c = consensus_plane(torch.cat([left, bad_l]), torch.cat([right, bad_r]), eps_d=0.04, eps_theta=1.0, margin_angle=5.0, lam=0.25)
        angle, _ = plane_errors(c.normal, c.offset, normal, torch.tensor(0.3, dtype=torch.float64), torch.zeros(3, dtype=torch.float64))
        assert angle < 0.05 and int(c.inliers[:60].sum()) >= 58 and int(c.inliers[60:].sum()) <= 2
        assert c.runner_up < 10


class TestDetectMultiviewPlane:
    def test_synthetic_plane_recovered(self, result, scene):
        assert result.found and result.score > 0.9
        angle, offset = _errors(result, scene)
        assert angle < 0.5 and offset < 0.02  # the facade is 4 units wide
        assert len(result.cameras.image_names) == 6 and result.points.shape[1] == 3
        json.dumps(result.to_dict(), allow_nan=False)

    @pytest.mark.slow
    def test_no_symmetry_reported(self):
        s = symmetric_scene(6, height=360, width=480, symmetric=False, generator=torch.Generator().manual_seed(2))
        r = detect_multiview_plane(s.images)
        assert not r.found and r.score < 0.3 and "no symmetry found" in r.notes[0]
        assert float(r.normal.abs().sum()) == 0.0

    @pytest.mark.slow
    def test_same_seed_same_bits(self, scene, result):
        again = detect_multiview_plane(scene.images)
        a, b = result.to_dict(), again.to_dict()
        a.pop("timings"), b.pop("timings")
        assert a == b

    @pytest.mark.slow
    def test_artifacts(self, result, scene, tmp_path):
        from torchsym.viz import write_artifacts

        paths = write_artifacts(result, scene.images, tmp_path, "scene")
        names = sorted(p.name for p in paths)
        assert names == ["scene_colmap", "scene_plane3d.png", "scene_views.png"]
        assert (tmp_path / "scene_colmap" / "points3D.bin").is_file()

    def test_fewer_than_two_photos(self, scene):
        with pytest.raises(InputValueError, match="images: expected at least 2 photos"):
            detect_multiview_plane(scene.images[:1])

    def test_unreadable_file(self, tmp_path, scene):
        import cv2

        good = tmp_path / "a.png"
        cv2.imwrite(str(good), (scene.images[0].permute(1, 2, 0).numpy() * 255).astype(np.uint8))
        bad = tmp_path / "b.jpg"
        bad.write_bytes(b"not a jpeg")
        with pytest.raises(InputFileError, match="b.jpg' cannot be read"):
            detect_multiview_plane([good, bad])

    def test_photos_that_do_not_overlap(self):
        g = torch.Generator().manual_seed(5)
        noise = [torch.rand(3, 200, 200, generator=g) for _ in range(3)]
        with pytest.raises(SolverError, match="reconstruction failed"):
            detect_multiview_plane(noise)

    def test_wrong_shape(self):
        with pytest.raises(InputShapeError, match="images"):
            detect_multiview_plane(torch.zeros(3, 32, 32))

    def test_settings_checked(self):
        with pytest.raises(ConfigError, match=r"consensus\.eps_theta: expected a finite number > 0.0"):
            MultiviewPlaneSettings.from_dict({"consensus": {"eps_theta": 0}})


class TestAlignCameras:
    def test_recovers_similarity(self):
        g = torch.Generator().manual_seed(0)
        src = torch.randn(6, 3, generator=g, dtype=torch.float64)
        q, _ = torch.linalg.qr(torch.randn(3, 3, generator=g, dtype=torch.float64))
        if torch.det(q) < 0:
            q[:, 0] *= -1
        dst = 2.5 * src @ q.T + torch.tensor([1.0, -2.0, 0.5], dtype=torch.float64)
        s, r, t = align_cameras(src, dst)
        assert abs(float(s) - 2.5) < 1e-9 and torch.allclose(r, q) and torch.allclose(2.5 * src @ r.T + t, dst)


def test_votes_equal_the_table():
    g = torch.Generator().manual_seed(4)
    normal = torch.nn.functional.normalize(torch.randn(3, generator=g, dtype=torch.float64), dim=0)
    left = torch.randn(300, 3, generator=g, dtype=torch.float64)
    right = torch.randn(300, 3, generator=g, dtype=torch.float64)
    right[:100] = reflect_points(left[:100], normal, torch.tensor(0.1, dtype=torch.float64))
    from torchsym.multiview.plane import plane_votes

    n, b = pair_planes(left, right)
    table = inlier_table(left, right, n, b, 0.04, 1.0)
    assert torch.equal(plane_votes(left, right, n, b, 0.04, 1.0), table.sum(1))


def test_number_by_name(scene, tmp_path):
    """Photos extracted out of name order get ids in name order, each keeping its features."""
    import cv2

    from torchsym.multiview.reconstruct import number_by_name

    names = [f"view_{i}.png" for i in range(3)]
    for name, image in zip(names, scene.images[:3]):
        a = (image.clamp(0, 1) * 255).round().to(torch.uint8).expand(3, -1, -1).permute(1, 2, 0).numpy()
        cv2.imwrite(str(tmp_path / name), a)
    db = tmp_path / "database.db"
    options = pycolmap.FeatureExtractionOptions(num_threads=1)
    pycolmap.extract_features(db, tmp_path, image_names=names[::-1], camera_mode=pycolmap.CameraMode.SINGLE,
                              extraction_options=options, device=pycolmap.Device.cpu)
    before = pycolmap.Database.open(str(db))
    features = {im.name: before.read_descriptors(im.image_id).data.copy() for im in before.read_all_images()}
    before.close()
    number_by_name(db)
    after = pycolmap.Database.open(str(db))
    images = sorted(after.read_all_images(), key=lambda im: im.image_id)
    assert [im.name for im in images] == names
    for im in images:
        np.testing.assert_array_equal(after.read_descriptors(im.image_id).data, features[im.name])
    after.close()
