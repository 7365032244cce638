"""The base class of every result torchsym returns.

A result is a frozen dataclass whose fields are tensors, numbers, strings, or nested
results. ``to_dict()`` turns it into plain Python (lists, floats) for JSON; ``to(device)``
moves every tensor. Subclasses document each field with its shape and may override
:meth:`Result.write_artifacts` to write pictures a person can look at.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import json
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import torch

__all__ = ["ArraySink", "Result", "on_input_device", "restore_arrays", "to_jsonable"]

F = TypeVar("F", bound=Callable[..., Any])


@dataclasses.dataclass
class ArraySink:
    """Where :meth:`Result.to_dict` puts the arrays too large for a JSON record.

    A tensor or array of more than ``max_inline`` elements is stored in ``arrays`` under
    its dotted name in the result (``"pairs"``, ``"planes.0.inliers"``) and the dict holds
    ``{"$array": name, "shape": [...], "dtype": "int64"}`` in its place; the dataset
    runner writes ``arrays`` to one ``.npz`` per input beside its results file.

    Attributes:
        max_inline: the most elements an array may have and still be written inline.
        arrays: name -> NumPy array (CPU), in the order met.
    """

    max_inline: int = 1024
    arrays: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)

    def take(self, name: str, array: np.ndarray) -> dict[str, Any]:
        """Keep ``array`` under ``name`` (made unique); returns the reference that replaces it."""
        key = name or "array"
        if key in self.arrays:
            key = f"{key}.{len(self.arrays)}"
        self.arrays[key] = array
        return {"$array": key, "shape": list(array.shape), "dtype": str(array.dtype)}


def _join(name: str, part: Any) -> str:
    return f"{name}.{part}" if name else str(part)


def to_jsonable(value: Any, sink: ArraySink | None = None, name: str = "") -> Any:
    """Convert tensors, arrays, dataclasses and containers to JSON-friendly Python.

    With ``sink``, tensors and arrays of more than ``sink.max_inline`` elements go to the
    sink and a reference takes their place (``name`` is the value's dotted name).
    """
    if isinstance(value, Result):
        return value.to_dict() if sink is None else value.to_dict(sink, name)
    if isinstance(value, torch.Tensor):
        value = value.detach().cpu()
        if value.dtype in (torch.float16, torch.bfloat16):
            value = value.float()
        if sink is not None and value.numel() > sink.max_inline:
            return sink.take(name, value.numpy())
        if not value.is_complex() and (not value.is_floating_point() or bool(torch.isfinite(value).all())):
            return value.tolist()  # NumPy's tolist on a tensor's array is 100x slower
        return to_jsonable(value.numpy())
    if isinstance(value, np.ndarray):
        if sink is not None and value.size > sink.max_inline and value.dtype != object:
            return sink.take(name, value)
        if np.issubdtype(value.dtype, np.floating):
            return [to_jsonable(v) for v in value] if value.ndim else to_jsonable(float(value))
        return value.tolist()
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.bool_,)):
        return bool(value)
    if isinstance(value, dict):
        return {str(k): to_jsonable(v, sink, _join(name, k)) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v, sink, _join(name, i)) for i, v in enumerate(value)]
    if isinstance(value, Path):
        return str(value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_jsonable(getattr(value, f.name), sink, _join(name, f.name)) for f in dataclasses.fields(value)}
    return value


def restore_arrays(value: Any, arrays: Mapping[str, np.ndarray]) -> Any:
    """``value`` with every ``{"$array": name, ...}`` reference replaced by ``arrays[name]``."""
    if isinstance(value, dict):
        if "$array" in value and value["$array"] in arrays:
            return arrays[value["$array"]]
        return {k: restore_arrays(v, arrays) for k, v in value.items()}
    if isinstance(value, list):
        return [restore_arrays(v, arrays) for v in value]
    return value


def _move(value: Any, device: torch.device | str) -> Any:
    if isinstance(value, torch.Tensor):
        return value.to(device)
    if isinstance(value, Result):
        return value.to(device)
    if isinstance(value, dict):
        return {k: _move(v, device) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_move(v, device) for v in value)
    return value


@dataclasses.dataclass(frozen=True)
class Result:
    """Base of every solver result: a frozen dataclass with JSON and device helpers."""

    def to_dict(self, sink: ArraySink | None = None, name: str = "") -> dict[str, Any]:
        """Every field as plain Python (tensors become nested lists), plus ``type``.

        With ``sink``, arrays of more than ``sink.max_inline`` elements go there and a
        reference takes their place (:class:`ArraySink`); ``name`` prefixes their names.
        """
        out: dict[str, Any] = {"type": type(self).__name__}
        for f in dataclasses.fields(self):
            out[f.name] = to_jsonable(getattr(self, f.name), sink, _join(name, f.name))
        return out

    def to_json(self, path: str | Path | None = None, *, indent: int | None = 2) -> str:
        """The result as JSON text; also written to ``path`` when given."""
        text = json.dumps(self.to_dict(), indent=indent)
        if path is not None:
            Path(path).write_text(text)
        return text

    def to(self, device: torch.device | str) -> Result:
        """A copy with every tensor moved to ``device``."""
        changes = {f.name: _move(getattr(self, f.name), device) for f in dataclasses.fields(self)}
        return dataclasses.replace(self, **changes)

    def write_artifacts(self, data: Any, out_dir: Path, stem: str) -> list[Path]:
        """Write pictures of this result on ``data`` into ``out_dir``; returns the paths.

        The base class writes nothing; each family of results overrides it.
        """
        return []


def _device_of(data: Any) -> torch.device | None:
    if isinstance(data, torch.Tensor):
        return data.device
    vertices = getattr(data, "vertices", None)  # a Mesh
    return vertices.device if isinstance(vertices, torch.Tensor) else None


def on_input_device(fn: F) -> F:
    """Decorator: the result of ``fn(data, ...)`` comes back on the device of ``data``.

    For solvers whose combinatorial stages (kd-trees, assignment, integer programs, OpenCV)
    run on the CPU whatever the input's device: their tensor stages (kornia's SIFT and
    Harris, say) still run where the input lies, and the caller gets the result where the
    input was, as from a solver that runs on the device throughout.
    """

    first = next(iter(inspect.signature(fn).parameters))  # the input's name, e.g. image or mesh

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        out = fn(*args, **kwargs)
        data = args[0] if args else kwargs.get(first)
        device = _device_of(data)
        if device is not None and device.type != "cpu" and isinstance(out, Result):
            out = out.to(device)
        return out

    return wrapper  # type: ignore[return-value]
