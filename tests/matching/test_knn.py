"""Nearest neighbours: the kd-tree and the brute-force path give the same answers."""

from __future__ import annotations

import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.matching.knn import KNNIndex


def gen(seed: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
@pytest.mark.parametrize("k", [1, 5])
def test_brute_equals_tree(dtype, k):
    # points far from the origin and close together: the matrix-product form of the
    # distance loses their order in float32, the exact re-ranking must not
    pts = 100.0 + torch.rand(3000, 3, generator=gen(0), dtype=torch.float64) * 0.05
    q = 100.0 + torch.rand(700, 3, generator=gen(1), dtype=torch.float64) * 0.05
    pts, q = pts.to(dtype), q.to(dtype)
    d_tree, i_tree = KNNIndex(pts, method="tree").query(q, k=k)
    d_brute, i_brute = KNNIndex(pts, method="brute", chunk=256).query(q, k=k)
    assert i_brute.dtype == torch.int64 and d_brute.dtype == dtype
    tol = 1e-5 if dtype == torch.float32 else 1e-12
    torch.testing.assert_close(d_brute, d_tree, atol=tol, rtol=0)
    # indices agree wherever the distances are not tied within rounding
    agree = (i_brute == i_tree) | ((d_brute - d_tree).abs() <= tol)
    assert bool(agree.all())
    assert (i_brute == i_tree).double().mean() > 0.99


def test_brute_max_distance_and_few_points():
    pts = torch.tensor([[0.0, 0.0], [1.0, 0.0], [0.0, 3.0]])
    q = torch.tensor([[0.1, 0.0], [10.0, 10.0]])
    for method in ("tree", "brute"):
        d, i = KNNIndex(pts, method=method).query(q, k=2, max_distance=1.5)
        assert i[0].tolist() == [0, 1] and i[1].tolist() == [3, 3]
        assert torch.isinf(d[1]).all() and torch.isfinite(d[0]).all()


def test_auto_uses_the_tree_on_the_cpu():
    index = KNNIndex(torch.rand(10, 3, generator=gen(2)))
    assert index.method == "tree"


def test_bad_method():
    with pytest.raises(InputValueError, match="method"):
        KNNIndex(torch.rand(10, 3), method="ball")
