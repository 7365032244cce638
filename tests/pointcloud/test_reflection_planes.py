import json
import math

import pytest
import torch

import torchsym
from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.geometry import reflection_matrix
from torchsym.pointcloud import (
    ReflectionPlanesDetector,
    ReflectionPlanesResult,
    box_mesh,
    cone_mesh,
    detect_reflection_planes,
    group_from_bop,
    models_info_entry,
    prism_mesh,
    read_models_info,
    sample_surface,
    symmetry_group,
    write_models_info,
)
from torchsym.pointcloud.reflection_planes.group import group_from_generators

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]


def _cloud(mesh, n=5000, seed=1):
    return sample_surface(mesh, n, generator=seed).float()


@pytest.fixture(scope="module")
def box():
    pts = _cloud(box_mesh((3.0, 2.0, 1.0), (1.0, 2.0, 3.0)))
    return pts, detect_reflection_planes(pts)


@pytest.fixture(scope="module")
def cylinder():
    pts = _cloud(prism_mesh(256, 1.0, 1.5), 6000)
    return pts, detect_reflection_planes(pts)


def _has_normal(normals, axis, deg=2.0):
    return any(abs(float(n.double() @ axis)) > math.cos(math.radians(deg)) for n in normals)


def test_smoke(box):
    _, res = box
    assert isinstance(res, ReflectionPlanesResult)
    assert res.normals.shape == (res.n_planes, 3) and res.offsets.shape == (res.n_planes,)
    assert res.transforms.shape == (res.n_planes, 4, 4)
    assert bool(((res.scores >= 0) & (res.scores <= 1)).all())
    assert bool((res.scores[:-1] >= res.scores[1:]).all())  # best first
    assert res.pairs.shape[1] == 3 and int(res.pairs[:, 0].max()) < res.n_planes
    json.dumps(res.to_dict())


def test_box_three_planes_and_group(box):
    _, res = box
    assert res.n_planes == 3 and res.continuous_axes.shape[0] == 0
    for axis in torch.eye(3, dtype=torch.float64):
        assert _has_normal(res.normals, axis)
    # each plane through the box centre (1, 2, 3)
    centre = torch.tensor([1.0, 2.0, 3.0])
    assert bool(((res.normals @ centre + res.offsets).abs() < 0.02).all())
    g = symmetry_group(res)
    assert g.order == 8 and g.rotations.shape[0] == 3 and g.orders.tolist() == [2, 2, 2]


def test_box_bop_matches_hand_derived_and_round_trips(box, tmp_path):
    pts, res = box
    entry = models_info_entry(pts, symmetry_group(res))
    assert "symmetries_continuous" not in entry and len(entry["symmetries_discrete"]) == 3
    centre = torch.tensor([1.0, 2.0, 3.0], dtype=torch.float64)
    hand = []
    for k in range(3):  # half-turns about the three axes through the centre, in model units
        rot = -torch.eye(3, dtype=torch.float64)
        rot[k, k] = 1.0
        t = torch.eye(4, dtype=torch.float64)
        t[:3, :3], t[:3, 3] = rot, centre - rot @ centre
        hand.append(t)
    got = [torch.tensor(f, dtype=torch.float64).reshape(4, 4) for f in entry["symmetries_discrete"]]
    for h in hand:
        assert min(float((h - t).abs().max()) for t in got) < 0.03
    assert entry["size_x"] == pytest.approx(3.0, abs=0.05) and entry["diameter"] == pytest.approx(math.sqrt(14), abs=0.05)
    write_models_info(tmp_path / "models_info.json", {7: entry})
    back = read_models_info(tmp_path / "models_info.json")
    assert list(back) == [7]
    again = group_from_bop(back[7])
    assert again.rotations.shape[0] == 3
    for t in got:
        assert min(float((t - r).abs().max()) for r in again.rotations) < 1e-9


def test_prism_n_plus_one_planes():
    res = detect_reflection_planes(_cloud(prism_mesh(5, 1.0, 0.6)))
    assert res.n_planes == 6
    assert _has_normal(res.normals, torch.tensor([0.0, 0.0, 1.0], dtype=torch.float64))
    g = symmetry_group(res)
    assert g.order == 20 and sorted(g.orders.tolist()) == [2, 2, 2, 2, 2, 5]


