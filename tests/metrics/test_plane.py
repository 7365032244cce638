import math

import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.metrics import (
    evaluate_planes,
    plane_box_width,
    plane_center_in_box,
    plane_match,
    plane_threshold_curve,
    precision_recall,
    precision_recall_curve,
)

LO, HI = torch.zeros(3), torch.tensor([2.0, 2.0, 2.0])
X = torch.tensor([1.0, 0.0, 0.0])


class TestPlaneMatch:
    def test_identical(self):
        m = plane_match(X, torch.tensor(-1.0), X, torch.tensor(-1.0), LO, HI)
        assert m.correct and m.angle == 0.0 and m.distance == 0.0

    def test_sign_does_not_matter(self):
        assert plane_match(-X, torch.tensor(1.0), X, torch.tensor(-1.0), LO, HI).correct

    def test_angle_threshold(self):
        n = torch.tensor([math.cos(math.radians(6)), math.sin(math.radians(6)), 0.0])
        m = plane_match(n, -(n * torch.ones(3)).sum(), X, torch.tensor(-1.0), LO, HI)
        assert math.isclose(m.angle, 6.0, rel_tol=1e-4) and not m.correct
        assert plane_match(n, -(n * torch.ones(3)).sum(), X, torch.tensor(-1.0), LO, HI, angle_threshold=7).correct

    def test_distance_relative_to_box(self):
        # shifted by 0.2 along x in a box of diagonal 2 sqrt(3): relative distance 0.0577
        m = plane_match(X, torch.tensor(-1.2), X, torch.tensor(-1.0), LO, HI)
        assert math.isclose(m.distance, 0.2 / (2 * math.sqrt(3)), rel_tol=1e-6) and not m.correct
        assert plane_match(X, torch.tensor(-1.2), X, torch.tensor(-1.0), LO, HI, distance_threshold=0.06).correct

    def test_center_in_box(self):
        c = plane_center_in_box(X, torch.tensor(-1.5), LO, HI)
        assert torch.allclose(c, torch.tensor([1.5, 1.0, 1.0], dtype=torch.float64))

    def test_box_width(self):
        # x = 1 cuts the 2-cube in a 2 x 2 square: the largest triangle has legs 2, 2
        assert math.isclose(plane_box_width(X, torch.tensor(-1.0), LO, HI), 2.0)
        # a corner cut through (0.5, 0, 0), (0, 0.5, 0), (0, 0, 0.5): equilateral, side 0.5 sqrt 2
        n = torch.ones(3) / math.sqrt(3)
        assert math.isclose(plane_box_width(n, torch.tensor(-0.5 / math.sqrt(3)), LO, HI), 0.5 * math.sqrt(2), rel_tol=1e-6)
        assert plane_box_width(X, torch.tensor(-5.0), LO, HI) == 0.0  # misses the box
        with pytest.raises(InputShapeError, match=r"normal: expected a \(3,\) tensor"):
            plane_box_width(torch.ones(2), torch.tensor(0.0), LO, HI)
        with pytest.raises(InputValueError, match="normal: expected a non-zero vector"):
            plane_box_width(torch.zeros(3), torch.tensor(0.0), LO, HI)

    def test_distance_in_width(self):
        m = plane_match(X, torch.tensor(-1.2), X, torch.tensor(-1.0), LO, HI)
        assert math.isclose(m.width, 2.0) and math.isclose(m.distance_in_width, 0.1, rel_tol=1e-6)

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"normal: expected a \(3,\) tensor"):
            plane_match(torch.zeros(2), torch.tensor(0.0), X, torch.tensor(0.0), LO, HI)


class TestPR:
    def test_counts(self):
        assert precision_recall(3, 1, 1) == (0.75, 0.75, 0.75)
        assert precision_recall(0, 0, 2) == (1.0, 0.0, 0.0)
        with pytest.raises(InputValueError, match="fp: expected a count >= 0"):
            precision_recall(1, -1, 0)

    def test_curve(self):
        curve = precision_recall_curve([0.9, 0.8, 0.7, 0.1], [True, False, True, False], 3)
        assert torch.allclose(curve.precision, torch.tensor([1.0, 0.5, 2 / 3, 0.5], dtype=torch.float64))
        assert torch.allclose(curve.recall, torch.tensor([1 / 3, 1 / 3, 2 / 3, 2 / 3], dtype=torch.float64))
        assert math.isclose(curve.max_f, 2 / 3) and curve.best_threshold == 0.7

    def test_ties_enter_together(self):
        curve = precision_recall_curve([0.5, 0.5], [True, False], 1)
        assert curve.precision.tolist() == [0.5]

    def test_exception(self):
        with pytest.raises(InputValueError, match="exceed n_ground_truth"):
            precision_recall_curve([0.5, 0.4], [True, True], 1)


class TestEvaluatePlanes:
    def test_mixed(self):
        gt = [(X, torch.tensor(-1.0))] * 3
        boxes = [(LO, HI)] * 3
        dets = [(X, torch.tensor(-1.0), 0.9), (torch.tensor([0.0, 1.0, 0.0]), torch.tensor(-1.0), 0.8), None]
        s = evaluate_planes(dets, gt, boxes)
        assert (s.precision, s.recall) == (0.5, 1 / 3)
        assert s.correct.tolist() == [True, False, False]
        assert math.isclose(s.curve.max_f, 0.5)


class TestThresholdCurve:
    def test_loosening_thresholds(self):
        tilt = torch.tensor([math.cos(math.radians(10)), math.sin(math.radians(10)), 0.0])
        ms = [
            plane_match(X, torch.tensor(-1.0), X, torch.tensor(-1.0), LO, HI),  # exact
            plane_match(tilt, -(tilt * torch.ones(3)).sum(), X, torch.tensor(-1.0), LO, HI),  # 10 deg, through the centre
            plane_match(torch.tensor([0.0, 1.0, 0.0]), torch.tensor(-1.0), X, torch.tensor(-1.0), LO, HI),  # 90 deg
        ]
        c = plane_threshold_curve(ms + [None], 4)
        assert c.f[0] == 0.0  # nothing is below a zero threshold
        # from 1 degree on the exact plane counts; from 11 degrees the tilted one too; the 90-degree one never
        p1 = 2 * (1 / 3) * (1 / 4) / (1 / 3 + 1 / 4)
        p2 = 2 * (2 / 3) * (2 / 4) / (2 / 3 + 2 / 4)
        assert math.isclose(float(c.f[1]), p1) and math.isclose(float(c.f[10]), p1) and math.isclose(float(c.f[11]), p2)
        assert math.isclose(c.max_f, p2) and c.best_angle == 11.0 and math.isclose(c.best_distance, 2 * 11 / 45)

    def test_in_evaluate_planes(self):
        s = evaluate_planes([(X, torch.tensor(-1.0), 1.0)], [(X, torch.tensor(-1.0))], [(LO, HI)])
        assert s.threshold_curve.max_f == 1.0 and "threshold_curve" in s.to_dict()

    def test_exception(self):
        with pytest.raises(InputValueError, match="steps: expected an integer >= 2"):
            plane_threshold_curve([], 0, steps=1)
        with pytest.raises(InputValueError, match="max_angle"):
            plane_threshold_curve([], 0, max_angle=-1.0)
        m = plane_match(X, torch.tensor(-1.0), X, torch.tensor(-1.0), LO, HI)
        with pytest.raises(InputValueError, match="exceed n_ground_truth"):
            plane_threshold_curve([m, m], 1)
