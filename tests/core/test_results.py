import dataclasses
import json

import numpy as np
import pytest
import torch

from torchsym.core.results import ArraySink, Result, restore_arrays


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


class TestArraySink:
    def test_large_arrays_leave_the_dict(self):
        inner = _Toy(torch.arange(6.0), torch.tensor([True]), 0.1, {})
        r = _Toy(torch.tensor([1.0, 0.0]), torch.ones(5, dtype=torch.bool), 0.5,
                 {"big": np.arange(7), "runs": [torch.zeros(2, 3, dtype=torch.int64)], "inner": inner})
        sink = ArraySink(max_inline=4)
        d = r.to_dict(sink)
        assert d["normal"] == [1.0, 0.0] and d["score"] == 0.5
        assert d["mask"] == {"$array": "mask", "shape": [5], "dtype": "bool"}
        assert d["extra"]["big"]["$array"] == "extra.big" and d["extra"]["runs"][0]["$array"] == "extra.runs.0"
        assert d["extra"]["inner"]["normal"] == {"$array": "extra.inner.normal", "shape": [6], "dtype": "float32"}
        assert list(sink.arrays) == ["mask", "extra.big", "extra.runs.0", "extra.inner.normal"]
        json.dumps(d)  # the references are JSON
        back = restore_arrays(d, sink.arrays)
        plain = r.to_dict()
        assert back["mask"].tolist() == plain["mask"] and back["extra"]["runs"][0].tolist() == plain["extra"]["runs"][0]
        assert back["extra"]["inner"]["normal"].tolist() == plain["extra"]["inner"]["normal"]

    def test_names_made_unique(self):
        sink = ArraySink(max_inline=0)
        a, b = sink.take("x", np.zeros(1)), sink.take("x", np.ones(1))
        assert a["$array"] != b["$array"] and len(sink.arrays) == 2

    def test_small_and_object_arrays_stay_inline(self):
        r = _Toy(torch.tensor([1.0, 0.0]), torch.tensor([True]), 0.5, {"names": np.array(["a", 1, None], dtype=object)})
        sink = ArraySink(max_inline=2)
        assert r.to_dict(sink) == r.to_dict() and sink.arrays == {}


class TestOnInputDevice:
    def test_result_follows_the_input(self):
        from torchsym.core.results import on_input_device

        @on_input_device
        def solve(x, scale=1.0):
            """Doc."""
            x = x.to("cpu") if x.device.type != "meta" else torch.ones(2)  # a CPU-only stage
            return _Toy(x * scale, torch.tensor([True]), 1.0, {"a": torch.tensor([1])})

        assert solve.__doc__ == "Doc." and "scale" in str(__import__("inspect").signature(solve))
        cpu = solve(torch.ones(2))
        assert cpu.normal.device.type == "cpu"
        moved = solve(torch.ones(2, device="meta"), scale=2.0)
        assert moved.normal.device.type == "meta" and moved.extra["a"].device.type == "meta"
        assert solve(x=torch.ones(2, device="meta")).normal.device.type == "meta"  # by keyword

    @pytest.mark.parametrize(
        "fn", ["ksymmetry_axes", "boundary_clique_axes", "point_symm_image", "intrinsic_symmetry"]
    )
    def test_solvers_return_on_the_input_device(self, fn):
        import inspect

        import torchsym

        solver = getattr(torchsym, fn)
        assert getattr(solver, "__wrapped__", None) is not None  # decorated with on_input_device
        assert next(iter(inspect.signature(solver).parameters)) in ("image", "mesh")

    def test_solver_called_by_keyword(self):
        import torchsym

        img = torch.zeros(1, 32, 32)
        img[:, 8:24, 10:22] = 1.0
        assert isinstance(torchsym.ksymmetry_axes(image=img), Result)

    def test_mesh_input(self):
        from types import SimpleNamespace

        from torchsym.core.results import on_input_device
        from torchsym.mesh.synthetic import icosphere

        @on_input_device
        def solve(mesh):
            return _Toy(torch.ones(1), torch.tensor([True]), 1.0, {})

        assert solve(icosphere(1)).normal.device.type == "cpu"
        # anything with a vertices tensor counts as a mesh (a Mesh validates, which meta tensors cannot)
        assert solve(SimpleNamespace(vertices=torch.ones(3, 3, device="meta"))).normal.device.type == "meta"
