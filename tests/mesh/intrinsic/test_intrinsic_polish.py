"""Step 13: the polish (torchsym.mesh.intrinsic.polish)."""

from __future__ import annotations

import numpy as np
import pytest

from torchsym.errors import ConfigError
from torchsym.mesh import IntrinsicSymmetry, intrinsic_symmetry
from torchsym.metrics.mesh import correspondence_rate


class TestPolish:
    """Step 13: ZoomOut on into ``polish.n_eigen`` eigenfunctions, kept unless the orientation reversal falls."""

    def test_default_polishes_to_40(self, solved):
        result, mesh, gt = solved
        assert result.refined_functional_map.shape == (40, 40) and "polish" in result.timings
        assert correspondence_rate(mesh, result.map, ground_truth=gt).rate == 1.0
        assert not any("polish.n_eigen" in n for n in result.notes)

    @pytest.mark.parametrize("settings", [{"polish": {"enabled": False}}, {"polish": {"n_eigen": 25}}, {"refine": {"enabled": False}}])
    def test_off(self, blob, settings):
        mesh, gt = blob
        out = intrinsic_symmetry(mesh, **settings)
        assert "polish" not in out.timings
        assert out.refined_functional_map.shape == ((0, 0) if "refine" in settings else (25, 25))
        if "refine" not in settings:
            assert correspondence_rate(mesh, out.map, ground_truth=gt).rate == 1.0

    def test_not_kept_when_the_orientation_reversal_falls(self, blob, monkeypatch, settings_spy):
        from torchsym.mesh.intrinsic import polish

        mesh, gt = blob
        out = intrinsic_symmetry(mesh, polish={"orientation_drop": -2.0})  # no share can rise by 2
        assert out.refined_functional_map.shape == (25, 25) and "polish" in out.timings
        assert any(n.startswith("ZoomOut to polish.n_eigen = 40 eigenfunctions not kept (orientation reversed at") for n in out.notes)
        assert correspondence_rate(mesh, out.map, ground_truth=gt).rate == 1.0

    def test_a_polish_that_drifts_home_is_not_kept(self, blob, monkeypatch, settings_spy):
        from torchsym.mesh import fmaps

        mesh, _ = blob
        original = fmaps.zoomout

        def polish_drifts_home(big, area, rows, image, ks, trees, involution=True, oriented=None, brute=False):
            if int(ks[0]) <= 25:  # steps 9 and 12
                return original(big, area, rows, image, ks, trees, involution, oriented, brute=brute)
            return rows.copy(), np.eye(int(ks[-1]))

        monkeypatch.setattr(fmaps, "zoomout", polish_drifts_home)
        kept = intrinsic_symmetry(mesh, polish={"max_iters": 1})
        assert kept.refined_functional_map.shape == (25, 25)
        assert any("not kept" in n for n in kept.notes)

    @pytest.mark.parametrize("rising", [True, False])
    def test_distortion_decides_without_a_winding(self, blob, monkeypatch, rising):
        """Without a consistent winding the geodesic distortion decides: the probe here reports
        a distortion that rises (or falls) with every call, so the polished map, measured
        after the map it came from, is rejected (or kept) whatever the orientation says."""
        from torchsym.mesh.intrinsic import GeodesicProbe, polish, spectrum

        mesh, gt = blob
        calls = []

        def fake(self, image):
            calls.append(1)
            return (1e-4 * len(calls)) if rising else (0.1 - 1e-4 * len(calls))

        monkeypatch.setattr(spectrum, "consistently_wound", lambda faces: False)
        monkeypatch.setattr(GeodesicProbe, "distortion", fake)
        out = intrinsic_symmetry(mesh, polish={"orientation_drop": -2.0})  # would reject every polish if used
        assert any("not consistently wound" in n for n in out.notes)
        rejected = any(n.startswith("ZoomOut to polish.n_eigen = 40 eigenfunctions not kept (geodesic distortion") for n in out.notes)
        assert rejected == rising
        assert out.refined_functional_map.shape == ((25, 25) if rising else (40, 40))

    def test_polish_n_eigen_lowered_on_a_small_mesh(self, blob):
        mesh, gt = blob
        n = mesh.num_vertices
        out = intrinsic_symmetry(mesh, polish={"n_eigen": 5000, "max_iters": 1})
        assert any(f"polish.n_eigen lowered from 5000 to {n - 1}" in note for note in out.notes)
        assert out.refined_functional_map.shape in ((n - 1, n - 1), (25, 25))

    def test_bad_settings_and_the_module(self, blob, monkeypatch, settings_spy):
        with pytest.raises(ConfigError, match="polish.max_iters"):
            intrinsic_symmetry(blob[0], polish={"max_iters": 0})
        with pytest.raises(ConfigError, match="polish.n_eigen"):
            intrinsic_symmetry(blob[0], polish={"n_eigen": 0})
        with pytest.raises(ConfigError, match="polish.n_eigen"):
            IntrinsicSymmetry(polish={"n_eigen": 1.5})
        seen = settings_spy
        IntrinsicSymmetry(polish={"n_eigen": 30, "max_iters": 2})(blob[0])
        assert seen["settings"].polish.n_eigen == 30 and seen["settings"].polish.max_iters == 2
