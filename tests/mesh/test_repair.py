from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.errors import ConfigError
from torchsym.mesh.intrinsic import intrinsic_symmetry
from torchsym.mesh.operators import edge_face_counts
from torchsym.mesh.repair import HoleFilling, _loop_spans, boundary_loops, close_holes
from torchsym.mesh.synthetic import icosphere, punch_holes
from torchsym.metrics.mesh import correspondence_rate


def _sphere_with_holes(centres: list[int]) -> tuple[np.ndarray, np.ndarray]:
    s = icosphere(3)
    v, f = s.vertices.numpy(), s.faces.numpy()
    return v, f[~np.isin(f, centres).any(axis=1)]  # remove each centre's fan: one hole each


class TestCloseHoles:
    def test_closes_every_hole(self):
        v, f = _sphere_with_holes([0, 300])
        v_before, f_before = v.copy(), f.copy()
        assert boundary_loops(f, v.shape[0]) == 2
        filling = close_holes(v, f)
        assert isinstance(filling, HoleFilling) and filling.notes == ()
        assert filling.holes_closed == 2 and boundary_loops(filling.faces, v.shape[0]) == 0
        assert filling.faces.dtype == np.int64
        np.testing.assert_array_equal(filling.faces[: f.shape[0]], f)  # the input's triangles first
        assert (edge_face_counts(filling.faces)[1] == 2).all()  # a closed manifold
        np.testing.assert_array_equal(v, v_before)  # inputs untouched
        np.testing.assert_array_equal(f, f_before)

    def test_holes_touching_at_a_vertex(self):
        # the fans of two vertices two edges apart share a vertex: two loops, two patches
        s = icosphere(3)
        v, f = s.vertices.numpy(), s.faces.numpy()
        ring = np.setdiff1d(f[(f == 0).any(axis=1)], [0])
        second = np.setdiff1d(f[np.isin(f, ring).any(axis=1)], np.r_[ring, 0])[0]
        holed = f[~np.isin(f, [0, second]).any(axis=1)]
        assert boundary_loops(holed, v.shape[0]) == 2
        filling = close_holes(v, holed)
        assert filling.holes_closed == 2 and boundary_loops(filling.faces, v.shape[0]) == 0

    def test_closed_mesh_unchanged(self):
        s = icosphere(2)
        f = s.faces.numpy()
        filling = close_holes(s.vertices.numpy(), f)
        assert filling.holes_closed == 0 and filling.notes == ()
        np.testing.assert_array_equal(filling.faces, f)

    def test_outline_of_open_surface_left_open(self):
        # a hemisphere's rim is no hole: its patch would be half the surface's area
        s = icosphere(3)
        v, f = s.vertices.numpy(), s.faces.numpy()
        upper = f[(v[f][:, :, 2] > -1e-9).all(axis=1)]
        filling = close_holes(v, upper)
        assert filling.holes_closed == 0 and "left open" in filling.notes[0]
        np.testing.assert_array_equal(filling.faces, upper)
        assert boundary_loops(upper, v.shape[0]) == 1
        # with a larger limit it is covered
        filling = close_holes(v, upper, max_area=1.0)
        assert filling.holes_closed == 1 and boundary_loops(filling.faces, v.shape[0]) == 0

    def test_large_outline_skips_meshlab(self, monkeypatch):
        # the rim's vector area (pi, half the hemisphere's area) bounds any patch from below,
        # so the rim is left open without asking MeshLab
        import sys

        s = icosphere(3)
        v, f = s.vertices.numpy(), s.faces.numpy()
        upper = f[(v[f][:, :, 2] > -1e-9).all(axis=1)]
        span, simple = _loop_spans(v, upper)
        assert simple.tolist() == [True] and abs(span[0] - np.pi) < 0.05 * np.pi
        monkeypatch.setitem(sys.modules, "pymeshlab", None)  # importing it now fails
        filling = close_holes(v, upper)
        assert filling.holes_closed == 0 and "1 boundary loops left open" in filling.notes[0]

    def test_small_hole_touching_a_large_outline_is_closed(self):
        # a hole whose outline meets the hemisphere's rim at one vertex: one boundary
        # component, not a single loop, whose summed vector area exceeds the limit; the
        # shortcut must not skip MeshLab there, and the small hole is covered
        s = icosphere(3)
        v, f = s.vertices.numpy(), s.faces.numpy()
        upper = f[(v[f][:, :, 2] > -1e-9).all(axis=1)]
        edges, counts = edge_face_counts(upper)
        on_rim = np.zeros(v.shape[0], dtype=bool)
        on_rim[np.unique(edges[counts == 1])] = True

        def ring(u):
            return np.setdiff1d(upper[(upper == u).any(axis=1)], [u])

        u, w = next(
            (u, w)
            for u in np.unique(upper)
            if not on_rim[ring(u)].any() and not on_rim[u]
            for w in ring(u)
            if on_rim[ring(w)].sum() == 1
        )
        holed = upper[~np.isin(upper, [u, w]).any(axis=1)]
        span, simple = _loop_spans(v, holed)
        assert boundary_loops(holed, v.shape[0]) == 2 and simple.tolist() == [False] and span[0] > 1.0
        assert close_holes(v, holed).holes_closed == 1

    @pytest.mark.parametrize("shift", [0.0, 100.0, 1e8])
    def test_flipped_rim_triangle_and_far_coordinates(self, shift):
        # a small hole with one flipped triangle on its rim, anywhere in space, is closed
        s = icosphere(3)
        v, f0 = s.vertices.numpy() + np.array([shift, 0.0, 0.0]), s.faces.numpy()
        rim = np.setdiff1d(f0[(f0 == 0).any(axis=1)], [0])
        f = f0[~(f0 == 0).any(axis=1)].copy()
        j = np.flatnonzero(np.isin(f, rim).sum(axis=1) == 2)[0]
        f[j] = f[j][::-1]
        assert _loop_spans(v, f)[1].tolist() == [False]
        assert close_holes(v, f).holes_closed == 1
        if shift:  # a consistently oriented hole far away: its vector area is still small
            g = f0[~(f0 == 0).any(axis=1)]
            span, simple = _loop_spans(v, g)
            assert simple.all() and span[0] < 0.05

    def test_vector_area_bounds_the_patch(self):
        # each hole's patch is at least as large as the hole's vector area
        from torchsym.mesh.operators import face_areas

        v, f = _sphere_with_holes([0, 300, 500])
        span, simple = _loop_spans(v, f)
        filling = close_holes(v, f, max_area=1.0)
        assert simple.all() and filling.holes_closed == 3
        patches = face_areas(v, filling.faces[f.shape[0] :])
        assert 0 < span.sum() <= patches.sum() + 1e-12
        assert span.sum() > 0.8 * patches.sum()  # small, nearly flat holes: close to it

    def test_small_hole_kept_beside_an_outline(self):
        # an open hemisphere with a small hole: the hole is covered, the rim left open
        s = icosphere(3)
        v, f = s.vertices.numpy(), s.faces.numpy()
        top = int(np.argmax(v[:, 2]))
        upper = f[(v[f][:, :, 2] > -1e-9).all(axis=1) & ~(f == top).any(axis=1)]
        assert boundary_loops(upper, v.shape[0]) == 2
        filling = close_holes(v, upper)
        assert filling.holes_closed == 1 and boundary_loops(filling.faces, v.shape[0]) == 1


