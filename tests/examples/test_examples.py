"""Every script in examples/ runs (shortened where it trains) and writes its pictures."""

from __future__ import annotations

import runpy
import sys
from pathlib import Path

import pytest
import torch

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

# script, extra arguments (shorter training runs), pictures expected under --out
CASES = [
    pytest.param("pointcloud_plane", [], ["pointcloud_plane_plane.png"], marks=pytest.mark.slow),
    ("pointset_nd", [], ["pointset_nd_pointsymm.png"]),
    ("mesh_intrinsic", [], ["mesh_intrinsic_symmetry.png"]),
    pytest.param("image_pointsymm", [], ["image_pointsymm_axis.png"], marks=pytest.mark.slow),
    pytest.param("image_axes", [], ["boundary_cliques_axes.png", "ksymmetry_axes.png"], marks=pytest.mark.slow),
    pytest.param("symmslic", [], ["symmslic_superpixels.png"], marks=pytest.mark.slow),
    pytest.param("symmetry_map", [], ["symmetry_map_pairs.png", "symmetry_map_nmrf0.png", "stylized_stylized.png"], marks=pytest.mark.slow),
    pytest.param("multiview_plane", [], ["multiview_views.png", "multiview_plane3d.png"], marks=pytest.mark.slow),
    pytest.param("learn_plane", ["--steps", "20", "--starts", "2", "--points", "200"], ["learn_plane.png"], marks=pytest.mark.slow),
    pytest.param(
        "axis_heatmap",
        ["--steps", "3", "--train", "8", "--test", "4", "--batch", "4", "--fit-steps", "3"],
        ["axis_heatmap.png"],
        marks=pytest.mark.slow,
    ),
]


@pytest.fixture(autouse=True)
def _torch_state():
    """An example may set torch's thread count or global seed: restored for the tests after it."""
    threads, rng = torch.get_num_threads(), torch.get_rng_state()
    yield
    torch.set_num_threads(threads)
    torch.set_rng_state(rng)


@pytest.mark.parametrize(("name", "args", "pictures"), CASES)
def test_example_writes_its_pictures(name, args, pictures, tmp_path, monkeypatch):
    monkeypatch.setattr(sys, "argv", [f"{name}.py", "--out", str(tmp_path), *args])
    runpy.run_path(str(EXAMPLES / f"{name}.py"), run_name="__main__")
    for picture in pictures:
        assert (tmp_path / picture).stat().st_size > 1000, picture
