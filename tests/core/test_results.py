import dataclasses
import json

import torch

from torchsym.core.results import Result


@dataclasses.dataclass(frozen=True)
class _Toy(Result):
    normal: torch.Tensor
    mask: torch.Tensor
    score: float
    extra: dict


class TestResult:
    def test_to_dict_json(self):
        r = _Toy(torch.tensor([1.0, 0.0]), torch.tensor([True, False]), 0.5, {"t": torch.tensor(2.0)})
        d = json.loads(r.to_json())
        assert d == {"type": "_Toy", "normal": [1.0, 0.0], "mask": [True, False], "score": 0.5, "extra": {"t": 2.0}}

    def test_nan_becomes_null(self):
        r = _Toy(torch.tensor([float("nan")]), torch.tensor([True]), float("inf"), {})
        d = r.to_dict()
        assert d["normal"] == [None] and d["score"] is None

    def test_to_device(self):
        r = _Toy(torch.tensor([1.0]), torch.tensor([True]), 1.0, {"a": torch.tensor([1])})
        moved = r.to("cpu")
        assert moved.normal.device.type == "cpu" and moved is not r and moved.extra["a"].device.type == "cpu"
