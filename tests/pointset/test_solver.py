"""Tests of PointSymm (thesis Ch. 7) on planted symmetries."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import torch

import torchsym
from torchsym.core.registry import SOLVERS
from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.geometry import plane_angle
from torchsym.manifolds import SpecialOrthogonal
from torchsym.pointset import PointSymm, PointSymmResult, PointSymmSettings, point_symm
from torchsym.pointset.synthetic import make_symmetric_pointset
from torchsym.pointset.transform import reflection_from_rotations

DT = torch.float64


def planted(n: int, d: int, seed: int, sigma2: float = 0.0):
    return make_symmetric_pointset(n, d, sigma2, generator=torch.Generator().manual_seed(seed))


def gen(seed: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


class TestPointSymm:
    def test_smoke(self):
        s = planted(30, 3, 0)
        res = point_symm(s.points)
        assert isinstance(res, PointSymmResult)
        assert res.normal.shape == (3,) and res.offset.shape == ()
        assert res.rotations.shape == (2, 3, 3) and res.translation.shape == (3,)
        assert res.permutation.shape == (30,) and res.permutation.dtype == torch.int64
        assert 0.0 <= res.score <= 1.0
        assert abs(float(res.normal.norm()) - 1) < 1e-12
        assert res.to_dict()["type"] == "PointSymmResult"

    @pytest.mark.parametrize("d, n", [(2, 40), (3, 60), (6, 60)])
    def test_planted_symmetry(self, d, n):
        s = planted(n, d, seed=d)
        res = point_symm(s.points)
        assert math.degrees(float(plane_angle(res.normal, s.normal))) < 1e-6
        # same plane, not just the same normal: the offsets agree up to the normal's sign
        sign = torch.sign(res.normal @ s.normal)
        assert abs(float(res.offset - sign * s.offset)) < 1e-9
        assert torch.equal(res.permutation, s.correspondence)
        assert res.converged and res.score > 0.999

    def test_rotations_encode_plane(self):
        # Theorem 7.2.3: the reflection T E T^T fixes t and maps the normal to minus itself
        s = planted(40, 4, 1)
        res = point_symm(s.points)
        t = torch.eye(4, dtype=DT)
        for r in res.rotations:
            t = t @ r
        refl = t @ torch.diag(torch.tensor([1.0, 1.0, 1.0, -1.0], dtype=DT)) @ t.T
        assert torch.allclose(refl @ res.normal, -res.normal, atol=1e-10)
        assert abs(float(res.normal @ res.translation + res.offset)) < 1e-10

    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_rigid_motion_invariance(self, d):
        s = planted(50, d, 2)
        q = SpecialOrthogonal(d).random_point(generator=gen(3))
        shift = torch.linspace(-1.0, 2.0, d, dtype=DT)
        moved = s.points @ q.T + shift
        a, b = point_symm(s.points), point_symm(moved)
        assert float(plane_angle(b.normal, q @ a.normal)) < 1e-8
        assert torch.equal(a.permutation, b.permutation)

    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_permutation_invariance(self, d):
        s = planted(50, d, 4)
        order = torch.randperm(50, generator=gen(5))
        a, b = point_symm(s.points), point_symm(s.points[order])
        assert float(plane_angle(a.normal, b.normal)) < 1e-8
        # b's mirror of point k is the mirror of point order[k] in a
        assert torch.equal(order[b.permutation], a.permutation[order])

    @pytest.mark.parametrize("d", [2, 3, 6])
    def test_seeded_determinism(self, d):
        s = planted(40, d, 6, sigma2=0.001)
        a = point_symm(s.points, generator=gen(7))
        b = point_symm(s.points, generator=gen(7))
        assert torch.equal(a.normal, b.normal) and torch.equal(a.offset, b.offset)
        assert torch.equal(a.permutation, b.permutation) and a.score == b.score

    def test_thesis_initialisation(self):
        # Sec. 7.2.4 as written: without noise in 6-D the first passing pairs are true pairs
        s = planted(60, 6, 11)
        res = point_symm(s.points, init={"method": "thesis"})
        assert math.degrees(float(plane_angle(res.normal, s.normal))) < 1e-6
        assert torch.equal(res.permutation, s.correspondence)
        again = point_symm(s.points, init={"method": "thesis"})
        assert torch.equal(res.normal, again.normal)

    def test_small_noise(self):
        s = planted(60, 3, 8, sigma2=1e-6)
        res = point_symm(s.points)
        assert math.degrees(float(plane_angle(res.normal, s.normal))) < 0.5
        assert torch.equal(res.permutation, s.correspondence)

    def test_keeps_dtype(self):
        s = planted(30, 2, 9)
        res = point_symm(s.points.float())
        assert res.normal.dtype == torch.float32 and res.residuals.dtype == torch.float32

    def test_sparse_matches_exact(self):
        s = planted(60, 3, 10)
        exact = point_symm(s.points, assignment={"method": "exact"})
        sparse = point_symm(s.points, assignment={"method": "sparse", "n_neighbors": 5})
        assert exact.assignment == "exact" and sparse.assignment == "sparse"
        assert torch.equal(exact.permutation, sparse.permutation)
        assert float(plane_angle(exact.normal, sparse.normal)) < 1e-8

    def test_missing_part(self):
        # a symmetric set plus points without a mirror: the cardinality limit leaves them unmatched
        s = planted(60, 2, 11)
        extra = torch.rand(10, 2, generator=gen(12), dtype=DT) * 3 + 2
        res = point_symm(torch.cat([s.points, extra]), match_fraction=60 / 70)
        assert math.degrees(float(plane_angle(res.normal, s.normal))) < 1e-6
        assert bool((res.permutation[60:] == -1).all())
        assert torch.equal(res.permutation[:60], s.correspondence)

    def test_two_points(self):
        pts = torch.tensor([[0.0, 0.0], [2.0, 0.0]], dtype=DT)
        res = point_symm(pts)
        assert torch.allclose(res.normal, torch.tensor([1.0, 0.0], dtype=DT))
        assert abs(float(res.offset) + 1.0) < 1e-12

    @pytest.mark.slow
    def test_noisy_set_multistart(self):
        # sigma = 0.03 in the unit cube: on this set the thesis's single start (n_starts=1,
        # no scan) ends in a wrong plane; the pair search's other starts find it
        s = planted(300, 3, 506, sigma2=1e-3)
        single = point_symm(s.points, init={"n_starts": 1}, scan={"enabled": False})
        assert math.degrees(float(plane_angle(single.normal, s.normal))) > 5.0
        res = point_symm(s.points, scan={"enabled": False})
        assert math.degrees(float(plane_angle(res.normal, s.normal))) < 2.0
        assert res.score > single.score
        with pytest.raises(ConfigError, match="init.n_starts: expected an int >= 1"):
            point_symm(s.points, init={"n_starts": 0})

    @pytest.mark.slow
    @pytest.mark.parametrize(("d", "seed", "sigma2"), [(3, 505, 1e-3), (3, 500, 3e-3), (6, 501, 1e-2)])
    def test_noisy_set_scan(self, d, seed, sigma2):
        # noise near the point spacing: every start of the pair search ends in a wrong
        # plane; the scan of planes through the centroid and the principal axes finds it
        s = make_symmetric_pointset(300, d, sigma2, generator=torch.Generator().manual_seed(seed))
        without = point_symm(s.points, scan={"enabled": False})
        assert math.degrees(float(plane_angle(without.normal, s.normal))) > 20.0
        res = point_symm(s.points)
        assert math.degrees(float(plane_angle(res.normal, s.normal))) < 5.0
        assert res.cost < without.cost
        again = point_symm(s.points)  # seeded: the same bits
        assert torch.equal(again.normal, res.normal) and torch.equal(again.permutation, res.permutation)
        with pytest.raises(ConfigError, match="scan.n_normals: expected an int >= 1"):
            point_symm(s.points, scan={"n_normals": 0})
        with pytest.raises(ConfigError, match="scan.n_starts: expected an int >= 1"):
            point_symm(s.points, scan={"n_starts": 0})

    @pytest.mark.slow
    def test_scan_skipped_on_exact_symmetry_and_warm_start(self, monkeypatch):
        # an exact symmetry scores 1 after the pair search (at most match_fraction when only
        # that share may match): the scan does not run; nor after a caller's start
        import torchsym.pointset.solver as ps

        def fail(*args, **kwargs):
            raise AssertionError("the scan ran")

        monkeypatch.setattr(ps, "normal_scan", fail)
        s = planted(200, 3, 3)
        res = point_symm(s.points)
        assert torch.equal(res.permutation, s.correspondence)
        part = point_symm(s.points, match_fraction=0.4)
        assert math.degrees(float(plane_angle(part.normal, s.normal))) < 1e-6
        noisy = planted(300, 3, 500, sigma2=3e-3)
        point_symm(noisy.points, initial=(noisy.normal, noisy.offset))

    @pytest.mark.slow
    def test_flat_set_not_its_trivial_mirror(self):
        # a symmetric set in the plane z = 0 of 3-D space is also its own mirror across that
        # plane; the scan must not return it
        flat = make_symmetric_pointset(300, 2, 3e-3, generator=torch.Generator().manual_seed(3))
        x = torch.cat([flat.points, torch.zeros(300, 1, dtype=flat.points.dtype)], dim=1)
        truth = torch.cat([flat.normal, torch.zeros(1, dtype=flat.normal.dtype)])
        res = point_symm(x)
        assert math.degrees(float(plane_angle(res.normal, truth))) < 2.0
        assert float((res.permutation == torch.arange(300)).double().mean()) < 0.5

    @pytest.mark.slow
    def test_set_in_a_proper_subspace(self):
        # an exact symmetric set of R^3 placed in a 3-D affine subspace of R^7: solved inside
        # its hull, the plane comes back in R^7 with the same mirrors
        s = planted(60, 3, 21)
        q, _ = torch.linalg.qr(torch.randn(7, 3, generator=gen(4), dtype=DT))
        shift = torch.randn(7, generator=gen(5), dtype=DT)
        x = s.points @ q.T + shift
        res = point_symm(x)
        flat = point_symm(s.points)
        assert torch.equal(res.permutation, flat.permutation) and torch.equal(res.permutation, s.correspondence)
        assert math.degrees(float(plane_angle(res.normal, q @ s.normal))) < 1e-6
        mids = 0.5 * (x + x[res.permutation])
        assert float((mids @ res.normal + res.offset).abs().max()) < 1e-9
        assert float((res.translation @ res.normal + res.offset).abs()) < 1e-9
        refl = reflection_from_rotations(list(res.rotations))
        assert torch.allclose(refl, torch.eye(7, dtype=DT) - 2 * torch.outer(res.normal, res.normal), atol=1e-12)
        assert res.score == pytest.approx(flat.score)
        # a warm start in R^7 is taken into the hull
        tilt = q @ (s.normal + 0.05 * torch.tensor([1.0, -1.0, 0.5], dtype=DT))
        warm = point_symm(x, initial=(tilt, -float(tilt @ (q @ (-s.offset * s.normal) + shift))))
        assert math.degrees(float(plane_angle(warm.normal, res.normal))) < 1e-6

    @pytest.mark.slow
    def test_thin_set_is_not_flattened(self):
        # a slab 5e-5 thick, mirror-symmetric across it, in float32: the thin extent is real
        # (far above float32 rounding), so the symmetry across it must be found
        h = torch.rand(1000, 3, generator=gen(0), dtype=DT)
        h[:, 0], h[:, 1], h[:, 2] = h[:, 0] ** 3, h[:, 1] ** 2, (0.2 + h[:, 2]) * 5e-5
        m = h.clone()
        m[:, 2] *= -1
        for shift in (0.0, 300.0):  # also far from the origin along another axis
            x = torch.cat([h, m]) + torch.tensor([shift, 0.0, 0.0], dtype=DT)
            res = point_symm(x.float())
            assert math.degrees(float(plane_angle(res.normal.double(), torch.tensor([0.0, 0.0, 1.0], dtype=DT)))) < 1e-3
            assert res.score > 0.99

    def test_warm_start_containing_a_flat_set(self):
        flat = planted(40, 2, 3).points
        x = torch.cat([flat, torch.full((flat.shape[0], 1), 3.0, dtype=DT)], 1)
        with pytest.raises(InputValueError, match="initial: expected a plane that cuts the set"):
            point_symm(x, initial=(torch.tensor([0.0, 0.0, 1.0], dtype=DT), -3.0))
        with pytest.raises(InputValueError, match="initial: expected a plane that cuts the set"):
            point_symm(x.float(), initial=(torch.tensor([0.0, 0.0, 1.0]), -3.0))  # float32 rounding of the hull

    def test_two_points_in_high_dimension(self):
        pts = torch.tensor([[0.0, 1.0, 2.0, 3.0, 4.0], [2.0, 1.0, 0.0, 3.0, 5.0]], dtype=DT)
        res = point_symm(pts)
        d = pts[1] - pts[0]
        assert math.degrees(float(plane_angle(res.normal, d / d.norm()))) < 1e-6
        assert float(0.5 * (pts[0] + pts[1]) @ res.normal + res.offset) == pytest.approx(0.0, abs=1e-12)
        assert res.permutation.tolist() == [1, 0]

    def test_initial_plane(self):
        # a warm start a few degrees off the truth converges to the exact plane
        s = planted(60, 3, 21)
        tilt = s.normal + 0.05 * torch.tensor([1.0, -1.0, 0.5], dtype=DT)
        res = point_symm(s.points, initial=(tilt, s.offset + 0.01))
        assert math.degrees(float(plane_angle(res.normal, s.normal))) < 1e-6
        assert torch.equal(res.permutation, s.correspondence)
        module = PointSymm()(s.points, initial=(tilt.tolist(), float(s.offset)))
        assert torch.equal(module.permutation, res.permutation)
        # the start is taken in input coordinates: moving the set moves the start with it
        moved = point_symm(s.points + 5.0, initial=(tilt, s.offset + 0.01 - 5.0 * tilt.sum()))
        assert torch.equal(moved.permutation, res.permutation)

    @pytest.mark.parametrize(
        "initial, text",
        [
            (torch.ones(3), "initial: expected a \\(normal, offset\\) pair"),
            ((torch.ones(2), 0.0), r"initial\[0\]: expected \(N, D\) with D = 3"),
            ((torch.zeros(3), 0.0), r"initial\[0\]: expected a non-zero normal"),
            ((torch.ones(3), float("nan")), r"initial\[1\]: expected a finite scalar"),
            ((torch.tensor([1.0, float("inf"), 0.0]), 0.0), r"initial\[0\]: expected finite values"),
        ],
    )
    def test_initial_plane_errors(self, initial, text):
        with pytest.raises((InputShapeError, InputValueError), match=text):
            point_symm(planted(20, 3, 0).points, initial=initial)

    @pytest.mark.slow
    def test_no_symmetry_low_score(self):
        pts = torch.rand(80, 3, generator=gen(13), dtype=DT)
        res = point_symm(pts)
        assert res.score < 0.2

    @pytest.mark.parametrize(
        "points, error, text",
        [
            (torch.zeros(10, 1), InputShapeError, r"points: expected \(N, D\) with D >= 2 and N >= 2, got \(10, 1\)"),
            (torch.zeros(1, 3), InputShapeError, r"points: expected \(N, D\) with D >= 2 and N >= 2, got \(1, 3\)"),
            (torch.zeros(3, 4, 2), InputShapeError, r"got \(3, 4, 2\)"),
            (torch.tensor([[0.0, float("nan")], [1.0, 2.0]]), InputValueError, "points: expected finite values"),
            (torch.ones(5, 3), InputValueError, "points: expected at least two distinct points"),
        ],
    )
    def test_exception(self, points, error, text):
        with pytest.raises(error, match=text):
            point_symm(points)

    def test_exception_settings(self):
        pts = planted(10, 2, 0).points
        with pytest.raises(ConfigError, match="assignment.method: expected one of"):
            point_symm(pts, assignment={"method": "lp"})
        with pytest.raises(ConfigError, match="match_fraction"):
            point_symm(pts, match_fraction=1.5)
        with pytest.raises(ConfigError, match="init.method: expected one of 'search', 'thesis', got 'random'"):
            point_symm(pts, init={"method": "random"})
        with pytest.raises(ConfigError, match="n_scan: unknown setting of PointSymmSettings"):
            point_symm(pts, n_scan=0)


class TestPointSymmModule:
    def test_registered(self):
        entry = SOLVERS.get("pointsymm")
        assert entry.cls is PointSymm and entry.kind == "points"
        assert SOLVERS.default_for("points").cls is PointSymm
        assert torchsym.PointSymm is PointSymm

    def test_forward_matches_function(self):
        s = planted(40, 3, 14)
        module = PointSymm(init={"n_runs": 5}, seed=3)
        a = module(s.points)
        b = point_symm(s.points, PointSymmSettings(init={"n_runs": 5}), generator=gen(3))
        assert torch.equal(a.normal, b.normal) and torch.equal(a.permutation, b.permutation)
        assert "init.n_runs=5" in repr(module)

    def test_forward_does_not_mutate(self):
        module = PointSymm()
        before = repr(module)
        module(planted(20, 2, 15).points)
        assert repr(module) == before

    def test_exception(self):
        with pytest.raises(ConfigError, match="init.n_runs: expected an int >= 1"):
            PointSymm(init={"n_runs": 0})

    def test_config_builds(self):
        pipe = torchsym.build_pipeline(Path(__file__).resolve().parents[2] / "configs" / "pointset_pointsymm.yaml")
        res = pipe(planted(20, 3, 16).points)
        assert isinstance(res, PointSymmResult)


@pytest.mark.slow
def test_auto_assignment_exact_for_partial_sets():
    # full matching: sparse above max_exact_points; with a cardinality limit, which the sparse
    # solver only approximates, exact up to four times as many points
    s = planted(600, 3, 5)
    assert point_symm(s.points, generator=gen(0)).assignment == "sparse"
    cut = s.points[s.points[:, 0] < 0.9 * float(s.points[:, 0].max())]
    assert 500 < cut.shape[0] <= 2000
    res = point_symm(cut, match_fraction=0.85, generator=gen(0))
    assert res.assignment == "exact"
    assert point_symm(cut, match_fraction=0.85, assignment={"max_exact_points": 100}, generator=gen(0)).assignment == "sparse"


@pytest.mark.slow
def test_scan_runs_the_alternation_from_scan_n_starts_planes(monkeypatch):
    # when the scan runs, the alternation starts from at most scan.n_starts scanned planes
    # besides the pair search's starts, and normal_scan is asked for that many
    import torchsym.pointset.alternation as alt
    import torchsym.pointset.solver as ps

    asked, runs = [], []
    scan, alternate = ps.normal_scan, alt.alternate

    def counting_scan(*args, **kwargs):
        asked.append(kwargs["n_keep"])
        out = scan(*args, **kwargs)
        runs.append(("scan", len(out)))
        return out

    def counting_alternate(*args, **kwargs):
        runs.append(("run", 1))
        return alternate(*args, **kwargs)

    monkeypatch.setattr(ps, "normal_scan", counting_scan)
    monkeypatch.setattr(alt, "alternate", counting_alternate)
    s = planted(300, 3, 500, sigma2=3e-3)
    for k in (1, 3):
        asked.clear()
        runs.clear()
        point_symm(s.points, scan={"n_starts": k})
        assert asked == [k]
        i = [kind for kind, _ in runs].index("scan")
        n_scanned = runs[i][1]
        assert 1 <= n_scanned <= k
        assert sum(1 for r in runs[i + 1 :] if r[0] == "run") == n_scanned


class TestSizeLimits:
    def test_transposed_cloud_refused(self):
        # a (3, 4000) cloud read as 3 points in 4000-D: refused at once, the transpose suggested
        pts = torch.rand(3, 4000, generator=gen(0), dtype=DT)
        with pytest.raises(InputShapeError, match=r"points: expected \(N, D\) with D <= max_dim = 512, got \(3, 4000\); .*points\.T"):
            point_symm(pts)

    def test_high_dimension_refused(self):
        pts = torch.rand(20, 2000, generator=gen(1), dtype=DT)
        with pytest.raises(InputShapeError, match="max_dim = 512.*transposed"):
            point_symm(pts)
        with pytest.raises(InputShapeError, match="max_dim = 8, got \\(20, 9\\)$"):
            point_symm(torch.rand(20, 9, generator=gen(1), dtype=DT)[:, :9], max_dim=8)  # N > D: no transpose hint

    def test_too_many_points_refused(self):
        pts = torch.rand(20_001, 3, generator=gen(2), dtype=DT)
        with pytest.raises(InputShapeError, match="points: expected N <= max_points = 10000, got \\(20001, 3\\); subsample"):
            point_symm(pts)
        with pytest.raises(InputShapeError, match="max_points = 50"):
            PointSymm(max_points=50)(planted(60, 2, 0).points)

    def test_limits_are_settings(self):
        s = planted(40, 3, 0)
        assert torch.equal(point_symm(s.points, max_points=40, max_dim=3).permutation, point_symm(s.points).permutation)
        with pytest.raises(ConfigError, match="max_dim: expected an int >= 2"):
            PointSymmSettings(max_dim=1)


class TestSettings:
    def test_defaults_are_the_module_defaults(self):
        assert PointSymm().settings == PointSymmSettings()
        assert PointSymmSettings().init.eps_theta == 2.0  # degrees

    def test_yaml_nested_groups(self, tmp_path):
        cfg = tmp_path / "c.yaml"
        cfg.write_text("input: points\nsteps:\n  - name: pointsymm\n    params:\n      init: {n_runs: 3}\n      scan: {enabled: false}\n")
        pipe = torchsym.build_pipeline(cfg)
        s = planted(30, 3, 1)
        assert torch.equal(pipe(s.points).permutation, point_symm(s.points, init={"n_runs": 3}, scan={"enabled": False}).permutation)
        cfg.write_text("input: points\nsteps:\n  - name: pointsymm\n    params:\n      init: {n_run: 3}\n")
        with pytest.raises(ConfigError, match="init.n_run: unknown setting.*n_runs"):
            torchsym.build_pipeline(cfg)
