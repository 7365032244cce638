"""torchsym.pointcloud.reflection_plane.kernel: the kernel-correlation stage, for perturbed clouds."""

import itertools
import math

import pytest
import torch

from torchsym.errors import ConfigError
from torchsym.geometry import plane_angle, reflect_points
from torchsym.matching import KNNIndex
from torchsym.pointcloud import (
    add_outliers,
    detect_reflection_plane,
    perturb,
    planted_symmetric_cloud,
)
from torchsym.pointcloud.reflection_plane.kernel import kernel_refine, kernel_score, surface_variation
from torchsym.pointcloud.prepare import dense_part


def _turned(normal: torch.Tensor, degrees: float) -> torch.Tensor:
    """``normal`` turned by ``degrees`` about an axis perpendicular to it."""
    other = torch.tensor([1.0, 0.0, 0.0], dtype=normal.dtype)
    if abs(float(other @ normal)) > 0.9:
        other = torch.tensor([0.0, 1.0, 0.0], dtype=normal.dtype)
    side = torch.linalg.cross(normal, other)
    side = side / side.norm()
    t = math.radians(degrees)
    return math.cos(t) * normal + math.sin(t) * side


class TestKernelRefine:
    def test_score_is_highest_at_the_plane(self):
        cloud = planted_symmetric_cloud(800, generator=1, dtype=torch.float64)
        index = KNNIndex(cloud.points)
        true = kernel_score(cloud.points, index, cloud.normal, cloud.offset, 0.02)
        centre = cloud.points.mean(0)
        for deg in (3.0, 10.0, 30.0):
            n = _turned(cloud.normal, deg)
            assert kernel_score(cloud.points, index, n, -(n @ centre), 0.02) < 0.8 * true

    def test_batched_score_equals_one_by_one(self):
        cloud = planted_symmetric_cloud(500, generator=1, dtype=torch.float64)
        noisy = perturb(cloud, 30, isotropic=True, generator=3).points
        index = KNNIndex(noisy)
        normals = torch.nn.functional.normalize(torch.randn(5, 3, generator=torch.Generator().manual_seed(0), dtype=torch.float64), dim=1)
        offsets = -(normals @ noisy.mean(0))
        batched = kernel_score(noisy, index, normals, offsets, 0.03)
        assert batched.shape == (5,)
        for j in range(5):
            assert float(batched[j]) == kernel_score(noisy, index, normals[j], offsets[j], 0.03)

    def test_refine_returns_to_the_plane_under_noise(self):
        cloud = planted_symmetric_cloud(1000, generator=2, dtype=torch.float64)
        noisy = perturb(cloud, 30, isotropic=True, generator=3).points
        index = KNNIndex(noisy)
        centre = noisy.mean(0)
        start = _turned(cloud.normal, 8.0)
        d, _ = index.query(reflect_points(noisy, cloud.normal, cloud.offset))
        width = 2.0 * float(d.median())
        n, _, steps = kernel_refine(noisy, index, start, -(start @ centre), width, max_iters=100)
        assert math.degrees(float(plane_angle(n, cloud.normal))) < 1.0 and 1 < steps < 100
        short = kernel_refine(noisy, index, start, -(start @ centre), width, max_iters=3)  # slow from afar
        assert short[2] == 3 and math.degrees(float(plane_angle(short[0], cloud.normal))) > 2.0
        assert abs(float(n.norm()) - 1.0) < 1e-9


