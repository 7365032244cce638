"""torchsym.pointcloud.reflection_plane.prealign: neighbourhoods, pre-alignment and support."""

import torch

from torchsym.geometry import reflect_points
from torchsym.matching import KNNIndex
from torchsym.pointcloud import planted_symmetric_cloud
from torchsym.pointcloud.neighbourhood import neighbourhood_pca
from torchsym.pointcloud.reflection_plane.prealign import local_pca, support


def _cloud(n: int = 2000):
    c = planted_symmetric_cloud(n, generator=torch.Generator().manual_seed(4), dtype=torch.float64)
    return c.points, c.normal, c.offset


class TestNeighbourhoodPca:
    def test_smoke(self):
        pts, _, _ = _cloud()
        at = pts[:7] + 0.01
        centroid, lam, vecs = neighbourhood_pca(pts, KNNIndex(pts), at, 10)
        assert centroid.shape == (7, 3) and lam.shape == (7, 3) and vecs.shape == (7, 3, 3)
        assert bool((lam[:, 1:] >= lam[:, :-1]).all())

    def test_value(self):
        """At the points themselves, the eigenpairs are local_pca's; the centroid is the
        mean of the k nearest points."""
        pts, _, _ = _cloud()
        index = KNNIndex(pts)
        centroid, lam, vecs = neighbourhood_pca(pts, index, pts, 10)
        lam_ref, vecs_ref = local_pca(pts, index, 10)
        assert torch.equal(lam, lam_ref) and torch.equal(vecs, vecs_ref)
        _, j = index.query(pts[:3], k=10)
        assert torch.allclose(centroid[:3], pts[j].mean(1), atol=1e-15)


class TestSupport:
    def test_value(self):
        """The bounded search gives the kernel mean over every residual (those beyond the
        reach add nothing visible)."""
        pts, normal, offset = _cloud()
        index = KNNIndex(pts)
        tilted = torch.nn.functional.normalize(normal + torch.tensor([0.2, -0.1, 0.05], dtype=normal.dtype), dim=0)
        for n in (normal, tilted):
            d, _ = index.query(reflect_points(pts, n, offset))
            for sigma in (1e-3, 1e-2):
                frac, med = support(pts, index, n, offset, sigma)
                assert abs(frac - float(torch.exp(-0.5 * (d / sigma) ** 2).mean())) < 1e-7
                assert med == float(d.median()) or (med == float("inf") and float(d.median()) >= 6 * sigma)

    def test_exact_plane_full_support(self):
        pts, normal, offset = _cloud()
        frac, med = support(pts, KNNIndex(pts), normal, offset, 1e-3)
        assert frac > 0.999 and med < 1e-9
