"""The whole symmetry group: rotations found directly (chiral shapes, no plane), the
group's closure, and the checks of what the group functions accept (issues 58, 59)."""

import math

import pytest
import torch

import torchsym
from torchsym.errors import InputShapeError, InputValueError
from torchsym.geometry import reflection_matrix
from torchsym.geometry.mesh import Mesh
from torchsym.pointcloud import (
    SymmetryDetector,
    SymmetryResult,
    box_mesh,
    boxes_mesh,
    detect_reflection_planes,
    detect_symmetry,
    random_rigid_motion,
    sample_surface,
    symmetry_group,
)
from torchsym.pointcloud.reflection_planes.group import group_from_generators
from torchsym.pointcloud.rotational_shapes import about_axis, bolt_mesh, fan_mesh, gear_mesh
from torchsym.pointcloud.synthetic import SymmetricCloud


ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]


def _cloud(mesh, n=6000, seed=1, pose=None):
    pts = sample_surface(mesh, n, generator=seed).float()
    if pose is not None:
        z = torch.zeros(3)
        pts = random_rigid_motion(SymmetricCloud(pts, torch.tensor([1.0, 0, 0]), z[0], torch.zeros(0)), generator=pose).points
    return pts


#: an asymmetric part off the axis: two boxes of different sizes at odd places
PART = boxes_mesh([((0.5, 0.2, 0.15), (0.6, 0.1, 0.05)), ((0.15, 0.3, 0.25), (0.9, -0.05, 0.2))])


def _planes(group) -> int:
    return int(group.reflections.shape[0])


class TestRotationsFoundDirectly:
    @pytest.mark.slow
    @pytest.mark.parametrize("n", [3, 5])
    def test_chiral_part_about_an_axis(self, n):
        res = detect_symmetry(_cloud(about_axis(PART, n), pose=n))
        assert isinstance(res, SymmetryResult)
        assert res.orders.tolist()[:1] == [n]
        g = res.group
        assert g.closed and g.order == n and _planes(g) == 0
        assert sorted(g.orders.tolist()) == [n]

    @pytest.mark.slow
    def test_achiral_part_about_an_axis(self):
        res = detect_symmetry(_cloud(about_axis(PART, 4, mirror=True), pose=7))
        g = res.group
        assert g.closed and g.order == 8 and _planes(g) == 4
        assert int(g.orders.max()) == 4

    @pytest.mark.slow
    def test_fan_with_pitched_blades_is_dihedral_without_planes(self):
        g = detect_symmetry(_cloud(fan_mesh(5), pose=3)).group
        assert g.closed and g.order == 10 and _planes(g) == 0
        assert sorted(g.orders.tolist()) == [2, 2, 2, 2, 2, 5]

    @pytest.mark.slow
    def test_gear(self):
        g = detect_symmetry(_cloud(gear_mesh(7), n=8000)).group
        assert g.closed and g.order == 28 and _planes(g) == 8

    @pytest.mark.slow
    def test_bolt_is_not_a_surface_of_revolution(self):
        res = detect_symmetry(_cloud(bolt_mesh(), n=8000))
        assert res.planes.continuous_axes.shape[0] == 0
        assert int(res.group.orders.max()) == 6 and _planes(res.group) == 6

    @pytest.mark.slow
    def test_asymmetric_part_has_no_symmetry(self):
        g = detect_symmetry(_cloud(PART)).group
        assert g.order == 1

    @pytest.mark.slow
    def test_module_matches_function_and_detect(self):
        pts = _cloud(about_axis(PART, 3))
        a = SymmetryDetector()(pts)
        b = torchsym.detect(pts, ROOT / "configs" / "pointcloud_symmetry.yaml")
        assert a.group.order == b.group.order == 3
        assert torch.equal(a.axes, b.axes)