class TestIntrinsicSymmetryWithHoles:
    def test_fill_holes_recovers_the_map(self, blob):
        # 10 % of the area punched out at asymmetric places: without closing the holes the
        # pairing finds a wrong map (rate 0.2); on the patched mesh it is exact
        mesh, gt = blob
        holed, truth = punch_holes(mesh, torch.from_numpy(gt), area_fraction=0.1, generator=torch.Generator().manual_seed(0))
        verts, faces = holed.vertices.clone(), holed.faces.clone()
        filled = intrinsic_symmetry(holed)
        assert filled.holes_closed >= 1 and any("fill_holes" in note for note in filled.notes)
        assert correspondence_rate(holed, filled.map, ground_truth=truth).rate > 0.95
        assert int(filled.map.max()) < holed.num_vertices  # a map of the input's vertices
        plain = intrinsic_symmetry(holed, fill_holes=False, extrinsic={"enabled": False})
        assert plain.holes_closed == 0
        assert correspondence_rate(holed, plain.map, ground_truth=truth).rate < 0.5
        assert torch.equal(holed.vertices, verts) and torch.equal(holed.faces, faces)  # input untouched
        again = intrinsic_symmetry(holed)  # seeded: the same bits
        assert torch.equal(again.map, filled.map)

    def test_bad_flag(self, blob):
        with pytest.raises(ConfigError, match="fill_holes: expected true or false"):
            intrinsic_symmetry(blob[0], fill_holes="yes")
