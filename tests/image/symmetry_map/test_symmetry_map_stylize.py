from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.core.registry import SOLVERS
from torchsym.errors import InputValueError
from torchsym.image.symmetry_map import StylizedResult, StylizeSolver, stylize
from torchsym.image.symmetry_map.stylize import adjacency, merge_regions


class TestMergeRegions:
    def test_toy_example(self):
        """Fig. 3.10: six regions in two rows; the lowest (s5) merges into its lowest neighbour (s4)."""
        labels = np.array([[0, 1, 5], [2, 3, 4]])
        nbrs = adjacency(labels)
        assert nbrs[3] == {1, 2, 4}
        scores = [0.9, 0.8, 0.7, 0.3, 0.1, 0.95]
        parent = merge_regions(list(scores), nbrs, min_score=0.15)
        assert parent[4] == 3  # s5 into s4, new score 0.2 > 0.15: stop
        assert [int(p) for p in parent] == [0, 1, 2, 3, 3, 5]

    def test_all_merge(self):
        labels = np.array([[0, 1], [2, 3]])
        parent = merge_regions([0.1, 0.2, 0.3, 0.2], adjacency(labels), min_score=0.9)
        assert len(set(parent.tolist())) == 1


class TestStylize:
    def test_smoke(self, irs_result):
        out = stylize(irs_result, region_px=12, min_score=0.5)
        assert isinstance(out, StylizedResult)
        assert out.image.shape == irs_result.image.shape
        assert out.region_scores.numel() == int(out.labels.max()) + 1 <= out.n_superpixels
        # each region one colour
        lab = out.labels.reshape(-1)
        img = out.image.reshape(3, -1)
        for r in range(min(5, out.region_scores.numel())):
            cols = img[:, lab == r]
            assert torch.allclose(cols, cols[:, :1].expand_as(cols))

    def test_threshold(self, irs_result):
        few = stylize(irs_result, region_px=12, min_score=0.9)
        many = stylize(irs_result, region_px=12, min_score=0.0)
        assert few.region_scores.numel() < many.region_scores.numel() == many.n_superpixels

    def test_solver(self, irs_result):
        assert SOLVERS.get("stylize").kind == "any"
        assert isinstance(StylizeSolver(region_px=12)(irs_result), StylizedResult)

    def test_empty_map(self):
        from torchsym.image.symmetry_map import symmetry_map

        r = symmetry_map(torch.full((3, 48, 48), 0.3))
        out = stylize(r, region_px=8)
        assert out.notes and out.region_scores.numel() == 1

    def test_exception(self):
        with pytest.raises(InputValueError, match="SymmetryMapResult"):
            stylize(torch.rand(3, 10, 10))
