"""Step 14: the realignment (torchsym.mesh.intrinsic.realign)."""

from __future__ import annotations

import numpy as np
import pytest

from torchsym.errors import ConfigError, InputValueError
from torchsym.mesh import IntrinsicSymmetry, intrinsic_symmetry
from torchsym.metrics.mesh import correspondence_rate


class TestRealign:
    """Step 14: realignment by distances to anchors, kept only when the orientation reversal clearly rises."""

    def test_repairs_a_region_mapped_to_itself(self, blob):
        """The true map with a cap of the blob sent to itself (the failure it is for): the
        realignment by geodesic distances to anchors restores the cap's mirror."""
        from torchsym.mesh.geodesic import geodesic_distances
        from torchsym.mesh.intrinsic.realign import anchor_realignment
        from torchsym.mesh.operators import edge_graph

        mesh, gt = blob
        v, f = mesh.vertices.numpy(), mesh.faces.numpy()
        graph = edge_graph(v, f)
        broken = gt.copy()
        cap = v[:, 2] > 0.5 * v[:, 2].max()  # a cap across the mirror plane x = 0
        broken[cap] = np.flatnonzero(cap)
        rng = np.random.default_rng(0)
        rows = np.sort(rng.choice(v.shape[0], 400, replace=False))
        anchors = rng.choice(rows, 48, replace=False)
        calls: list[int] = []

        def distances(sources):
            calls.extend(int(s) for s in sources)
            return geodesic_distances(graph, sources)

        image = anchor_realignment(distances, rows, broken, anchors, iters=3)
        tol = 0.1 * np.ptp(v, axis=0).max()
        wrong_before = np.linalg.norm(v[broken[rows]] - v[gt[rows]], axis=1) > tol
        wrong_after = np.linalg.norm(v[image] - v[gt[rows]], axis=1) > tol
        assert wrong_before[cap[rows]].mean() > 0.5  # the cap was broken
        assert wrong_after.mean() < 0.05
        assert len(calls) == len(set(calls))  # distances from a repeated source are read once
        with pytest.raises(InputValueError, match="anchors"):
            anchor_realignment(distances, rows, broken, np.array([rows.max() + 1]), iters=1)

    def test_exact_symmetry_is_left_alone(self, solved):
        result, mesh, gt = solved
        assert "realign" in result.timings
        assert not any(n.startswith("realigned") for n in result.notes)  # it reverses it everywhere already
        assert correspondence_rate(mesh, result.map, ground_truth=gt).rate == 1.0

    def test_kept_when_forced_and_still_exact(self, blob, monkeypatch, settings_spy):
        from torchsym.mesh.intrinsic import realign

        mesh, gt = blob
        out = intrinsic_symmetry(mesh, realign={"below": 2.0, "gain": -2.0})  # run whatever the share, keep any map
        assert any(n.startswith("realigned by ") and "distances to 64 anchors" in n for n in out.notes)
        assert correspondence_rate(mesh, out.map, ground_truth=gt).rate == 1.0

    def test_not_kept_without_a_clear_rise(self, blob, monkeypatch, settings_spy):
        from torchsym.mesh.intrinsic import realign

        mesh, _ = blob
        calls = []
        original = realign.anchor_realignment
        monkeypatch.setattr(realign, "anchor_realignment", lambda *a, **k: calls.append(1) or original(*a, **k))
        out = intrinsic_symmetry(mesh, realign={"below": 2.0, "gain": 2.0})  # no share can rise by 2
        assert len(calls) == 2  # geodesic and biharmonic distances were both tried
        assert not any(n.startswith("realigned") for n in out.notes)

    @pytest.mark.parametrize("settings", [{"realign": {"enabled": False}}, {"refine": {"enabled": False}}])
    def test_off(self, blob, settings):
        assert "realign" not in intrinsic_symmetry(blob[0], **settings).timings

    def test_runs_without_polish_in_refine_k(self, blob, monkeypatch, settings_spy):
        from torchsym.mesh.intrinsic import realign

        mesh, gt = blob
        out = intrinsic_symmetry(mesh, polish={"enabled": False}, realign={"below": 2.0, "gain": -2.0})
        assert "realign" in out.timings and "polish" not in out.timings
        assert any(n.startswith("realigned by ") for n in out.notes)
        assert out.refined_functional_map.shape == (25, 25)  # the realigned map's C in refine_k
        assert correspondence_rate(mesh, out.map, ground_truth=gt).rate == 1.0

    def test_skipped_with_a_note_without_a_winding(self, blob, monkeypatch, settings_spy):
        from torchsym.mesh.intrinsic import spectrum

        monkeypatch.setattr(spectrum, "consistently_wound", lambda faces: False)
        out = intrinsic_symmetry(blob[0])
        assert "realign" not in out.timings
        assert any(n.startswith("realignment (step 14) skipped") for n in out.notes)

    def test_bad_settings_and_the_module(self, blob, monkeypatch, settings_spy):
        with pytest.raises(ConfigError, match="realign.n_anchors"):
            intrinsic_symmetry(blob[0], realign={"n_anchors": 0})
        with pytest.raises(ConfigError, match="realign.max_iters"):
            IntrinsicSymmetry(realign={"max_iters": 1.5})
        seen = settings_spy
        IntrinsicSymmetry(realign={"n_anchors": 32, "max_iters": 2})(blob[0])
        assert seen["settings"].realign.n_anchors == 32 and seen["settings"].realign.max_iters == 2
