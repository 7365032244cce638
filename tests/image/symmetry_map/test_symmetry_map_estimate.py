from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.core.registry import SOLVERS
from torchsym.errors import ConfigError, InputShapeError
from torchsym.image.symmetry_map import SymmetryMapResult, SymmetryMapSettings, SymmetryMapSolver, symmetry_map
from torchsym.image.synthetic import mirrored_photo
from torchsym.metrics.symmetry_map import nmrf_correspondence_rate


def _back_distance(nmrf: torch.Tensor) -> torch.Tensor:
    """``|f(f(p)) - p|`` per pixel."""
    h, w, _ = nmrf.shape
    x = nmrf[..., 0].round().long().clamp(0, w - 1)
    y = nmrf[..., 1].round().long().clamp(0, h - 1)
    ys, xs = torch.meshgrid(torch.arange(h), torch.arange(w), indexing="ij")
    return (nmrf[y, x] - torch.stack([xs, ys], -1)).norm(dim=-1)


class TestSymmetryMap:
    def test_smoke(self, irs_result, mirrored):
        r = irs_result
        assert isinstance(r, SymmetryMapResult)
        assert r.nmrf.shape == (1, 160, 200, 2) and r.ssm.shape == (1, 160, 200)
        assert float(r.ssm.min()) >= 0 and float(r.ssm.max()) <= 1
        assert r.scheme == "irs" and r.iterations == 6 and r.notes == ()
        assert set(r.seconds) >= {"candidates", "clustering", "descriptors", "patchmatch", "score"}
        d = r.to_dict()
        assert d["n_axes"] == 1 and d["map_size"] == [160, 200]

    def test_exact_field_recovered(self, irs_result, mirrored):
        rate = nmrf_correspondence_rate(irs_result.nmrf[0], mirrored["nmrf"], mirrored["mask"], (5,))
        assert float(rate[0]) >= 0.8

    def test_axis_recovered(self, irs_result, mirrored):
        a, b = irs_result.lines[0, :2]
        ta, tb = mirrored["line"][:2]
        assert abs(float(a * ta + b * tb)) > 0.995  # within ~6 degrees

    def test_involution(self, irs_result, mirrored):
        back = _back_distance(irs_result.nmrf[0])[mirrored["mask"]]
        assert float((back <= 3).float().mean()) >= 0.8

    @pytest.mark.parametrize("scheme", ["mmp", "bmp"])
    def test_other_schemes(self, mirrored, scheme):
        r = symmetry_map(mirrored["image"], n_axes=1, patchmatch={"scheme": scheme})
        assert r.iterations == 0
        rate = nmrf_correspondence_rate(r.nmrf[0], mirrored["nmrf"], mirrored["mask"], (5,))
        assert float(rate[0]) >= 0.8

    def test_milp_cover(self, mirrored):
        r = symmetry_map(mirrored["image"], n_axes=1, clustering={"cover": "milp"}, patchmatch={"max_iters": 1})
        assert len(r) == 1

    def test_determinism(self, mirrored):
        a = symmetry_map(mirrored["image"], n_axes=1, patchmatch={"max_iters": 2})
        b = symmetry_map(mirrored["image"], n_axes=1, patchmatch={"max_iters": 2})
        c = symmetry_map(mirrored["image"], n_axes=1, patchmatch={"max_iters": 2}, generator=torch.Generator().manual_seed(5))
        assert torch.equal(a.nmrf, b.nmrf) and torch.equal(a.ssm, b.ssm)
        assert not torch.equal(a.nmrf, c.nmrf)

    def test_solver_module(self, mirrored):
        entry = SOLVERS.get("symmetry_map")
        assert entry.kind == "image" and entry.settings_class is SymmetryMapSettings
        solver = SymmetryMapSolver(n_axes=1, patchmatch={"max_iters": 1})
        assert "n_axes=1" in repr(solver)
        r = solver(mirrored["image"])
        assert len(r) == 1

    def test_max_side(self, mirrored):
        big = torch.nn.functional.interpolate(mirrored["image"][None], scale_factor=2.0, mode="bilinear")[0]
        r = symmetry_map(big, n_axes=1, max_side=200, patchmatch={"max_iters": 1})
        assert r.ssm.shape[-2:] == (160, 200) and r.scale == pytest.approx(2.0)


class TestBadInput:
    def test_no_pairs(self):
        r = symmetry_map(torch.full((3, 64, 64), 0.5), n_axes=1)
        assert len(r) == 0 and r.nmrf.shape == (0, 64, 64, 2)
        assert "no mirror pairs" in r.notes[0]
        assert torch.equal(r.score_map, torch.zeros(64, 64))

    def test_tiny_image(self):
        r = symmetry_map(torch.rand(3, 10, 12))
        assert len(r) == 0 and r.notes and r.score_map.shape == (10, 12)

    def test_k_larger_than_clusters(self, mirrored):
        r = symmetry_map(mirrored["image"], n_axes=6, patchmatch={"max_iters": 1})
        assert 1 <= len(r) < 6
        assert "asked for 6 axes" in r.notes[0]

    def test_exception(self):
        with pytest.raises(InputShapeError, match="image"):
            symmetry_map(torch.rand(2, 3, 40, 40))
        with pytest.raises(InputShapeError, match="channels"):
            symmetry_map(torch.rand(2, 40, 40))
        with pytest.raises(InputShapeError, match="image"):
            symmetry_map(np.array([["a", "b"]]))
        with pytest.raises(ConfigError, match="n_axes"):
            symmetry_map(torch.rand(3, 40, 40), n_axes=0)
        with pytest.raises(ConfigError, match="scheme"):
            symmetry_map(torch.rand(3, 40, 40), patchmatch={"scheme": "irz"})


@pytest.mark.slow
def test_real_photo_crop(shared_data):
    photos = shared_data / "images" / "reflection_single_dev"
    if not photos.is_dir():
        pytest.skip("no dev photographs")
    d = mirrored_photo(height=240, width=320, photo_dir=str(photos), generator=torch.Generator().manual_seed(2))
    r = symmetry_map(d["image"], n_axes=1)
    rate = nmrf_correspondence_rate(r.nmrf[0], d["nmrf"], d["mask"], (5,))
    assert float(rate[0]) >= 0.6


@pytest.mark.slow
def test_axes_from_the_axis_stage(mirrored):
    from torchsym.image.axes import image_axes

    r = symmetry_map(mirrored["image"], patchmatch={"max_iters": 1})
    found = image_axes(mirrored["image"])
    assert len(r) == int(found.accepted.sum()) >= 1 and "axes" in r.seconds


def test_clusters_about_axes_takes_the_pairs_near_each_axis():
    from torchsym.image.symmetry_map.estimate import clusters_about_axes

    pairs = torch.tensor([[40.0, 10.0, 60.0, 10.0], [30.0, 50.0, 70.0, 50.0], [10.0, 10.0, 20.0, 40.0]])
    lines = torch.tensor([[1.0, 0.0, -50.0]])  # x = 50
    own = [torch.tensor([[45.0, 5.0, 55.0, 5.0]])]
    all_pairs, members = clusters_about_axes(pairs, lines, own, max_angle=2.0, max_distance=3.0, min_support=2)
    assert all_pairs.shape[0] == 3 and members[0].tolist() == [0, 1]
    all_pairs, members = clusters_about_axes(pairs, lines, own, max_angle=2.0, max_distance=3.0, min_support=3)
    assert all_pairs.shape[0] == 4 and members[0].tolist() == [0, 1, 3]
