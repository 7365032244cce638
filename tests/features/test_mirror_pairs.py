"""Mutual k1-NN mirror pairs (thesis Def. 2.2.1) and the elbow rule."""

from __future__ import annotations

import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.features import (
    choose_k1,
    elbow_index,
    mirror_descriptors,
    mirror_distance_matrix,
    mirror_sift_knn,
    mutual_knn_pairs,
    nearest_mirrors,
)


class TestNearestMirrors:
    def test_value(self):
        inf = float("inf")
        d = torch.tensor([[inf, 0.3, 0.1], [0.3, inf, inf], [0.1, inf, inf]])
        i, j, dist = nearest_mirrors(d, 2)
        assert i.tolist() == [0, 0, 1, 2] and j.tolist() == [2, 1, 0, 0]
        assert torch.equal(dist, torch.tensor([0.1, 0.3, 0.3, 0.1]))

    def test_k_capped(self):
        i, _, _ = nearest_mirrors(torch.tensor([[float("inf"), 1.0], [1.0, float("inf")]]), 5)
        assert i.tolist() == [0, 1]


class TestMirrorSiftKnn:
    def test_smoke(self):
        from torchsym.image.synthetic import mirrored_objects_image

        image, _ = mirrored_objects_image(1, height=160, width=200, generator=torch.Generator().manual_seed(0))
        feats, i, j, dist = mirror_sift_knn(image, num_features=200, k=2)
        assert len(feats) >= 2 and i.shape == j.shape == dist.shape and i.numel() <= 2 * len(feats)
        assert bool((i != j).all()) and bool(torch.isfinite(dist).all())

    def test_no_keypoints(self):
        feats, i, j, dist = mirror_sift_knn(torch.full((3, 64, 64), 0.5))
        assert i.numel() == j.numel() == dist.numel() == 0


class TestMutualKnnPairs:
    def test_value(self):
        d = torch.tensor(
            [[float("inf"), 1.0, 5.0, 6.0], [1.0, float("inf"), 2.0, 7.0], [5.0, 2.0, float("inf"), 3.0], [6.0, 7.0, 3.0, float("inf")]]
        )
        assert mutual_knn_pairs(d, 1).tolist() == [[0, 1]]  # 2 and 3 are not best buddies: 2 prefers 1
        assert mutual_knn_pairs(d, 2).tolist() == [[0, 1], [1, 2], [2, 3]]

    def test_never_self(self):
        d = torch.zeros(5, 5)
        d.fill_diagonal_(float("inf"))
        pairs = mutual_knn_pairs(d, 4)
        assert bool((pairs[:, 0] != pairs[:, 1]).all())

    def test_exception(self):
        with pytest.raises(InputValueError, match="k1: expected an integer >= 1"):
            mutual_knn_pairs(torch.zeros(3, 3), 0)


class TestMirrorDistanceMatrix:
    def test_planted_mirror(self):
        g = torch.Generator().manual_seed(0)
        d = torch.rand(6, 128, generator=g)
        d[3] = mirror_descriptors(d[0])  # keypoint 3 is the mirror of keypoint 0
        pts = torch.rand(6, 2, generator=g) * 100
        dist = mirror_distance_matrix(d, pts)
        assert torch.allclose(dist, dist.T)
        assert float(dist[0, 3]) < 1e-5
        assert [0, 3] in mutual_knn_pairs(dist, 1).tolist()

    def test_exception(self):
        with pytest.raises(InputShapeError, match="descriptors: expected"):
            mirror_distance_matrix(torch.rand(4, 128), torch.rand(5, 2))


class TestElbow:
    def test_value(self):
        assert elbow_index(torch.tensor([10.0, 3.0, 2.5, 2.2, 2.0])) == 1
        assert elbow_index(torch.tensor([5.0, 5.0, 5.0])) == 0

    def test_choose_k1_in_range(self):
        g = torch.Generator().manual_seed(1)
        d = torch.rand(30, 30, generator=g)
        d = d + d.T
        d.fill_diagonal_(float("inf"))
        assert 1 <= choose_k1(d, k_max=6) <= 6
