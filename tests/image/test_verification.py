"""The shared verification tail: evidence, suppression, result (torchsym.image.verification)."""

from __future__ import annotations

import numpy as np
import torch

from torchsym.image.verification import Axis, GradientField, finish_axes, verify_axis


def _square() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A bright square symmetric about x = 49.5, its axis and mirror pairs across it."""
    img = np.zeros((100, 100), np.float32)
    img[30:70, 30:70] = 1.0
    line = np.array([1.0, 0.0, -49.5])
    pairs = np.array([[31.0, y, 68.0, y] for y in np.linspace(35, 65, 7)])
    return img, line, pairs


class TestVerifyAxis:
    def test_true_axis_scores_and_weight(self):
        img, line, pairs = _square()
        field = GradientField.of(img)
        axis = verify_axis(field, line, pairs, np.arange(7))
        assert axis.score > 0 and axis.members.tolist() == list(range(7)) and axis.extent[0] < axis.extent[1]
        half = verify_axis(field, line, pairs, np.arange(7), weight=0.5)
        assert half.score == 0.5 * axis.score

    def test_wrong_axis_scores_less(self):
        img, line, pairs = _square()
        field = GradientField.of(img)
        shifted = np.array([1.0, 0.0, -40.0])
        assert verify_axis(field, shifted, pairs, np.arange(7)).score < verify_axis(field, line, pairs, np.arange(7)).score


class TestFinishAxes:
    def test_sorted_suppressed_and_counted(self):
        _, line, pairs = _square()
        near = line + np.array([0.0, 0.0, -1.0])  # the same object, 1 px off
        axes = [Axis(line, np.arange(4), 1.0, (30.0, 70.0)), Axis(near, np.arange(4, 7), 2.0, (30.0, 70.0))]
        info: dict = {}
        res = finish_axes(axes, pairs, 100, 100, "test", duplicate_distance=5.0, info=info)
        assert len(res) == 1 and res.scores.tolist() == [2.0] and info["duplicates_dropped"] == 1
        assert res.pair_axis.tolist() == [-1] * 4 + [0] * 3
        kept = finish_axes(axes, torch.from_numpy(pairs), 100, 100, "test", info={})
        assert len(kept) == 2 and "duplicates_dropped" not in kept.info