class TestGroupClosure:
    def _two(self, angle):
        n = torch.tensor([[1.0, 0.0, 0.0], [math.cos(angle), math.sin(angle), 0.0]], dtype=torch.float64)
        return group_from_generators(reflection_matrix(n), torch.zeros(3))

    @pytest.mark.parametrize("k", [2, 5, 12])
    def test_planes_at_pi_over_k_close(self, k):
        g = self._two(math.pi / k)
        assert g.closed and g.order == 2 * k and g.orders.tolist() == [k]

    def test_planes_one_radian_apart_are_not_closed(self):
        assert not self._two(1.0).closed

    def test_slightly_off_planes_snap_to_the_group(self):
        # a 7-gon's planes, each off by up to 1.5 degrees: the closure alone runs away
        ang = [k * math.pi / 7 + math.radians(d) for k, d in zip(range(7), [0, 1.5, -1.0, 0.5, -1.5, 1.0, 0.3])]
        n = torch.tensor([[math.cos(a), math.sin(a), 0.0] for a in ang] + [[0.0, 0.0, 1.0]], dtype=torch.float64)
        res = type("R", (), {"normals": n, "center": torch.zeros(3, dtype=torch.float64)})()
        g = symmetry_group(res)
        assert g.closed and g.order == 28

    def test_300_fold_is_bounded(self):
        import time

        t = torch.tensor(2 * math.pi / 300)
        r = torch.tensor([[torch.cos(t), -torch.sin(t), 0.0], [torch.sin(t), torch.cos(t), 0.0], [0.0, 0.0, 1.0]], dtype=torch.float64)
        t0 = time.perf_counter()
        g = group_from_generators(r[None], torch.zeros(3), max_order=400, tol=0.01)
        assert time.perf_counter() - t0 < 10.0
        assert g.closed and g.order == 300


class TestWhatTheGroupAccepts:
    def _res(self, normals):
        return type("R", (), {"normals": normals, "center": torch.zeros(3)})()

    @pytest.mark.parametrize("kw", [{"tol": float("nan")}, {"tol": 0.0}, {"tol": float("inf")}, {"max_order": 0},
                                    {"max_order": 10**9}, {"max_order": 2.5}, {"max_order": True}])
    def test_bad_bounds_are_typed(self, kw):
        with pytest.raises(InputValueError):
            symmetry_group(self._res(torch.eye(3)), **kw)

    def test_nan_normals_are_typed(self):
        with pytest.raises(InputValueError):
            symmetry_group(self._res(torch.tensor([[float("nan"), 0.0, 1.0]])))

    def test_2d_normals_are_typed(self):
        with pytest.raises(InputShapeError):
            symmetry_group(self._res(torch.tensor([[1.0, 0.0]])))

    def test_zero_normal_is_typed(self):
        with pytest.raises(InputValueError):
            symmetry_group(self._res(torch.zeros(1, 3)))

    def test_non_orthogonal_generators_are_typed(self):
        with pytest.raises(InputValueError):
            group_from_generators(2.0 * torch.eye(3)[None], torch.zeros(3))


class TestNoFalseRevolution:
    def _axes(self, pts):
        return detect_reflection_planes(pts.float()).continuous_axes.shape[0]

    def test_regular_tetrahedron(self):
        v = torch.tensor([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1.0]], dtype=torch.float64)
        tet = Mesh(v, torch.tensor([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]))
        assert self._axes(sample_surface(tet, 8000, generator=0)) == 0

    @pytest.mark.slow
    def test_filled_cube(self):
        assert self._axes(torch.rand(8000, 3, generator=torch.Generator().manual_seed(0))) == 0

    def test_flat_random_patch(self):
        g = torch.Generator().manual_seed(1)
        pts = torch.cat([torch.rand(8000, 2, generator=g), torch.zeros(8000, 1)], 1)
        assert self._axes(pts) == 0


def test_every_point_twice_still_has_its_planes():
    pts = sample_surface(box_mesh((3.0, 2.0, 1.0)), 3000, generator=0).float()
    assert detect_reflection_planes(torch.cat([pts, pts])).n_planes == 3


