"""The objects users already hold (trimesh, Open3D, PIL, channels-last photo arrays) as inputs."""

from __future__ import annotations

import numpy as np
import pytest
import torch

import torchsym
from torchsym.errors import InputShapeError
from torchsym.io.objects import from_user_object, is_channels_last_image


class _O3dPointCloud:
    """The part of ``open3d.geometry.PointCloud`` torchsym reads: ``points``."""

    def __init__(self, points: np.ndarray) -> None:
        self.points = points


class _O3dTriangleMesh:
    """The part of ``open3d.geometry.TriangleMesh`` torchsym reads."""

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray) -> None:
        self.vertices, self.triangles = vertices, triangles


@pytest.fixture
def chair() -> np.ndarray:
    return torchsym.data.sample_pointcloud().numpy()


@pytest.fixture
def photo() -> np.ndarray:
    g = np.random.default_rng(0)
    img = (g.random((96, 128, 3)) * 255).astype(np.uint8)
    return np.concatenate([img[:, :64], img[:, :64][:, ::-1]], axis=1)  # mirrored about x = 64


def _tetra() -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return v, f


class TestFromUserObject:
    def test_open3d_point_cloud(self, chair):
        got = from_user_object(_O3dPointCloud(chair))
        assert got.shape == (len(chair), 3) and got.dtype == torch.float32

    def test_open3d_triangle_mesh(self):
        v, f = _tetra()
        got = from_user_object(_O3dTriangleMesh(v, f))
        assert isinstance(got, torchsym.Mesh) and got.num_faces == 4

    def test_trimesh(self):
        trimesh = pytest.importorskip("trimesh")
        v, f = _tetra()
        mesh = from_user_object(trimesh.Trimesh(v, f, process=False))
        assert isinstance(mesh, torchsym.Mesh) and mesh.num_vertices == 4
        cloud = from_user_object(trimesh.PointCloud(v))
        assert torch.equal(cloud, torch.from_numpy(v).float())

    def test_pil_image(self, photo):
        from PIL import Image

        got = from_user_object(Image.fromarray(photo).convert("RGBA"))
        assert got.shape == (3, 96, 128) and got.dtype == torch.uint8
        assert torch.equal(got, torch.from_numpy(photo).permute(2, 0, 1))

    @pytest.mark.parametrize("channels", [3, 4])
    def test_channels_last_array(self, photo, channels):
        arr = np.concatenate([photo, np.full(photo.shape[:2] + (1,), 255, np.uint8)], axis=2)[..., :channels]
        assert is_channels_last_image(arr)
        assert from_user_object(arr).shape == (3, 96, 128)

    def test_point_arrays_and_chw_images_unchanged(self, chair):
        assert from_user_object(chair) is chair
        chw = np.zeros((3, 32, 32), np.uint8)
        assert from_user_object(chw) is chw and not is_channels_last_image(chw)
        assert not is_channels_last_image(np.zeros((32, 32, 3), np.float32))  # float: no guess

    def test_exception(self):
        with pytest.raises(InputShapeError, match="points"):
            from_user_object(_O3dPointCloud(np.zeros((5, 2))))
        with pytest.raises(InputShapeError, match="faces"):
            from_user_object(_O3dTriangleMesh(*_tetra()[:1], np.zeros((2, 4), np.int64)))


class TestDetect:
    def test_same_plane_as_the_tensor(self, chair):
        want = torchsym.detect(torch.from_numpy(chair))
        got = torchsym.detect(_O3dPointCloud(chair))
        assert torch.equal(got.normal, want.normal)

    def test_photo_array_as_opencv_gives_it(self, photo):
        want = torchsym.detect(torch.from_numpy(photo).permute(2, 0, 1).contiguous())
        got = torchsym.detect(photo)
        assert torch.equal(got.axes, want.axes)

    def test_unknown_object_is_named(self):
        with pytest.raises(InputShapeError, match="PIL image, got object"):
            torchsym.detect(object())
