"""torchsym.pointcloud.reflection_plane.starts: the list of starts and when it ends."""

import pytest
import torch

import torchsym.pointcloud.reflection_plane.starts as starts
from torchsym.core.settings import resolve_settings
from torchsym.pointcloud import planted_symmetric_cloud
from torchsym.pointcloud.prepare import normalise, subsample
from torchsym.pointcloud.reflection_plane.settings import ReflectionPlaneSettings


def _search(n: int, seed: int, noise: float = 0.0, **overrides):
    g = torch.Generator().manual_seed(seed)
    pts = planted_symmetric_cloud(n, generator=g, dtype=torch.float64).points
    pts = pts + noise * torch.randn(pts.shape, generator=g, dtype=pts.dtype)  # no exact mirror left
    settings = resolve_settings(ReflectionPlaneSettings, None, overrides)
    gen = torch.Generator().manual_seed(0)
    norm = normalise(pts, torch.float64)
    subs = subsample(norm, settings, gen)
    axes = starts.principal_axes(subs.centered, subs.sample, subs.index, subs.spacing)
    ctx = starts.refine_context(norm.xs, subs, settings, gen)
    return starts.search_starts(axes, subs, ctx, settings)


class TestSearchStarts:
    def test_accepted(self):
        search = _search(4000, 3)
        assert search.stop == "accepted" and search.tried <= 3

    def test_dominant_ends_without_fallback(self, monkeypatch):
        """A start that dominates decides the search: the Algorithm 6 fallback does not run."""
        def no_fallback(*args, **kwargs):
            raise AssertionError("the fallback ran")

        monkeypatch.setattr(starts, "_fallback", no_fallback)
        search = _search(1000, 5, 0.05, starts={"accept": 1.0, "reference_floor": 1.0, "pca": False, "dominance": 0.0, "dominance_gap": 0.0,
                                         "dominance_after": 2})
        assert search.stop == "dominant" and search.tried == 2

    def test_exhausted_runs_fallback(self, monkeypatch):
        calls = []
        monkeypatch.setattr(starts, "_fallback", lambda search, ctx, settings: calls.append(search.tried))
        search = _search(1000, 5, 0.05, n_starts=3, starts={"accept": 1.0, "reference_floor": 1.0, "pca": False, "dominance": 100.0})
        assert search.stop == "exhausted" and calls == [search.tried]

    def test_confirmed(self):
        """With ``starts.confirm`` a start aligned onto the best plane so far ends the list."""
        kw = {"n_starts": 40, "starts": {"accept": 1.0, "reference_floor": 1.0, "dominance": 100.0, "confirm": True}}
        search = _search(1000, 5, 0.005, **kw)
        assert search.stop == "confirmed" and search.tried < 43
        off = _search(1000, 5, 0.005, **{**kw, "starts": {**kw["starts"], "confirm": False}})
        assert off.stop == "exhausted" and off.tried > search.tried

    def test_same_plane(self):
        pts = torch.randn(200, 3, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
        n = torch.tensor([0.0, 0.0, 1.0], dtype=torch.float64)
        b = torch.tensor(0.1, dtype=torch.float64)
        assert starts.same_plane(pts, (n, b), (-n, -b), 1e-9)
        assert starts.same_plane(pts, (n, b), (n, b + 0.004), 0.01)
        assert not starts.same_plane(pts, (n, b), (n, b + 0.01), 0.01)

    @pytest.mark.parametrize("supports, expected", [([0.9, 0.3, 0.3, 0.3, 0.3, 0.3], True), ([0.9, 0.3], False)])
    def test_is_dominant(self, supports, expected):
        assert starts.is_dominant(supports, ReflectionPlaneSettings().starts) is expected
