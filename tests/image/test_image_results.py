"""The result types and how a result is assembled (torchsym.image.results)."""

from __future__ import annotations

import json

import torch

from torchsym.image.results import ReflectionAxesBatch, ReflectionAxesResult, build_result, empty_result


class TestResult:
    def _result(self):
        pairs = torch.tensor([[40.0, 20.0, 60.0, 20.0], [45.0, 70.0, 55.0, 70.0], [1.0, 1.0, 3.0, 3.0]])
        line = torch.tensor([1.0, 0.0, -50.0], dtype=torch.float64)
        return build_result([line], [torch.tensor([0, 1])], [2.0], pairs, 100, 120, "test")

    def test_fields_and_json(self):
        res = self._result()
        assert isinstance(res, ReflectionAxesResult)
        assert res.axes.shape == (1, 4) and res.pair_axis.tolist() == [0, 0, -1]
        d = json.loads(res.to_json())
        assert d["type"] == "ReflectionAxesResult" and d["method"] == "test" and len(d["axes"]) == 1

    def test_sorted_and_extents(self):
        pairs = torch.tensor([[40.0, 20.0, 60.0, 30.0], [10.0, 30.0, 10.0, 50.0]])
        lines = [torch.tensor([1.0, 0.0, -50.0], dtype=torch.float64), torch.tensor([0.0, 1.0, -40.0], dtype=torch.float64)]
        res = build_result(lines, [torch.tensor([0]), torch.tensor([1])], [1.0, 3.0], pairs, 100, 120, "test",
                           extents=[None, (-20.0, -5.0)])
        assert res.scores.tolist() == [3.0, 1.0] and res.pair_axis.tolist() == [1, 0]
        assert res.axes[0].tolist() == [20.0, 40.0, 5.0, 40.0]  # y = 40 from t = -20 to -5 (direction (-1, 0))
        assert res.axes[1].tolist() == [50.0, 20.0, 50.0, 30.0]  # x = 50 over its pair's extent

    def test_empty_and_batch(self):
        res = empty_result(30, 40, "test", pairs=torch.zeros(2, 4), reason="none")
        assert len(res) == 0 and res.pair_axis.tolist() == [-1, -1] and res.info["reason"] == "none"
        batch = ReflectionAxesBatch((res, res))
        assert len(batch) == 2 and batch[1] is res and json.loads(batch.to_json())["type"] == "ReflectionAxesBatch"
