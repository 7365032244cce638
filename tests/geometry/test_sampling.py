"""Tests of the deterministic direction samples."""

from __future__ import annotations

import torch

from torchsym.geometry import sphere_normals


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
