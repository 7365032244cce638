import math

import pytest
import torch

import torchsym
from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.geometry import plane_angle, point_plane_distance
from torchsym.pointcloud import (
    ReflectionPlaneDetector,
    ReflectionPlaneResult,
    ReflectionPlaneSettings,
    add_outliers,
    detect_reflection_plane,
    mirror_complete,
    perturb,
    planted_symmetric_cloud,
    random_rigid_motion,
    remove_part,
    sample_surface,
)


def _gen(seed: int = 0) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


def _deg(a, b):
    return float(plane_angle(a.double(), b.double())) * 180 / math.pi


def _same_plane(res, normal, offset, atol_deg=0.05, atol_off=1e-2):
    sign = 1.0 if float((res.normal * normal).sum()) > 0 else -1.0
    return _deg(res.normal, normal) < atol_deg and abs(float(res.offset) * sign - float(offset)) < atol_off


@pytest.fixture(scope="module")
def cloud():
    return planted_symmetric_cloud(3000, generator=3)


class TestDetectReflectionPlane:
    def test_smoke(self, cloud):
        res = detect_reflection_plane(cloud.points)
        assert isinstance(res, ReflectionPlaneResult)
        assert res.normal.shape == (3,) and res.offset.shape == () and res.matrix.shape == (3, 3)
        assert res.transform.shape == (4, 4) and res.inliers.shape == (3000,) and res.pairs.shape[1] == 2
        assert math.isclose(float(res.normal.norm()), 1.0, rel_tol=1e-5)
        assert res.converged

    @pytest.mark.parametrize("seed", [0, 1, 2, 5])
    def test_planted_symmetry_recovered(self, seed):
        c = planted_symmetric_cloud(3000, generator=seed)
        res = detect_reflection_plane(c.points)
        assert _same_plane(res, c.normal, c.offset, atol_deg=1e-2, atol_off=1e-3)
        assert res.score > 0.95

    def test_pairs_are_true_mirrors(self, cloud):
        res = detect_reflection_plane(cloud.points)
        i, j = res.pairs[:, 0], res.pairs[:, 1]
        off_plane = i != j
        assert float((cloud.mirror[i[off_plane]] == j[off_plane]).float().mean()) > 0.99
        # the centre lies on the plane
        assert abs(float(point_plane_distance(res.center[None], res.normal, res.offset))) < 1e-4

    def test_rigid_motion_moves_plane(self, cloud):
        moved = random_rigid_motion(cloud, generator=11)
        a = detect_reflection_plane(cloud.points)
        b = detect_reflection_plane(moved.points)
        assert _same_plane(a, cloud.normal, cloud.offset) and _same_plane(b, moved.normal, moved.offset)

    def test_permutation_changes_nothing(self, cloud):
        perm = torch.randperm(3000, generator=torch.Generator().manual_seed(4))
        a = detect_reflection_plane(cloud.points)
        b = detect_reflection_plane(cloud.points[perm])
        assert _deg(a.normal, b.normal) < 1e-3
        assert abs(a.score - b.score) < 1e-3
        assert torch.equal(a.inliers[perm], b.inliers)

    def test_same_seed_same_bits(self, cloud):
        a = detect_reflection_plane(cloud.points, generator=7)
        b = detect_reflection_plane(cloud.points, generator=7)
        assert torch.equal(a.normal, b.normal) and torch.equal(a.offset, b.offset) and torch.equal(a.pairs, b.pairs)

    def test_module_repeatable(self, cloud):
        det = ReflectionPlaneDetector(seed=3)
        a, b = det(cloud.points), det(cloud.points)
        assert torch.equal(a.normal, b.normal)
        assert repr(det) == "ReflectionPlaneDetector(seed=3)"

    def test_float64_kept(self, cloud):
        res = detect_reflection_plane(cloud.points.double())
        assert res.normal.dtype == torch.float64

    def test_outliers(self):
        c = add_outliers(planted_symmetric_cloud(3000, generator=8), 100.0, generator=1)
        res = detect_reflection_plane(c.points)
        assert _deg(res.normal, c.normal) < 1.0

    def test_heavy_outliers_precise(self):
        # two outliers per surface point: the median residual belongs to an outlier, so
        # Algorithm 6 judges progress by the lower quartile (this ended 3.4 deg off before)
        c = add_outliers(planted_symmetric_cloud(1000, generator=2), 200.0, generator=102)
        res = detect_reflection_plane(c.points)
        assert _deg(res.normal, c.normal) < 0.5
        assert res.n_starts > 3  # no start reaches the clean-cloud acceptance level here

    def test_duplicated_points(self):
        # a fifth of the points doubled (as on mesh seams): the spacing quantile is 0, and
        # the dense-core rule for outliers must not reduce the cloud to the duplicates
        c = planted_symmetric_cloud(2000, generator=1)
        pts = torch.cat([c.points, c.points[:400]])
        res = detect_reflection_plane(pts)
        assert _deg(res.normal, c.normal) < 0.01 and res.score > 0.9

    def test_clean_cloud_accepts_early(self):
        # on a subsample the support is calibrated by held-out points, so a clean cloud
        # larger than n_refine_samples stops after a few of its 40 starts
        c = planted_symmetric_cloud(8000, generator=3)
        res = detect_reflection_plane(c.points)
        assert res.n_starts <= 3 and _deg(res.normal, c.normal) < 0.01

    def test_missing_part(self):
        c = remove_part(planted_symmetric_cloud(3000, generator=9), 0.15, generator=2)
        res = detect_reflection_plane(c.points)
        assert _deg(res.normal, c.normal) < 1.0

    @pytest.mark.slow
    def test_perturbation(self):
        c = perturb(planted_symmetric_cloud(3000, generator=10), 20.0, generator=2)
        res = detect_reflection_plane(c.points)
        assert _deg(res.normal, c.normal) < 5.0  # the correctness threshold of the benchmark

    def test_thesis_variant_runs(self, cloud):
        res = detect_reflection_plane(
            cloud.points,
            n_starts=1,
            init={"directions": "grid"},
            starts={"pca": False},
            prealign={"enabled": False},
            alternation={"accelerate": False, "update": "procrustes"},
        )
        assert res.n_starts == 1 and res.iterations >= 1

    def test_asymmetric_cloud_low_score(self):
        g = torch.Generator().manual_seed(0)
        # a random cloud with no reflection symmetry: clumps of random sizes at random places
        centres = torch.rand(12, 3, generator=g) * 4
        pts = (centres[torch.randint(0, 12, (3000,), generator=g)] + 0.3 * torch.rand(3000, 3, generator=g) ** 3)
        res = detect_reflection_plane(pts)
        sym = detect_reflection_plane(planted_symmetric_cloud(3000, generator=0).points)
        assert res.score < 0.6 < sym.score

    def test_planar_cloud_ok(self):
        g = torch.Generator().manual_seed(1)
        pts = torch.cat([torch.rand(500, 2, generator=g) * torch.tensor([2.0, 1.0]), torch.zeros(500, 1)], 1)
        res = detect_reflection_plane(pts)
        # a filled rectangle in z = 0: its symmetry planes are x = 1, y = 0.5 and z = 0 itself
        axis = res.normal.abs().argmax()
        assert float(res.normal.abs().max()) > math.cos(math.radians(2.0))
        assert int(axis) == 2 or abs(float(res.offset) / float(res.normal[axis]) + float(pts[:, axis].max() / 2)) < 0.05

    @pytest.mark.parametrize(
        "bad, kind, message",
        [
            (torch.tensor([[0.0, 0.0, float("nan")]] * 5), InputValueError, "points: expected finite values"),
            (torch.tensor([[0.0, 0.0, float("inf")]] * 5), InputValueError, "points: expected finite values"),
            (torch.zeros(3, 3), InputShapeError, r"points: expected \(N, D\) with D = 3 and N >= 4, got \(3, 3\)"),
            (torch.zeros(10, 2), InputShapeError, r"got \(10, 2\)"),
            (torch.zeros(10), InputShapeError, r"got \(10\)"),
            (torch.linspace(0, 1, 30)[:, None] * torch.tensor([[1.0, 2.0, 3.0]]), InputValueError, "on one line"),
            (torch.zeros(10, 3), InputValueError, "got 10 copies of one point"),
        ],
    )
    def test_exception(self, bad, kind, message):
        with pytest.raises(kind, match=message):
            detect_reflection_plane(bad)

    def test_exception_settings(self):
        with pytest.raises(ConfigError, match="init.directions: expected one of 'sphere', 'grid', got 'random'"):
            ReflectionPlaneDetector(init={"directions": "random"})
        with pytest.raises(ConfigError, match="n_starts: expected an int >= 1, got 0"):
            detect_reflection_plane(torch.rand(10, 3, generator=_gen()), n_starts=0)
        with pytest.raises(ConfigError, match=r"polish.max_iter: unknown setting of PolishSettings"):
            detect_reflection_plane(torch.rand(10, 3, generator=_gen()), polish={"max_iter": 3})
        with pytest.raises(ConfigError, match="settings: expected ReflectionPlaneSettings"):
            detect_reflection_plane(torch.rand(10, 3, generator=_gen()), settings=3)

    @pytest.mark.parametrize("factor", [1e200, 1e-200, 1e150])
    def test_extreme_scale(self, cloud, factor):
        """Coordinates of any finite magnitude: the same plane, scaled (eigh overflowed at 1e200)."""
        pts = cloud.points.double()
        ref = detect_reflection_plane(pts)
        res = detect_reflection_plane(pts * factor)
        assert _deg(res.normal, ref.normal) < 1e-6 and res.score == ref.score
        assert float(res.offset) / factor == pytest.approx(float(ref.offset), rel=1e-6, abs=1e-9)
        assert res.residual / factor == pytest.approx(ref.residual, rel=1e-6, abs=1e-12)
        assert torch.isfinite(res.center).all() and torch.isfinite(res.transform).all()

    def test_extreme_scale_too_wide(self):
        pts = (torch.rand(50, 3, generator=_gen(), dtype=torch.float64) * 2 - 1) * 1.7e308
        with pytest.raises(InputValueError, match="points: expected a bounding box whose diagonal is finite"):
            detect_reflection_plane(pts)

    def test_settings_object_mapping_and_overrides_agree(self, cloud):
        pts = cloud.points[:1000]
        a = detect_reflection_plane(pts, ReflectionPlaneSettings(n_starts=3).replace({"polish.enabled": False}))
        b = detect_reflection_plane(pts, {"n_starts": 3, "polish": {"enabled": False}})
        c = detect_reflection_plane(pts, n_starts=3, polish={"enabled": False})
        d = ReflectionPlaneDetector(n_starts=3, polish={"enabled": False})(pts)
        for r in (b, c, d):
            assert torch.equal(a.normal, r.normal) and torch.equal(a.pairs, r.pairs) and a.iterations == r.iterations

    def test_seed_setting(self, cloud):
        pts = cloud.points[:1000]
        a = detect_reflection_plane(pts, seed=4)
        b = detect_reflection_plane(pts, generator=4)
        assert torch.equal(a.normal, b.normal) and torch.equal(a.inliers, b.inliers)

    def test_to_dict_json(self, cloud):
        import json

        d = detect_reflection_plane(cloud.points[:500]).to_dict()
        assert d["type"] == "ReflectionPlaneResult" and len(json.loads(json.dumps(d))["normal"]) == 3

    def test_numpy_input(self, cloud):
        res = torchsym.detect(cloud.points.numpy())
        assert _same_plane(res, cloud.normal, cloud.offset)


