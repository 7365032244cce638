"""Dense mirror-gradient evidence of an axis: its score and extent (torchsym.image.axes.axis_evidence)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.image import boundary_clique_axes
from torchsym.image.axes import axis_evidence, mirror_gradients


def _kite(noise: float = 0.02) -> np.ndarray:
    """120 x 160 grey image: a kite symmetric about x = 60 from y = 20 to y = 140, seeded noise."""
    img = np.full((160, 120), 0.2, np.float32)
    poly = np.array([[60, 20], [95, 70], [60, 140], [25, 70]], np.int32)
    cv2.fillPoly(img, [poly], 0.8)
    return img + noise * np.random.default_rng(0).standard_normal(img.shape).astype(np.float32)


def _kite_pairs(y0: float, y1: float) -> np.ndarray:
    """Mirror pairs on the kite's lower edges between rows ``y0`` and ``y1``: ``x = 60 +- 35 (140 - y) / 70``."""
    y = np.linspace(y0, y1, 9)
    half = 35.0 * (140.0 - y) / 70.0
    return np.stack([60 - half, y, 60 + half, y], 1)


AXIS = np.array([1.0, 0.0, -60.0])  # x = 60; its parameter t is y


class TestAxisEvidence:
    def test_true_axis_is_mirrored(self):
        gx, gy = mirror_gradients(_kite())
        ev = axis_evidence(gx, gy, AXIS, _kite_pairs(80, 110))
        assert ev.symmetry > 0.8
        th = math.radians(10)
        tilted = np.array([math.cos(th), math.sin(th), 0.0])
        tilted[2] = -(tilted[:2] @ np.array([60.0, 95.0]))  # through the same centre
        assert axis_evidence(gx, gy, tilted, _kite_pairs(80, 110)).symmetry < ev.symmetry - 0.4
        assert 0 < ev.area < 1

    def test_noise_has_no_evidence(self):
        gray = np.random.default_rng(1).random((160, 120)).astype(np.float32)
        gx, gy = mirror_gradients(gray)
        assert abs(axis_evidence(gx, gy, AXIS, _kite_pairs(80, 110)).symmetry) < 0.15

    def test_extent_grows_to_the_object(self):
        gx, gy = mirror_gradients(_kite())
        pairs = _kite_pairs(80, 110)
        lo, hi = axis_evidence(gx, gy, AXIS, pairs).extent
        assert lo == pytest.approx(20, abs=8) and hi == pytest.approx(140, abs=8)
        assert axis_evidence(gx, gy, AXIS, pairs, grow_threshold=None).extent == pytest.approx((80, 110))

    def test_extent_stops_at_clutter(self):
        gray = _kite()
        gray[:40] = np.random.default_rng(2).random((40, 120))  # unsymmetric texture above the kite's tip
        gx, gy = mirror_gradients(gray)
        lo, hi = axis_evidence(gx, gy, AXIS, _kite_pairs(80, 110)).extent
        assert lo > 32 and hi == pytest.approx(140, abs=8)


class TestScores:
    def test_support_scores_count_pairs(self, single_objects):
        img, _ = single_objects[0]
        res = boundary_clique_axes(img, score="support")
        counts = torch.tensor([float((res.pair_axis == k).sum()) for k in range(len(res))])
        assert torch.equal(res.scores, counts)

    def test_gradient_extent_covers_support(self, single_objects):
        img, _ = single_objects[1]
        grown = boundary_clique_axes(img)
        plain = boundary_clique_axes(img, grow_threshold=None)
        assert torch.equal(grown.lines, plain.lines)
        for a, b in zip(grown.axes, plain.axes):
            assert (a[2:] - a[:2]).norm() >= (b[2:] - b[:2]).norm() - 1e-3

    @pytest.mark.parametrize(("kw", "name"), [({"score": "votes"}, "score"), ({"grow_threshold": 2.0}, "grow_threshold")])
    def test_bad_settings(self, kw, name):
        with pytest.raises(InputValueError, match=name):
            boundary_clique_axes(torch.rand(3, 32, 32), **kw)
