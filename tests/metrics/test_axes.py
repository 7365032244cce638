"""Axis evaluation protocol (thesis Sec. 2.4) on hand-made cases."""

from __future__ import annotations

import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.metrics.axes import (
    axis_angle,
    axis_center_distance,
    evaluate_axes,
    match_axes,
)

GT = torch.tensor([[50.0, 0.0, 50.0, 100.0]])  # vertical axis, centre (50, 50), length 100


class TestAxisGeometry:
    def test_angle_undirected(self):
        a = torch.tensor([0.0, 0.0, 10.0, 0.0])
        b = torch.tensor([10.0, 10.0, 0.0, 0.0])
        assert float(axis_angle(a, b)) == pytest.approx(45.0)
        assert float(axis_angle(a, torch.tensor([10.0, 0.0, 0.0, 0.0]))) == pytest.approx(0.0, abs=1e-9)

    def test_centre_distance(self):
        assert float(axis_center_distance(torch.tensor([0.0, 0, 2, 0]), torch.tensor([0.0, 3, 2, 3]))) == 3.0


class TestMatchAxes:
    def test_thesis_thresholds(self):
        size = (100, 200)  # d_t = 0.025 * 100 = 2.5 px, theta_t = 3 deg
        assert match_axes([[51.0, 0, 51, 100]], GT, image_size=size).tolist() == [True]
        assert match_axes([[53.0, 0, 53, 100]], GT, image_size=size).tolist() == [False]  # 3 px off
        tilted = [[50 - 2.5, 0, 50 + 2.5, 100]]  # 2.9 deg
        assert match_axes(tilted, GT, image_size=size).tolist() == [True]
        tilted = [[50 - 3, 0, 50 + 3, 100]]  # 3.4 deg
        assert match_axes(tilted, GT, image_size=size).tolist() == [False]

    def test_challenge_criterion(self):
        size = (100, 200)
        assert match_axes([[60.0, 0, 60, 100]], GT, image_size=size, criterion="challenge").tolist() == [True]
        assert match_axes([[71.0, 0, 71, 100]], GT, image_size=size, criterion="challenge").tolist() == [False]
        tilted = [[50 - 8, 0, 50 + 8, 100]]  # 9.1 deg
        assert match_axes(tilted, GT, image_size=size, criterion="challenge").tolist() == [True]

    def test_one_true_positive_per_gt(self):
        pred = [[50.0, 0, 50, 100], [50.5, 0, 50.5, 100]]
        assert match_axes(pred, GT, image_size=(100, 100), scores=[0.2, 0.9]).tolist() == [False, True]

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"pred: expected \(K, 4\)"):
            match_axes([[1.0, 2.0]], GT, image_size=(10, 10))
        with pytest.raises(InputValueError, match="criterion: expected one of"):
            match_axes(GT, GT, image_size=(10, 10), criterion="loose")


class TestEvaluateAxes:
    def test_pr_curve(self):
        dets = [
            (torch.tensor([[50.0, 0, 50, 100], [0.0, 50, 100, 50]]), torch.tensor([0.9, 0.5])),
            (torch.tensor([[10.0, 10, 20, 90]]), torch.tensor([0.7])),
        ]
        gts = [GT, torch.tensor([[80.0, 0, 80, 100]])]
        ev = evaluate_axes(dets, gts, [(100, 100), (100, 100)])
        assert ev.n_ground_truth == 2 and ev.n_detections == 3
        assert ev.precision == pytest.approx(1 / 3) and ev.recall == pytest.approx(0.5)
        # best threshold keeps only the 0.9 detection: P = 1, R = 0.5, F = 2/3
        assert ev.max_f == pytest.approx(2 / 3)

    def test_no_detections(self):
        ev = evaluate_axes([(torch.zeros(0, 4), torch.zeros(0))], [GT], [(100, 100)])
        assert ev.max_f == 0.0 and ev.recall == 0.0

    def test_exception(self):
        with pytest.raises(InputShapeError, match="detections: expected one entry per image"):
            evaluate_axes([], [GT], [(100, 100)])
