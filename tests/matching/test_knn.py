"""Nearest neighbours: the kd-tree and the brute-force path give the same answers."""

from __future__ import annotations

import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.matching.knn import KNNIndex


def gen(seed: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


def wide_cloud() -> tuple[torch.Tensor, torch.Tensor]:
    """Two 1 m patches 1 km apart in float32 (a long scan): the matrix-product form of the
    distance in float32 returns a wrong neighbour for most queries there."""
    patch = torch.rand(4000, 3, generator=gen(0), dtype=torch.float64) * torch.tensor([1.0, 1.0, 0.0])
    pts = torch.cat([patch + torch.tensor([-500.0, 0, 0]), patch + torch.tensor([500.0, 0, 0])]).float()
    return pts, pts[:500] + 0.001


@pytest.mark.parametrize("k", [1, 5])
def test_brute_equals_tree_on_a_wide_cloud(k):
    pts, q = wide_cloud()
    d_tree, i_tree = KNNIndex(pts, method="tree").query(q, k=k)
    d_brute, i_brute = KNNIndex(pts, method="brute", chunk=128).query(q, k=k)
    assert i_brute.dtype == torch.int64 and d_brute.dtype == torch.float32
    assert torch.equal(i_brute, i_tree)
    torch.testing.assert_close(d_brute, d_tree)


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_brute_equals_tree_near_ties(dtype):
    # a grid: many neighbours at equal distances, which the exact re-ranking must order
    # as the tree does up to ties
    g = torch.stack(torch.meshgrid(*[torch.arange(12.0)] * 3, indexing="ij"), -1).reshape(-1, 3).to(dtype)
    q = g[::7] + torch.tensor([0.1, 0.2, 0.3], dtype=dtype)
    d_tree, _ = KNNIndex(g, method="tree").query(q, k=7)
    d_brute, i_brute = KNNIndex(g, method="brute").query(q, k=7)
    torch.testing.assert_close(d_brute, d_tree)
    # every returned index is at its returned distance
    torch.testing.assert_close((q[:, None, :] - g[i_brute]).norm(dim=-1), d_brute)


def test_more_neighbours_than_points_and_no_queries():
    pts = torch.tensor([[0.0, 0.0], [1.0, 0.0], [0.0, 3.0]])
    for method in ("tree", "brute"):
        index = KNNIndex(pts, method=method)
        d, i = index.query(torch.tensor([[0.1, 0.0]]), k=5)
        assert i.tolist() == [[0, 1, 2, 3, 3]] and torch.isinf(d[0, 3:]).all()
        d, i = index.query(torch.zeros(0, 2), k=2)
        assert d.shape == (0, 2) and i.shape == (0, 2)


def test_dtypes_follow_the_queries():
    pts = torch.rand(50, 3, generator=gen(3), dtype=torch.float64)
    for method in ("tree", "brute"):
        d, _ = KNNIndex(pts, method=method).query(pts[:5].float())
        assert d.dtype == torch.float32
        d, _ = KNNIndex(pts.float(), method=method).query(pts[:5])
        assert d.dtype == torch.float64


def test_brute_max_distance_as_the_tree():
    pts = torch.tensor([[0.0, 0.0], [1.0, 0.0], [0.0, 3.0]])
    q = torch.tensor([[0.0, 0.0], [10.0, 10.0]])
    out = [KNNIndex(pts, method=m).query(q, k=2, max_distance=1.0) for m in ("tree", "brute")]
    for d, i in out:  # the neighbour at exactly max_distance is left out by both
        assert i.tolist() == [[0, 3], [3, 3]] and torch.isinf(d[1]).all() and torch.isinf(d[0, 1])


def test_auto_uses_the_tree_on_the_cpu():
    index = KNNIndex(torch.rand(10, 3, generator=gen(2)))
    assert index.method == "tree"


def test_bad_method():
    with pytest.raises(InputValueError, match="method"):
        KNNIndex(torch.rand(10, 3), method="ball")
