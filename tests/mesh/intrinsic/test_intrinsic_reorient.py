"""Step 12: the orientation check (torchsym.mesh.intrinsic.reorient)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.errors import ConfigError
from torchsym.mesh import IntrinsicSymmetry, Mesh, intrinsic_symmetry
from torchsym.metrics.mesh import correspondence_rate


class TestOrientationCheck:
    """Step 12: a final map that keeps the surface's orientation is refined again with the orientation penalty."""

    def test_oriented_fit_is_the_exact_minimiser(self, spectral25):
        from torchsym.mesh.fmaps import zoomout_fit
        from torchsym.mesh.intrinsic.reorient import oriented_fits

        big, area, ops, rows, gt = spectral25
        kk, weight = 16, 30.0
        factor = oriented_fits(big, area, rows, np.array([kk]), ops, (weight,))[0][kk]
        phi = big[rows, :kk]
        w = area[rows] / area[rows].sum()
        image = gt[rows].copy()
        wrong = np.random.default_rng(2).random(rows.size) < 0.3
        image[wrong] = rows[wrong]  # a third of the map left in place: no exact fit
        target = big[image, :kk]
        c = zoomout_fit(big[:, :kk], area, rows, image, factor)
        o = ops[:, :kk, :kk]
        scale = 2.0 * np.sum(o**2) + 2.0 * np.sum(np.trace(o, axis1=1, axis2=2) ** 2) / kk

        def energy(m):
            fit = np.sum(w[:, None] * (phi @ m - target) ** 2)
            return fit + weight * sum(np.sum((m @ x + x @ m) ** 2) for x in o) / scale

        rng = np.random.default_rng(1)
        base = energy(c)
        for _ in range(5):  # the gradient vanishes: a step either way costs the same, second-order amount
            d = rng.standard_normal((kk, kk))
            up, down = energy(c + 1e-3 * d), energy(c - 1e-3 * d)
            assert up > base and down > base
            assert abs(up - down) < 1e-6 * (up + down - 2 * base)

    def test_penalty_keeps_the_mirror_and_dislodges_the_identity(self, spectral25):
        from torchsym.mesh.fmaps import zoomout
        from torchsym.mesh.intrinsic.reorient import oriented_fits
        from torchsym.mesh.nearest import SampledSearch

        big, area, ops, rows, gt = spectral25
        ks = np.array([16, 19, 22, 25])
        trees = SampledSearch(big, None)
        oriented = oriented_fits(big, area, rows, ks, ops, (30.0,))[0]
        mirror, _ = zoomout(big, area, rows, gt[rows], ks, trees, True, oriented)
        assert np.mean(mirror == gt[rows]) > 0.99
        plain, _ = zoomout(big, area, rows, rows.copy(), ks, trees, True)
        assert np.mean(plain == rows) > 0.99  # plain ZoomOut cannot leave the identity
        moved, _ = zoomout(big, area, rows, rows.copy(), ks, trees, True, oriented)
        assert np.mean(moved == rows) < 0.2

    @staticmethod
    def _two_mirror_blob():
        """Symmetric across x = 0 and y = 0, hence also under the half turn about z (which keeps orientation)."""
        from scipy.spatial import cKDTree

        from torchsym.mesh.synthetic import icosphere

        s = icosphere(3)
        v = s.vertices.numpy()
        x, y, z = v.T
        scale = 1 + 0.8 * x**2 + 0.3 * y**2 + 0.25 * z
        for cx in (-1.0, 1.0):
            for cy in (-1.0, 1.0):
                c = np.array([0.6 * cx, 0.3 * cy, 0.7])
                scale = scale + 0.5 * np.exp(-((v - c / np.linalg.norm(c)) ** 2).sum(1) / 0.02)
        w = v * scale[:, None]
        maps = {name: cKDTree(w).query(w * np.array(m))[1] for name, m in
                (("x", [-1.0, 1.0, 1.0]), ("y", [1.0, -1.0, 1.0]), ("turn", [-1.0, -1.0, 1.0]))}
        return Mesh(torch.from_numpy(w), s.faces), maps

    @staticmethod
    def _turn_refiner(fmaps, maps, oriented_too: bool = False):
        """A stand-in for ZoomOut whose plain refinement (and with ``oriented_too`` every one) ends on the half turn."""
        from torchsym.mesh.fmaps import fit_functional

        original = fmaps.zoomout

        def refine_to_the_turn(big, area, rows, image, ks, trees, involution=True, oriented=None, brute=False):
            # an isometric involution that keeps the orientation
            if oriented is not None and not oriented_too:
                return original(big, area, rows, image, ks, trees, involution, oriented, brute=brute)
            k = int(ks[-1])
            turn = maps["turn"][rows]
            return turn, fit_functional(big[rows, :k], big[turn, :k], area[rows])

        return refine_to_the_turn

    def test_a_map_that_keeps_orientation_is_replaced(self, monkeypatch):
        from torchsym.mesh import fmaps
        from torchsym.mesh.orientation import orientation_reversal

        mesh, maps = self._two_mirror_blob()
        v, f = mesh.vertices.numpy(), mesh.faces.numpy()
        assert np.mean(orientation_reversal(v, f, maps["turn"]) < 0) == 0.0
        monkeypatch.setattr(fmaps, "zoomout", self._turn_refiner(fmaps, maps))
        off = intrinsic_symmetry(mesh, refine={"orientation_weight": 0.0})
        assert np.mean(off.map.numpy() == maps["turn"]) > 0.95 and "orientation_check" not in off.timings
        out = intrinsic_symmetry(mesh)
        got = out.map.numpy()
        assert np.mean(orientation_reversal(v, f, got) < 0) > 0.8
        assert max(np.mean(got == maps["x"]), np.mean(got == maps["y"])) > 0.9
        assert any("refined again with the orientation penalty" in n for n in out.notes)

    def test_a_reflection_passes_untouched(self, solved):
        result = solved[0]
        assert "orientation_check" in result.timings
        assert not any("orientation" in n and "penalty" in n for n in result.notes)

    def test_bad_weight(self, blob):
        with pytest.raises(ConfigError, match="refine.orientation_weight"):
            intrinsic_symmetry(blob[0], refine={"orientation_weight": -1.0})

    @staticmethod
    def _drifting_refiner(fmaps):
        """A stand-in for ZoomOut whose plain refinement drifts to the identity on every hypothesis, so none passes step 9."""
        original = fmaps.zoomout

        def plain_drifts_home(big, area, rows, image, ks, trees, involution=True, oriented=None, brute=False):
            if oriented is not None:
                return original(big, area, rows, image, ks, trees, involution, oriented, brute=brute)
            return rows.copy(), np.eye(int(ks[-1]))

        return plain_drifts_home

    def test_rescues_when_no_hypothesis_passes(self, blob, monkeypatch, settings_spy):
        from torchsym.mesh import fmaps

        mesh, gt = blob
        monkeypatch.setattr(fmaps, "zoomout", self._drifting_refiner(fmaps))
        off = intrinsic_symmetry(mesh, refine={"orientation_weight": 0.0})
        assert any("returned unrefined and is unreliable" in n for n in off.notes)
        out = intrinsic_symmetry(mesh)
        assert not any("unreliable" in n for n in out.notes)
        assert any(n.startswith("no hypothesis passed the tests of an isometric involution; refined") for n in out.notes)
        assert correspondence_rate(mesh, out.map, ground_truth=torch.from_numpy(gt)).rate > 0.95
        assert out.refined_functional_map.shape == (25, 25)

    def test_rescue_allows_more_distortion(self, blob, monkeypatch, settings_spy):
        """With no passing hypothesis the rescue takes maps up to 1.5x the distortion limit, and says so."""
        from torchsym.mesh import fmaps
        from torchsym.mesh.intrinsic import GeodesicProbe

        mesh, gt = blob
        monkeypatch.setattr(fmaps, "zoomout", self._drifting_refiner(fmaps))
        monkeypatch.setattr(GeodesicProbe, "distortion", lambda self, image: 0.15)
        out = intrinsic_symmetry(mesh, select={"max_distortion": 0.12})  # 0.15 < 1.5 x 0.12
        assert any("distorts geodesics by 0.150, above the limit 0.12: the map is less reliable" in n for n in out.notes)
        assert correspondence_rate(mesh, out.map, ground_truth=torch.from_numpy(gt)).rate > 0.95
        tight = intrinsic_symmetry(mesh, select={"max_distortion": 0.09})  # 0.15 > 1.5 x 0.09
        assert any("returned unrefined and is unreliable" in n for n in tight.notes)
        assert not any("refined with the orientation penalty" in n for n in tight.notes)

    def test_no_reoriented_map_found_keeps_the_map(self, monkeypatch):
        from torchsym.mesh import fmaps

        mesh, maps = self._two_mirror_blob()
        monkeypatch.setattr(fmaps, "zoomout", self._turn_refiner(fmaps, maps, oriented_too=True))
        out = intrinsic_symmetry(mesh)
        assert np.mean(out.map.numpy() == maps["turn"]) > 0.95
        assert any("found no map that reverses it at 60%, the map is unreliable" in n for n in out.notes)

    def test_skipped_on_inconsistent_winding(self, blob, monkeypatch, settings_spy):
        from torchsym.mesh import consistently_wound
        from torchsym.mesh import fmaps

        mesh, maps = self._two_mirror_blob()
        f = mesh.faces.numpy().copy()
        assert consistently_wound(f)
        right = mesh.vertices.numpy()[f].mean(axis=1)[:, 0] > 0
        f[right] = f[right][:, ::-1]  # half the mesh mirrored without flipping its triangles
        assert not consistently_wound(f)
        assert consistently_wound(f[:0])
        from torchsym.mesh.operators import _pair_keys

        assert _pair_keys(np.array([[0, 3_000_000_000]])) is None  # the slow exact path
        huge = mesh.faces.numpy() + 3_000_000_000  # indices only: the winding test needs no vertices
        assert consistently_wound(huge) and not consistently_wound(f + 3_000_000_000)
        monkeypatch.setattr(fmaps, "zoomout", self._turn_refiner(fmaps, maps))
        out = intrinsic_symmetry(Mesh(mesh.vertices, torch.from_numpy(f)))
        assert "orientation_check" not in out.timings
        assert any("not consistently wound" in n for n in out.notes)

    def test_skipped_above_refine_k_50(self, blob):
        out = intrinsic_symmetry(blob[0], refine={"n_eigen": 51})
        assert "orientation_check" not in out.timings
        assert any("refine.n_eigen > 50" in n for n in out.notes)

    def test_module_forwards_and_checks_the_weight(self, blob, monkeypatch, settings_spy):
        seen = settings_spy
        IntrinsicSymmetry(refine={"orientation_weight": 12.5})(blob[0])
        assert seen["settings"].refine.orientation_weight == 12.5
        with pytest.raises(ConfigError, match="refine.orientation_weight"):
            IntrinsicSymmetry(refine={"orientation_weight": -1.0})
