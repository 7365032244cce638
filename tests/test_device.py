"""Every solver on a CUDA device: results come back on the input's device and agree with the CPU.

Skipped where no CUDA device is present (CI has none); run on a GPU machine with
``pytest tests/test_device.py``. Nearest neighbours on a GPU go through chunked
``torch.cdist`` instead of the CPU's kd-tree, so each solver is checked against its own
CPU result and against the planted truth.
"""

from __future__ import annotations

import math
import os

import pytest
import torch

import torchsym
from torchsym.geometry import plane_angle
from torchsym.manifolds import (
    PlaneRotations,
    ProductManifold,
    SpecialOrthogonal,
    Stiefel,
)
from torchsym.matching.knn import KNNIndex
from torchsym.optim import trust_region

# TORCHSYM_TEST_DEVICE=cpu runs the same checks on the CPU (a dry run of the file itself)
CUDA = torch.device(os.environ.get("TORCHSYM_TEST_DEVICE", "cuda"))
pytestmark = pytest.mark.skipif(
    CUDA.type == "cuda" and not torch.cuda.is_available(), reason="no CUDA device"
)
DT = torch.float64


def gen(seed: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


def deg(a: torch.Tensor, b: torch.Tensor) -> float:
    return (
        float(plane_angle(a.detach().cpu().double(), b.detach().cpu().double()))
        * 180
        / math.pi
    )


def tensors_on(result, device_type: str) -> list[str]:
    """Names of the result's tensor fields that are not on ``device_type``."""
    return [
        k
        for k, v in vars(result).items()
        if isinstance(v, torch.Tensor) and v.device.type != device_type
    ]


class TestNearestNeighbours:
    def test_cdist_path_equals_kdtree(self):
        pts = torch.rand(5000, 3, generator=gen(0), dtype=DT)
        q = torch.rand(3000, 3, generator=gen(1), dtype=DT)
        d_cpu, i_cpu = KNNIndex(pts).query(q, k=4)
        d_gpu, i_gpu = KNNIndex(pts.to(CUDA), chunk=1000).query(q.to(CUDA), k=4)
        assert i_gpu.device.type == CUDA.type
        torch.testing.assert_close(d_gpu.cpu(), d_cpu)
        assert torch.equal(i_gpu.cpu(), i_cpu)

    def test_large_queries_use_the_host_tree(self):
        pts = torch.rand(4000, 3, generator=gen(4))
        q = torch.rand(1000, 3, generator=gen(5))
        d_cpu, i_cpu = KNNIndex(pts).query(q, k=3)
        index = KNNIndex(pts.to(CUDA), brute_force_max=0)
        d_gpu, i_gpu = index.query(q.to(CUDA), k=3)
        assert i_gpu.device.type == CUDA.type and d_gpu.dtype == torch.float32
        assert torch.equal(i_gpu.cpu(), i_cpu)
        torch.testing.assert_close(d_gpu.cpu(), d_cpu)

    def test_max_distance(self):
        pts = torch.rand(2000, 3, generator=gen(2), dtype=DT)
        q = torch.rand(500, 3, generator=gen(3), dtype=DT) * 2
        d_cpu, i_cpu = KNNIndex(pts).query(q, max_distance=0.05)
        d_gpu, i_gpu = KNNIndex(pts.to(CUDA)).query(q.to(CUDA), max_distance=0.05)
        assert torch.equal(i_gpu.cpu(), i_cpu)
        assert torch.equal(torch.isinf(d_gpu.cpu()), torch.isinf(d_cpu))


class TestManifoldsAndSolver:
    @pytest.mark.parametrize(
        "manifold",
        [
            SpecialOrthogonal(4),
            Stiefel(6, 2),
            PlaneRotations(4, (1, 3)),
            ProductManifold(SpecialOrthogonal(3), Stiefel(5, 2)),
        ],
        ids=["so", "stiefel", "plane", "product"],
    )
    def test_retraction_and_projection_on_device(self, manifold):
        x = manifold.random_point(generator=gen(0))
        x = [t.to(CUDA) for t in x] if isinstance(x, (list, tuple)) else x.to(CUDA)
        u = manifold.random_tangent(x, generator=gen(1))
        y = manifold.retr(x, u)
        for t in y if isinstance(y, (list, tuple)) else [y]:
            assert t.device.type == CUDA.type
        assert manifold.inner(x, u, u) > 0
        back = manifold.retr(
            [t.cpu() for t in x] if isinstance(x, (list, tuple)) else x.cpu(),
            [t.cpu() for t in u] if isinstance(u, (list, tuple)) else u.cpu(),
        )
        for a, b in zip(
            y if isinstance(y, (list, tuple)) else [y],
            back if isinstance(back, (list, tuple)) else [back],
        ):
            torch.testing.assert_close(a.cpu(), b)

    def test_trust_region_procrustes(self):
        g = gen(0)
        q = SpecialOrthogonal(3).random_point(generator=g)
        a = torch.randn(3, 40, generator=g, dtype=DT)
        b = q @ a
        a, b = a.to(CUDA), b.to(CUDA)
        m = SpecialOrthogonal(3)
        res = trust_region(
            m,
            lambda r: ((r @ a - b) ** 2).sum(),
            m.random_point(generator=gen(2)).to(CUDA),
        )
        assert res.converged and res.x.device.type == CUDA.type
        assert (res.x.cpu() - q).abs().max() < 1e-7


class TestGeometry:
    def test_plane_from_pairs_and_gradient(self):
        n = torch.nn.functional.normalize(
            torch.tensor([0.3, -0.5, 0.8], dtype=DT), dim=0
        )
        x = torch.randn(200, 3, generator=gen(0), dtype=DT)
        y = torchsym.geometry.reflect_points(x, n, torch.tensor(0.2, dtype=DT))
        normal, offset = torchsym.geometry.plane_from_pairs(x.to(CUDA), y.to(CUDA))
        assert normal.device.type == CUDA.type and deg(normal, n) < 1e-6
        assert abs(abs(float(offset)) - 0.2) < 1e-9
        w = torch.tensor([0.1, 0.2, 0.9], dtype=DT, device=CUDA, requires_grad=True)
        loss = torchsym.geometry.reflect_points(
            x.to(CUDA), w / w.norm(), torch.tensor(0.0, dtype=DT, device=CUDA)
        ).sum()
        loss.backward()
        assert (
            w.grad is not None
            and w.grad.device.type == CUDA.type
            and torch.isfinite(w.grad).all()
        )


@pytest.fixture(scope="module")
def cloud():
    return torchsym.planted_symmetric_cloud(3000, generator=3)


@pytest.fixture(scope="module")
def image():
    from torchsym.image.synthetic import mirrored_objects_image

    return mirrored_objects_image(1, height=240, width=240, generator=gen(0))


class TestPointCloud:
    def test_plane_on_device(self, cloud):
        cpu = torchsym.detect_reflection_plane(cloud.points, generator=0)
        gpu = torchsym.detect_reflection_plane(cloud.points.to(CUDA), generator=0)
        assert tensors_on(gpu, CUDA.type) == []
        assert (
            deg(gpu.normal, cloud.normal) < 0.05
            and deg(cpu.normal, cloud.normal) < 0.05
        )
        assert abs(gpu.score - cpu.score) < 0.02
        assert gpu.to("cpu").normal.device.type == "cpu"

    def test_module_and_detect(self, cloud):
        res = torchsym.ReflectionPlaneDetector().to(CUDA)(cloud.points.to(CUDA))
        assert (
            res.normal.device.type == CUDA.type and deg(res.normal, cloud.normal) < 0.05
        )
        res = torchsym.detect(cloud.points.to(CUDA))
        assert (
            res.normal.device.type == CUDA.type and deg(res.normal, cloud.normal) < 0.05
        )

    def test_outliers_on_device(self, cloud):
        noisy = torchsym.add_outliers(cloud, 1.0, generator=1)
        gpu = torchsym.detect_reflection_plane(noisy.points.to(CUDA), generator=0)
        assert deg(gpu.normal, cloud.normal) < 1.0


class TestPointSet:
    def test_point_symm_on_device(self):
        s = torchsym.make_symmetric_pointset(200, 3, 1e-4, generator=gen(0))
        cpu = torchsym.point_symm(s.points, generator=gen(1))
        gpu = torchsym.point_symm(s.points.to(CUDA), generator=gen(1))
        assert tensors_on(gpu, CUDA.type) == []
        # the assignment and the trust region run on the CPU either way: same bits
        assert torch.equal(gpu.permutation.cpu(), cpu.permutation)
        torch.testing.assert_close(gpu.normal.cpu(), cpu.normal)

    def test_image_axis_on_device(self):
        size = 96
        g = gen(0)
        img = torch.zeros(1, size, size)
        for _ in range(8):
            x0 = int(torch.randint(2, size // 2 - 4, (1,), generator=g))
            y0 = int(torch.randint(2, size - 16, (1,), generator=g))
            img[0, y0 : y0 + 8, x0 : x0 + 6] = (
                float(torch.rand(1, generator=g)) * 0.7 + 0.3
            )
        img = torch.maximum(img, img.flip(-1))
        cpu = torchsym.point_symm_image(img, generator=gen(1))
        gpu = torchsym.point_symm_image(img.to(CUDA), generator=gen(1))
        assert tensors_on(gpu, CUDA.type) == []
        assert deg(gpu.normal, cpu.normal) < 0.5


class TestImages:
    @pytest.mark.parametrize("fn", ["ksymmetry_axes", "boundary_clique_axes"])
    def test_axes_on_device(self, image, fn):
        import cv2

        from torchsym.metrics.axes import match_axes

        if fn == "boundary_clique_axes" and not hasattr(cv2, "ximgproc"):
            pytest.skip("OpenCV without its contrib modules (edge thinning)")
        img, _ = image
        cpu = getattr(torchsym, fn)(img)
        gpu = getattr(torchsym, fn)(img.to(CUDA))
        assert tensors_on(gpu, CUDA.type) == []
        assert gpu.lines.shape[0] >= 1
        size = tuple(img.shape[-2:])
        # kornia's SIFT and edges run on the device: the strongest axis is the CPU's
        assert bool(
            match_axes(gpu.axes[:1].cpu(), cpu.axes[:1].cpu(), image_size=size).all()
        )


class TestMesh:
    def test_intrinsic_on_device(self):
        from torchsym.mesh.synthetic import icosphere

        s = icosphere(3)
        v = s.vertices.numpy()
        x, y, z = v.T
        w = v * (1 + 0.8 * x**2 + 0.3 * y + 0.25 * y * z + 0.2 * z**2 * y)[:, None]
        mesh = torchsym.Mesh(torch.from_numpy(w), s.faces)
        cpu = torchsym.intrinsic_symmetry(mesh)
        gpu = torchsym.intrinsic_symmetry(mesh.to(CUDA))
        assert tensors_on(gpu, CUDA.type) == []
        assert torch.equal(gpu.map.cpu(), cpu.map)