def test_cylinder_axis_and_one_plane(cylinder, tmp_path):
    _, res = cylinder
    assert res.continuous_axes.shape[0] == 1 and res.n_planes == 1
    z = torch.tensor([0.0, 0.0, 1.0], dtype=torch.float64)
    assert abs(float(res.continuous_axes[0].double() @ z)) > math.cos(math.radians(2.0))
    assert _has_normal(res.normals, z)
    g = symmetry_group(res)
    assert g.rotations.shape[0] == 1 and g.orders.tolist() == [2]  # the flip across the axis
    entry = models_info_entry(res.axis_points, g)
    assert len(entry["symmetries_continuous"]) == 1 and len(entry["symmetries_discrete"]) == 1
    write_models_info(tmp_path / "m.json", {1: entry})
    again = group_from_bop(read_models_info(tmp_path / "m.json")[1])
    assert again.continuous_axes.shape[0] == 1 and again.rotations.shape[0] == 1


def test_cone_axis_only():
    res = detect_reflection_planes(_cloud(cone_mesh(256, 1.0, 1.5), 6000))
    assert res.continuous_axes.shape[0] == 1 and res.n_planes == 0
    assert symmetry_group(res).rotations.shape[0] == 0


def test_no_symmetry_scores_low():
    g = torch.Generator().manual_seed(3)
    centres = torch.randn(6, 3, generator=g) * torch.tensor([1.0, 0.6, 0.3])
    pts = torch.cat([c + 0.25 * torch.randn(800, 3, generator=g) * (1 + k) / 3 for k, c in enumerate(centres)])
    res = detect_reflection_planes(pts)
    assert res.n_planes == 0 or float(res.scores.max()) < 0.3


def test_group_of_exact_generators():
    # the 4 planes of a square (through the z axis) and the plane across it: D4h, order 16
    normals = [torch.tensor([math.cos(a), math.sin(a), 0.0], dtype=torch.float64) for a in (0, math.pi / 4)]
    normals.append(torch.tensor([0.0, 0.0, 1.0], dtype=torch.float64))
    g = group_from_generators(reflection_matrix(torch.stack(normals)), torch.zeros(3, dtype=torch.float64))
    assert g.order == 16 and g.closed
    assert sorted(g.orders.tolist()) == [2, 2, 2, 2, 4]
    assert g.reflections.shape[0] == 5


def test_deterministic_and_input_unchanged(box):
    pts, res = box
    copy = pts.clone()
    again = detect_reflection_planes(pts)
    assert torch.equal(pts, copy)
    assert torch.equal(res.normals, again.normals) and torch.equal(res.offsets, again.offsets)
    assert torch.equal(res.scores, again.scores)


def test_module_and_detect_config(box):
    pts, res = box
    via_module = ReflectionPlanesDetector()(pts)
    assert torch.equal(via_module.normals, res.normals)
    via_detect = torchsym.detect(pts, ROOT / "configs" / "pointcloud_planes.yaml")
    assert isinstance(via_detect, ReflectionPlanesResult) and via_detect.n_planes == 3


def test_exception():
    with pytest.raises(InputShapeError):
        detect_reflection_planes(torch.zeros(10, 2))
    with pytest.raises(InputValueError):
        detect_reflection_planes(torch.full((10, 3), float("nan")))
    with pytest.raises(InputValueError):
        detect_reflection_planes(torch.linspace(0, 1, 30)[:, None] * torch.ones(1, 3))
    with pytest.raises(ConfigError):
        detect_reflection_planes(torch.randn(50, 3), accept={"max_ratio": 0.5})
    with pytest.raises(ConfigError):
        detect_reflection_planes(torch.randn(50, 3), unknown=1)
    with pytest.raises(InputValueError):
        symmetry_group(object())


def test_small_cloud_runs():
    pts = torch.tensor([[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0], [0, 0, 0.5]])
    res = detect_reflection_planes(pts)
    assert res.normals.shape[1] == 3


def test_picture(box, tmp_path):
    pts, res = box
    paths = torchsym.viz.write_artifacts(res, pts, tmp_path, "box")
    assert sorted(p.name for p in paths) == ["box_planes.ply", "box_planes.png"]
    assert all(p.stat().st_size > 0 for p in paths)


def test_group_of_one_plane_result():
    from torchsym.pointcloud import detect_reflection_plane

    res = detect_reflection_plane(_cloud(box_mesh((3.0, 2.0, 1.0)), 2000))
    g = symmetry_group(res)
    assert g.order == 2 and g.reflections.shape[0] == 1 and g.rotations.shape[0] == 0


def test_picture_without_planes(tmp_path):
    g = torch.Generator().manual_seed(5)
    pts = torch.randn(400, 3, generator=g) * torch.tensor([1.0, 0.5, 0.2])
    res = detect_reflection_planes(pts, accept={"max_ratio": 1.0})
    assert res.n_planes == 0 or bool((res.ratios <= 1.0).all())
    paths = torchsym.viz.write_artifacts(res, pts, tmp_path, "blob")
    assert all(p.stat().st_size > 0 for p in paths)