class TestKernelStage:
    def test_clean_cloud_skips_it(self):
        """Exact mirror pairs: the stage does not run, and the result equals the one without it."""
        cloud = planted_symmetric_cloud(1000, generator=0)
        on, off = detect_reflection_plane(cloud.points), detect_reflection_plane(cloud.points, kernel={"enabled": False})
        assert torch.equal(on.normal, off.normal) and torch.equal(on.offset, off.offset)
        assert on.timings["kernel"] < 0.01

    @pytest.mark.slow
    def test_perturbed_clouds_are_found_more_often(self):
        """Thesis 5.2.4's perturbation (w = 50): right planes 5 of 6 with the stage, 3 without."""
        right = {True: 0, False: 0}
        for seed in range(6):
            cloud = planted_symmetric_cloud(1000, generator=seed)
            noisy = perturb(cloud, 50, generator=100 + seed).points
            for stage in (True, False):
                res = detect_reflection_plane(noisy, kernel={"enabled": stage})
                right[stage] += float(plane_angle(res.normal, cloud.normal)) < 0.2  # radians, about 11 deg
        assert right[True] >= 5 and right[False] <= right[True] - 2

    def test_independently_sampled_surface_skips_it(self):
        """An ellipsoid sampled at random (no exact mirror pairs) is a thin surface: no kernel stage."""
        g = torch.Generator().manual_seed(4)
        u = torch.randn(3000, 3, generator=g, dtype=torch.float64)
        pts = u / u.norm(dim=1, keepdim=True) * torch.tensor([3.0, 2.0, 1.0], dtype=torch.float64)
        res = detect_reflection_plane(pts, kernel={"enabled": True})
        assert res.timings["kernel"] == 0.0
        assert surface_variation(pts, KNNIndex(pts)) < 0.1
        noisy = pts + 0.3 * torch.randn(3000, 3, generator=g, dtype=torch.float64)
        assert surface_variation(noisy, KNNIndex(noisy)) > 0.1

    @pytest.mark.parametrize("n", [6, 7])
    def test_tiny_clouds(self, n):
        """Fewer points than the kernel's 8 neighbours: no crash."""
        for seed in (6017, 7002, 7009):
            pts = torch.randn(n, 3, generator=torch.Generator().manual_seed(seed), dtype=torch.float64)
            res = detect_reflection_plane(pts, kernel={"enabled": True})
            assert torch.isfinite(res.normal).all()

    @pytest.mark.slow
    def test_result_describes_the_returned_plane(self):
        """After the stage, residual and inliers come from the returned plane, and the score rose step by step."""
        cloud = planted_symmetric_cloud(1000, generator=0, dtype=torch.float64)
        noisy = perturb(cloud, 50, generator=100).points
        res = detect_reflection_plane(noisy)  # on by default
        assert res.timings["kernel"] > 0 and detect_reflection_plane(noisy, kernel={"enabled": False}).timings["kernel"] == 0.0
        d, _ = KNNIndex(noisy).query(reflect_points(noisy, res.normal, res.offset))
        assert res.residual == pytest.approx(float(d.median()), rel=1e-6)
        assert torch.equal(res.inliers, d <= res.tolerance)
        index = KNNIndex(noisy)
        n, b = res.normal, res.offset
        start = _turned(n, 6.0)
        n, b = start, -(start @ noisy.mean(0))
        width = 2.0 * float(d.median())
        scores = [kernel_score(noisy, index, n, b, width)]
        for _ in range(5):
            n, b, steps = kernel_refine(noisy, index, n, b, width, max_iters=1)
            assert steps == 1
            scores.append(kernel_score(noisy, index, n, b, width))
        assert all(later >= earlier - 1e-9 for earlier, later in itertools.pairwise(scores)) and scores[-1] > scores[0]

    def test_dense_part_drops_box_outliers(self):
        """A perturbed cloud with 200 % uniform outliers: its points stay, most outliers go."""
        cloud = planted_symmetric_cloud(1000, generator=0, dtype=torch.float64)
        noisy = add_outliers(perturb(cloud, 20, generator=100), 200, generator=200).points
        kept, index = dense_part(noisy, KNNIndex(noisy))
        from_cloud = torch.cdist(kept, noisy).argmin(1) < 1000  # the first 1,000 are the cloud's
        assert int(from_cloud.sum()) >= 990 and int((~from_cloud).sum()) <= 400
        assert index.points.shape == kept.shape
        clean, _ = dense_part(cloud.points, KNNIndex(cloud.points))
        assert clean.shape[0] >= 950  # a sampled surface is (nearly) all dense

    def test_dense_part_with_duplicate_stacks(self):
        """Stacks of exact duplicates (distance 0) do not shrink the dense part to the stacks."""
        cloud = planted_symmetric_cloud(1000, generator=0, dtype=torch.float64)
        noisy = perturb(cloud, 50, generator=100).points
        stacked = torch.cat([noisy, noisy[:10].repeat(30, 1)])  # 10 points, 31 copies each
        kept, _ = dense_part(stacked, KNNIndex(stacked))
        plain, _ = dense_part(noisy, KNNIndex(noisy))  # 863 of the 1,000 without the stacks
        assert torch.unique(kept, dim=0).shape[0] >= 0.95 * plain.shape[0] > 800

    def test_mirror_pairs_among_outliers_skip_it(self):
        """200 % outliers without noise: the inliers keep exact mirror pairs, so the stage
        does not run although the outliers make the cloud look thick."""
        cloud = planted_symmetric_cloud(1000, generator=3)
        noisy = add_outliers(cloud, 200, generator=5).points
        index = KNNIndex(noisy.double())
        assert surface_variation(noisy.double(), index) > 0.1
        res = detect_reflection_plane(noisy)
        assert res.timings["kernel"] == 0.0 and math.degrees(float(plane_angle(res.normal, cloud.normal))) < 0.1

    @pytest.mark.slow
    def test_perturbed_clouds_with_outliers(self):
        """w = 20 and 200 % outliers: the stage, on the dense part, finds 4 of 4 planes within
        3 degrees; Algorithm 6's nearest-neighbour pairs alone 1 (on the whole cloud the
        kernel rewarded the outlier box's planes)."""
        right = {True: 0, False: 0}
        for seed in range(1, 5):
            cloud = planted_symmetric_cloud(1000, generator=seed)
            noisy = add_outliers(perturb(cloud, 20, generator=100 + seed), 200, generator=200 + seed).points
            for stage in (True, False):
                res = detect_reflection_plane(noisy, kernel={"enabled": stage})
                right[stage] += math.degrees(float(plane_angle(res.normal, cloud.normal))) < 3.0
        assert right[True] == 4 and right[False] <= 2

    def test_setting_is_checked(self):
        with pytest.raises(ConfigError, match="kernel.enabled: expected true or false, got 'yes'"):
            detect_reflection_plane(torch.rand(50, 3), kernel={"enabled": "yes"})
