"""torchsym.pointcloud.reflection_plane.polish: coarse-to-fine steps on a large cloud."""

import math

import torch

from torchsym.geometry import plane_angle
from torchsym.matching import KNNIndex
from torchsym.pointcloud import planted_symmetric_cloud
from torchsym.pointcloud.reflection_plane.polish import local_surface, pair_steps, surface_steps
from torchsym.pointcloud.reflection_plane.settings import PolishSettings


def _tilted(normal: torch.Tensor, degrees: float) -> torch.Tensor:
    """``normal`` turned by ``degrees`` about a direction orthogonal to it."""
    side = torch.linalg.cross(normal, torch.tensor([0.3, 0.5, 0.8], dtype=normal.dtype))
    side = side / side.norm()
    t = math.radians(degrees)
    return math.cos(t) * normal + math.sin(t) * side


def _cloud(n: int = 4000):
    c = planted_symmetric_cloud(n, generator=torch.Generator().manual_seed(3), dtype=torch.float64)
    return c.points, c.normal, c.offset


class TestLocalSurface:
    def test_plane(self):
        g = torch.Generator().manual_seed(0)
        pts = torch.cat([torch.rand(2000, 2, generator=g, dtype=torch.float64), torch.zeros(2000, 1, dtype=torch.float64)], 1)
        at = torch.tensor([[0.5, 0.5, 0.1]], dtype=torch.float64)
        centroid, nu = local_surface(pts, KNNIndex(pts), at, 10)
        assert centroid.shape == (1, 3) and nu.shape == (1, 3)
        assert abs(float(nu[0, 2])) > 0.999 and float(centroid[0, 2]) == 0.0
        assert float((centroid[0, :2] - 0.5).norm()) < 0.05


class TestSurfaceSteps:
    def test_value(self):
        pts, normal, offset = _cloud()
        start = _tilted(normal, 1.0)
        n, b, steps, converged, se = surface_steps(pts, pts, KNNIndex(pts), start, offset, PolishSettings())
        assert float(plane_angle(n, normal)) * 180 / math.pi < 0.1 and 1 <= steps <= 8 and se > 0


class TestPairSteps:
    def test_exact_pairs(self):
        """On an exactly mirrored cloud the Algorithm 6 steps return the exact plane."""
        pts, normal, offset = _cloud()
        start = _tilted(normal, 0.05)
        n, b, dist, nn_idx, steps = pair_steps(pts, KNNIndex(pts), start, offset, float("inf"), 0.05, 8)
        assert float(plane_angle(n, normal)) < 1e-9 and dist.shape == (pts.shape[0],) and steps >= 1

    def test_no_gain(self):
        """A fit no tighter than ``se`` leaves the plane as it is."""
        pts, normal, offset = _cloud()
        start = _tilted(normal, 0.05)
        n, b, _, _, steps = pair_steps(pts, KNNIndex(pts), start, offset, 0.0, 0.05, 8)
        assert torch.equal(n, start) and steps == 0