class TestSynthetic:
    def test_planted_is_symmetric(self, cloud):
        from torchsym.geometry import reflect_points

        refl = reflect_points(cloud.points.double(), cloud.normal.double(), cloud.offset.double())
        assert torch.allclose(refl, cloud.points[cloud.mirror].double(), atol=1e-4)

    def test_corruptions(self, cloud):
        assert add_outliers(cloud, 50, generator=0).points.shape[0] == 4500
        assert remove_part(cloud, 0.28, generator=0).points.shape[0] == 3000 - 840
        p = perturb(cloud, 100, generator=0)
        ext = (cloud.points.max(0).values - cloud.points.min(0).values).min()
        assert float((p.points - cloud.points).norm(dim=1).max()) <= float(ext) + 1e-5

    def test_remove_part_keeps_mirror_indices(self, cloud):
        c = remove_part(cloud, 0.2, generator=1)
        has = c.mirror >= 0
        from torchsym.geometry import reflect_points

        refl = reflect_points(c.points[has].double(), c.normal.double(), c.offset.double())
        assert torch.allclose(refl, c.points[c.mirror[has]].double(), atol=1e-4)

    def test_mirror_complete_given_plane_without_motion(self):
        g = torch.Generator().manual_seed(3)
        pts = torch.randn(500, 3, generator=g, dtype=torch.float64) * torch.tensor([1.0, 2.0, 3.0], dtype=torch.float64)
        c = mirror_complete(pts, normal=torch.tensor([0.0, 2.0, 0.0]), rigid_motion=False, generator=1, dtype=torch.float64)
        assert torch.equal(c.normal, torch.tensor([0.0, 1.0, 0.0], dtype=torch.float64))
        assert float(c.offset) == pytest.approx(-float(pts[:, 1].mean()))
        # the kept half (first half of the result) is the input itself, unmoved, all on one side
        kept = c.points[: c.points.shape[0] // 2]
        assert all(bool((pts == q).all(1).any()) for q in kept)
        side = kept[:, 1] + c.offset
        assert bool((side >= 0).all()) or bool((side < 0).all())
        refl = c.points[c.mirror].clone()
        refl[:, 1] = -2 * c.offset - refl[:, 1]
        assert torch.allclose(refl, c.points, atol=1e-12)

    @pytest.mark.parametrize(
        "normal, error, message",
        [
            (torch.zeros(3), InputValueError, "normal: expected a non-zero vector"),
            (torch.tensor([0.0, float("nan"), 1.0]), InputValueError, "normal: expected finite values"),
            (torch.ones(2), InputShapeError, r"normal: expected a \(3,\) vector, got shape \(2,\)"),
            ("x", InputShapeError, "normal: expected a tensor or array, got str"),
        ],
    )
    def test_mirror_complete_bad_normal(self, normal, error, message):
        with pytest.raises(error, match=message):
            mirror_complete(torch.randn(10, 3), normal=normal)

    def test_mirror_complete_real_mesh(self, shared_data):
        mesh = torchsym.io.read_mesh(shared_data / "meshes" / "cow.off")
        pts = sample_surface(mesh, 4000, generator=0)
        c = mirror_complete(pts, generator=1)
        res = detect_reflection_plane(c.points)
        assert _deg(res.normal, c.normal) < 0.1 and res.score > 0.9

    def test_embedded_sample(self):
        n, b = torchsym.data.sample_plane()
        res = torchsym.detect(torchsym.data.sample_path("chair.ply"))
        assert _same_plane(res, n, b, atol_deg=1e-2, atol_off=1e-3)


class TestScoreCalibration:
    """The score compares the plane's mirror share with the best of random planes."""

    @staticmethod
    def _mixture(n: int, seed: int) -> torch.Tensor:
        g = torch.Generator().manual_seed(seed)
        means = torch.randn(5, 3, generator=g) * 2
        factors = torch.randn(5, 3, 3, generator=g) * 0.6
        which = torch.multinomial(torch.rand(5, generator=g) + 0.2, n, replacement=True, generator=g)
        return means[which] + (factors[which] @ torch.randn(n, 3, 1, generator=g))[..., 0]

    @pytest.mark.slow
    def test_gaussian_mixtures_score_low(self):
        for seed in range(4):
            assert detect_reflection_plane(self._mixture(2000, seed)).score < 0.3

    @pytest.mark.slow
    def test_mirror_completed_clouds_score_high(self):
        for seed in range(3):
            assert detect_reflection_plane(planted_symmetric_cloud(2000, generator=seed).points).score > 0.7

    def test_coplanar_points_score_zero(self):
        g = torch.Generator().manual_seed(3)
        pts = torch.cat([torch.rand(800, 2, generator=g), torch.zeros(800, 1)], 1)
        assert detect_reflection_plane(pts).score == 0.0

    def test_raw_share(self):
        """``n_chance_planes=0`` gives the share of off-plane points that are inliers."""
        res = detect_reflection_plane(planted_symmetric_cloud(1000, generator=0).points, n_chance_planes=0)
        assert res.score > 0.95