class TestBOP:
    @pytest.mark.slow
    def test_models_folder_to_models_info_in_one_command(self, tmp_path):
        from torchsym.io import write_mesh
        from torchsym.pointcloud import read_models_info
        from torchsym.pointcloud.reflection_planes.bop import group_from_bop
        from torchsym.pointcloud.symmetry.bop_export import main

        models = tmp_path / "models"
        models.mkdir()
        write_mesh(models / "obj_000001.ply", about_axis(PART, 3))
        write_mesh(models / "obj_000002.ply", fan_mesh(4))
        assert main([str(models), "--points", "8000"]) == 0
        info = read_models_info(models / "models_info.json")
        assert sorted(info) == [1, 2]
        assert (tmp_path / "models" / "models_info_pictures" / "obj_000001.png").exists()
        g1, g2 = group_from_bop(info[1]), group_from_bop(info[2])
        assert g1.order == 3 and g1.orders.tolist() == [3]
        assert g2.order == 8 and sorted(g2.orders.tolist()) == [2, 2, 2, 2, 4]
        for e in info.values():
            assert {"diameter", "min_x", "size_z"} <= set(e)

    def test_export_refuses_a_missing_folder(self, tmp_path):
        from torchsym.pointcloud.symmetry.bop_export import main

        assert main([str(tmp_path / "nope")]) == 2

    @pytest.mark.parametrize("entry", [
        [1, 2], {"symmetries_discrete": "x"}, {"symmetries_discrete": [[1.0] * 15]}, {"symmetries_discrete": [["a"] * 16]},
        {"symmetries_discrete": [[1, 0, 0, float("inf"), 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]]},
        {"symmetries_discrete": [[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1]]},  # a reflection
        {"symmetries_discrete": [[2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]]},
        {"symmetries_continuous": [{"axis": [0, 0, 0], "offset": [0, 0, 0]}]},
        {"symmetries_continuous": [{"axis": [0, 0, 1]}]}, {"symmetries_continuous": [[0, 0, 1]]},
        {"symmetries_continuous": [{"axis": [0, float("nan"), 1], "offset": [0, 0, 0]}]},
    ])
    def test_malformed_entries_are_typed(self, entry):
        from torchsym.pointcloud.reflection_planes.bop import group_from_bop

        with pytest.raises(InputValueError):
            group_from_bop(entry)

    def test_300_fold_entry_is_bounded_and_right(self):
        import time

        from torchsym.pointcloud.reflection_planes.bop import group_from_bop

        a = 2 * math.pi / 300
        flat = [math.cos(a), -math.sin(a), 0, 0, math.sin(a), math.cos(a), 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
        t0 = time.perf_counter()
        g = group_from_bop({"symmetries_discrete": [flat]})
        assert time.perf_counter() - t0 < 10.0
        assert g.closed and g.orders.tolist() == [300]

    def test_read_and_write_errors_are_typed(self, tmp_path):
        from torchsym.errors import InputFileError
        from torchsym.pointcloud import read_models_info, write_models_info

        with pytest.raises(InputFileError):
            read_models_info(tmp_path / "missing.json")
        with pytest.raises(InputFileError):
            read_models_info(tmp_path)
        deep = tmp_path / "deep.json"
        deep.write_text("[" * 100000 + "]" * 100000)
        with pytest.raises(InputValueError):
            read_models_info(deep)
        with pytest.raises(InputValueError):
            write_models_info(tmp_path / "m.json", {1: {"diameter": float("nan")}})
        assert not (tmp_path / "m.json").exists()
        with pytest.raises(InputFileError):
            write_models_info(tmp_path / "no" / "m.json", {1: {"diameter": 1.0}})
        with pytest.raises(InputFileError):
            write_models_info(tmp_path, {1: {"diameter": 1.0}})
        write_models_info(tmp_path / "m.json", {1: {"diameter": 1.0}})
        assert read_models_info(tmp_path / "m.json") == {1: {"diameter": 1.0}}
