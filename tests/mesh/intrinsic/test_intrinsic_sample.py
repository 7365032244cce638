"""Step 9's vertex sample, its even subset and the deferred thesis map (torchsym.mesh.intrinsic.sample)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.errors import ConfigError
from torchsym.mesh import IntrinsicSymmetry, intrinsic_symmetry, laplacian_eigen


class TestVertexSubsample:
    """``select.max_search_vertices``: the searches on the vertex sample look among an even subset."""

    def test_even_subset(self):
        from scipy.spatial import cKDTree

        from torchsym.mesh.intrinsic.sample import even_subset
        from torchsym.mesh.synthetic import icosphere

        v = icosphere(4).vertices.double().numpy()  # (2562, 3)
        v = v / np.sqrt(4 * np.pi)  # about unit area
        rng = np.random.default_rng(0)
        rows = np.sort(rng.choice(v.shape[0], size=100, replace=False))
        sub = even_subset(v, rows, 500, np.random.default_rng(1))
        assert np.all(np.diff(sub) > 0) and np.isin(rows, sub).all() and 400 < sub.size <= 500
        # every vertex nearer a kept one than with a uniformly random subset of the same size
        gap = cKDTree(v[sub]).query(v)[0].max()
        random_gaps = [
            cKDTree(v[np.random.default_rng(s).choice(v.shape[0], size=sub.size, replace=False)]).query(v)[0].max()
            for s in range(5)
        ]
        assert gap < min(random_gaps)
        # the same generator state, the same subset; rows beyond m are all kept
        assert np.array_equal(sub, even_subset(v, rows, 500, np.random.default_rng(1)))
        assert np.array_equal(even_subset(v, rows, 50, np.random.default_rng(1)), rows)

    def test_sample_seed_read_ahead(self, blob, monkeypatch):
        # step 9's sample is drawn from the seed after the eigensolver's and one per pairing
        # with pairs; with the HKS pairing left without pairs, that is the third draw
        from torchsym.core.random import draw_seed
        from torchsym.mesh.intrinsic import hypotheses, solver

        mesh, _ = blob
        pairs_fn, probe_cls, seen = hypotheses.symmetric_pairs, solver.GeodesicProbe, []

        def no_hks_pairs(*args, **kwargs):
            pairs, cost = pairs_fn(*args, **kwargs)
            assert pairs.shape[0] > 0  # both pairings find pairs here: the guess of two sign draws would be right
            return (pairs[:0], cost) if kwargs["spectral_weight"] == 0.0 else (pairs, cost)

        monkeypatch.setattr(hypotheses, "symmetric_pairs", no_hks_pairs)
        monkeypatch.setattr(solver, "GeodesicProbe", lambda graph, rows, rng: seen.append(rows) or probe_cls(graph, rows, rng))
        intrinsic_symmetry(mesh, generator=torch.Generator().manual_seed(5), select={"n_samples": 200})
        gen = torch.Generator().manual_seed(5)
        seed = [draw_seed(gen) for _ in range(3)][-1]
        expected = np.sort(np.random.default_rng(seed).choice(mesh.num_vertices, size=200, replace=False))
        assert np.array_equal(seen[0], expected)

    def test_recovers_the_symmetry_searching_a_subset(self, blob, monkeypatch):
        from torchsym.mesh.nearest import SampledSearch

        mesh, gt = blob
        sizes = []
        original = SampledSearch.__init__

        def spy(self, big, targets):
            sizes.append(None if targets is None else targets.size)
            original(self, big, targets)

        monkeypatch.setattr(SampledSearch, "__init__", spy)
        # (without the extrinsic plane, which would recover this exact mirror symmetry by itself)
        out = intrinsic_symmetry(mesh, select={"n_samples": 160, "max_search_vertices": 320}, extrinsic={"enabled": False})
        whole = intrinsic_symmetry(mesh, select={"n_samples": 160}, extrinsic={"enabled": False})
        assert sizes[0] is not None and 160 <= sizes[0] <= 320 and sizes[1] is None  # 642 vertices
        assert out.hypothesis == whole.hypothesis == "pairs"
        assert (out.map.numpy() == gt).mean() > 0.99 and (whole.map.numpy() == gt).mean() > 0.99
        # at least twice the sample is searched, with a note
        raised = intrinsic_symmetry(mesh, select={"n_samples": 160, "max_search_vertices": 200}, extrinsic={"enabled": False})
        assert 200 < sizes[2] <= 320 and "select.max_search_vertices raised from 200 to 320, twice the vertex sample" in raised.notes

    def test_map_before_refine_is_searched_when_first_read(self, blob):
        from torchsym.mesh.intrinsic.result import Deferred

        mesh, _ = blob
        result = intrinsic_symmetry(mesh)
        assert isinstance(object.__getattribute__(result, "map_before_refine"), Deferred)
        first = result.map_before_refine
        assert first.dtype == torch.int64 and first.shape == result.map.shape
        assert result.map_before_refine is first  # searched once
        assert result.to_dict()["map_before_refine"] == first.tolist()
        assert torch.equal(result.to("cpu").map_before_refine, first)
        import copy
        import pickle

        for make in (lambda r: pickle.loads(pickle.dumps(r)), copy.deepcopy):  # before and after the first read
            fresh = intrinsic_symmetry(mesh)
            assert torch.equal(make(fresh).map_before_refine, first) and torch.equal(make(result).map_before_refine, first)
        unrefined = intrinsic_symmetry(mesh, refine={"enabled": False})  # there it is the result, searched in the call
        assert isinstance(object.__getattribute__(unrefined, "map_before_refine"), torch.Tensor)

    def test_map_before_refine_is_a_near_nearest_map(self, solved):
        # when ZoomOut's map replaces it, the thesis's dense map comes from an approximate
        # search: each image at most 1.5 times as far as the nearest row of the embedding
        from scipy.spatial import cKDTree

        result, mesh, _ = solved
        assert result.hypothesis == "pairs"
        v = mesh.vertices.double().numpy()
        _, phi = laplacian_eigen(v, mesh.faces.numpy(), 40)
        signs = np.diag(result.functional_map.numpy())
        emb = (phi[:, :13] @ result.rotation.numpy())[:, signs != 0]
        target, query = emb * signs[signs != 0], emb
        nearest, exact = cKDTree(target).query(query)
        image = result.map_before_refine.numpy()
        got = np.linalg.norm(query - target[image], axis=1)
        assert np.all(got <= 1.5 * nearest + 1e-12) and (image == exact).mean() > 0.9

    def test_bad_setting(self, blob):
        mesh, _ = blob
        with pytest.raises(ConfigError, match="select.max_search_vertices: expected an int >= 50, got 10"):
            intrinsic_symmetry(mesh, select={"max_search_vertices": 10})
        with pytest.raises(ConfigError, match="select.max_search_vertices: expected an int >= 50, got 10"):
            IntrinsicSymmetry(select={"max_search_vertices": 10})
