"""Boundary orientation + dominant cliques (thesis Sec. 2.3)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.errors import ConfigError, InputValueError
from torchsym.image import (
    BoundaryCliqueDetector,
    ReflectionAxesBatch,
    ReflectionAxesResult,
    boundary_clique_axes,
)
from torchsym.image.boundary import boundary_curves, remove_junctions
from torchsym.image.boundary_cliques.cliques import _vertex_cover_highs_zeros, _vertex_cover_lp_zeros, dominant_clique
from torchsym.metrics.axes import match_axes


class TestBoundaryCliqueAxes:
    def test_smoke(self, single_objects):
        img, _ = single_objects[0]
        res = boundary_clique_axes(img)
        assert isinstance(res, ReflectionAxesResult)
        k = res.axes.shape[0]
        assert res.axes.shape == (k, 4) and res.scores.shape == (k,) and res.lines.shape == (k, 3)
        assert bool((res.scores[:-1] >= res.scores[1:]).all())
        assert res.pair_axis.shape == (res.pairs.shape[0],)
        assert bool((res.axes[:, [0, 2]] >= -1e-3).all() and (res.axes[:, [0, 2]] <= 239 + 1e-3).all())

    def test_planted_axes_random_angles(self, single_objects):
        """The planted axis is among the three best in at least 4 of 5 random angles."""
        hits = 0
        for img, gt in single_objects:
            res = boundary_clique_axes(img)
            hits += bool(match_axes(res.axes[:3], gt, image_size=(240, 240), criterion="challenge").any())
        assert hits >= 4

    def test_deterministic(self, single_objects):
        img, _ = single_objects[2]
        a = boundary_clique_axes(img, max_boundary_pairs=30, generator=torch.Generator().manual_seed(5))
        b = boundary_clique_axes(img, max_boundary_pairs=30, generator=torch.Generator().manual_seed(5))
        assert torch.equal(a.axes, b.axes) and torch.equal(a.pairs, b.pairs)

    def test_canny_linking(self, single_objects):
        img, _ = single_objects[3]
        curves, tangent = boundary_curves(img[None], edges="canny")
        assert curves and tangent.shape == (240, 240)
        for c in curves:  # ordered chains: consecutive pixels are 8-neighbours
            assert np.abs(np.diff(c, axis=0)).max() <= 1

    def test_module_batch(self, single_objects):
        img, _ = single_objects[4]
        m = BoundaryCliqueDetector(max_axes=2)
        out = m(torch.stack([img, img]))
        assert isinstance(out, ReflectionAxesBatch) and len(out) == 2
        assert torch.equal(out[0].axes, out[1].axes)
        assert "max_axes=2" in repr(m)

    def test_stage_timings(self):
        from torchsym.image.synthetic import mirrored_objects_image

        img, _ = mirrored_objects_image(1)
        res = boundary_clique_axes(img)
        assert set(res.info["stage_seconds"]) == {"edges", "segments", "pairs", "graph", "cliques", "sift"}
        plain = boundary_clique_axes(img, sift={"enabled": False})
        assert set(plain.info["stage_seconds"]) == {"edges", "segments", "pairs", "graph", "cliques"}
        assert sum(res.info["stage_seconds"].values()) <= res.info["seconds"] + 1e-6
        again = boundary_clique_axes(img, cliques={"solver": "highs"})
        assert again.axes.shape[0] >= 1

    def test_max_samples_widens_the_stride(self):
        """Beyond ``segments.max_samples`` the same boundaries are sampled at a wider stride
        (and the pair slide follows it), not cut short."""
        from torchsym.image.boundary_cliques.detect import _boundary_samples
        from torchsym.image.boundary_cliques.settings import BoundaryCliquesSettings
        from torchsym.image.synthetic import mirrored_objects_image

        img, _ = mirrored_objects_image(2, generator=torch.Generator().manual_seed(7))
        full, _, stride = _boundary_samples(img[None], BoundaryCliquesSettings(), {})
        cap = len(full) // 3
        few, _, wide = _boundary_samples(img[None], BoundaryCliquesSettings(segments={"max_samples": cap}), {})
        assert stride == 1.5 and 0.8 * cap <= len(few) <= cap and wide == pytest.approx(1.5 * len(full) / cap)
        assert set(few.curve.tolist()) <= set(full.curve.tolist())
        span = np.ptp(full.points, axis=0)
        assert np.allclose(np.ptp(few.points, axis=0), span, atol=2 * wide)  # the same boundaries, end to end

    def test_exception(self):
        with pytest.raises(ConfigError, match="edges.detector: expected one of 'edge_drawing', 'canny', got 'sobel'"):
            BoundaryCliqueDetector(edges={"detector": "sobel"})
        with pytest.raises(ConfigError, match=r"theta: expected a finite number > 0.0 and <= 180.0, got -1.0"):
            boundary_clique_axes(torch.rand(3, 32, 32), theta=-1.0)


class TestDominantClique:
    def test_clique_plus_outliers(self):
        adj = np.zeros((9, 9), dtype=bool)
        big = [0, 2, 4, 6, 8]
        for i in big:
            for j in big:
                adj[i, j] = i != j
        adj[1, 3] = adj[3, 1] = True  # a smaller clique
        clique, used_lp = dominant_clique(adj)
        assert clique.tolist() == big and used_lp
        clique, used_lp = dominant_clique(adj, solver="highs")
        assert clique.tolist() == big and used_lp

    def test_bad_solver(self):
        with pytest.raises(InputValueError, match="solver: expected one of 'matching', 'highs', got 'glpk'"):
            dominant_clique(np.ones((3, 3), dtype=bool), solver="glpk")
        with pytest.raises(ConfigError, match="cliques.solver: expected one of 'matching', 'highs'"):
            BoundaryCliqueDetector(cliques={"solver": "glpk"})

    def test_empty(self):
        clique, _ = dominant_clique(np.zeros((4, 4), dtype=bool))
        assert clique.size == 0

    def test_matching_solves_the_lp(self):
        """The König / double-cover solution is feasible, has HiGHS's optimal value and rounds alike."""
        from scipy.optimize import linprog
        from scipy.sparse import coo_matrix, csr_matrix
        from scipy.sparse.csgraph import maximum_bipartite_matching

        rng = np.random.default_rng(0)
        for _ in range(10):
            n = int(rng.integers(20, 120))
            a = rng.random((n, n)) < 0.1
            s = rng.choice(n, int(rng.integers(3, n // 3)), replace=False)
            a[np.ix_(s, s)] = True
            a = np.triu(a, 1)
            a = a | a.T
            cu, cv = np.nonzero(np.triu(~a, 1))
            zero = _vertex_cover_lp_zeros(n, cu, cv)
            assert not (zero[cu] & zero[cv]).any()  # a clique of the graph
            m = cu.size
            a_ub = coo_matrix((-np.ones(2 * m), (np.repeat(np.arange(m), 2), np.stack([cu, cv], 1).reshape(-1))),
                              shape=(m, n)).tocsr()
            res = linprog(np.ones(n), A_ub=a_ub, b_ub=-np.ones(m), bounds=(0, 1), method="highs")
            assert res.status == 0
            r, c = np.concatenate([cu, cv]), np.concatenate([cv, cu])
            match = maximum_bipartite_matching(csr_matrix((np.ones(r.size), (r, c)), shape=(n, n)), perm_type="column")
            assert res.fun == pytest.approx(0.5 * int((match >= 0).sum()))  # König: LP optimum = matching / 2
            assert np.array_equal(np.nonzero(zero)[0], np.nonzero(res.x < 0.5)[0])
            assert np.array_equal(zero, _vertex_cover_highs_zeros(n, cu, cv))


class TestRemoveJunctions:
    def test_cross_is_split(self):
        e = np.zeros((21, 21), dtype=bool)
        e[10, 2:19] = True
        e[2:19, 10] = True
        strength = np.ones((21, 21), np.float32)
        out = remove_junctions(e, strength)
        import cv2

        count = cv2.filter2D(out.astype(np.float32), -1, np.ones((3, 3), np.float32), borderType=cv2.BORDER_CONSTANT)
        assert int(((count > 3.5) & out).sum()) == 0  # nothing branches any more
        assert out.sum() >= 28  # the four arms survive
