"""Tests of the deterministic direction samples and the seeded surface sampler."""

from __future__ import annotations

import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.geometry import Mesh, sample_surface, sphere_normals


class TestSphereNormals:
    def test_smoke(self):
        n = sphere_normals(100)
        assert n.shape == (100, 3) and n.dtype == torch.float64
        torch.testing.assert_close(n.norm(dim=1), torch.ones(100, dtype=torch.float64))
        assert bool((n[:, 2] > 0).all())  # the upper half sphere: one normal per plane

    def test_covers_the_half_sphere(self):
        # every direction of the half sphere lies within 12 degrees of one of 100 samples
        probe = torch.randn(2000, 3, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
        probe = probe / probe.norm(dim=1, keepdim=True)
        cos = (probe @ sphere_normals(100).T).abs().max(1).values
        assert float(torch.rad2deg(torch.arccos(cos.clamp(max=1.0))).max()) < 12.0

    def test_dtype(self):
        assert sphere_normals(5, dtype=torch.float32).dtype == torch.float32


def _two_squares() -> Mesh:
    """A unit square at z = 0 (two triangles) and a 3 x 3 square at z = 1 (two triangles):
    areas 1 and 9, vertex counts equal."""
    v = torch.tensor([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                      [0, 0, 1], [3, 0, 1], [3, 3, 1], [0, 3, 1]], dtype=torch.float32)
    f = torch.tensor([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    return Mesh(v, f)


class TestSampleSurface:
    def test_smoke(self):
        pts = sample_surface(_two_squares(), 500, generator=0)
        assert pts.shape == (500, 3) and pts.dtype == torch.float32
        assert sample_surface(_two_squares(), 7, dtype=torch.float64).dtype == torch.float64

    def test_points_lie_on_the_triangles(self):
        pts = sample_surface(_two_squares(), 2000, generator=1)
        low = pts[:, 2] == 0
        assert bool((pts[:, 2][~low] == 1).all())
        assert bool((pts[low, :2] >= 0).all() and (pts[low, :2] <= 1).all())
        assert bool((pts[~low, :2] >= 0).all() and (pts[~low, :2] <= 3).all())

    def test_area_weighted(self):
        # the big square holds 9/10 of the area, so 9/10 of the points (not half, as vertices would)
        pts = sample_surface(_two_squares(), 20000, generator=2)
        frac = float((pts[:, 2] == 1).double().mean())
        assert abs(frac - 0.9) < 0.01
        # uniform inside a triangle: the unit square's points have mean (0.5, 0.5)
        low = pts[pts[:, 2] == 0, :2].double()
        torch.testing.assert_close(low.mean(0), torch.tensor([0.5, 0.5], dtype=torch.float64), atol=0.03, rtol=0)

    def test_seeded(self):
        mesh = _two_squares()
        a = sample_surface(mesh, 300, generator=torch.Generator().manual_seed(5))
        b = sample_surface(mesh, 300, generator=torch.Generator().manual_seed(5))
        assert torch.equal(a, b)
        assert not torch.equal(a, sample_surface(mesh, 300, generator=6))
        assert torch.equal(sample_surface(mesh, 300), sample_surface(mesh, 300))  # None: seed 0

    def test_input_unchanged(self):
        mesh = _two_squares()
        before = mesh.vertices.clone()
        sample_surface(mesh, 100)
        assert torch.equal(mesh.vertices, before)

    def test_exception(self):
        with pytest.raises(InputValueError, match="count: expected an integer >= 1"):
            sample_surface(_two_squares(), 0)
        flat = Mesh(torch.zeros(3, 3), torch.tensor([[0, 1, 2]]))
        with pytest.raises(InputValueError, match="mesh: expected triangles of positive total area"):
            sample_surface(flat, 10)
