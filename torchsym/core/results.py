"""The base class of every result torchsym returns.

A result is a frozen dataclass whose fields are tensors, numbers, strings, or nested
results. ``to_dict()`` turns it into plain Python (lists, floats) for JSON and :func:`load_result`
turns that back into the typed result; ``to(device)`` moves every tensor; ``summary()`` is
one line for a person. A solver's result has a ``score`` in [0, 1] (a field, or a property
written to JSON beside the fields). Pictures are :func:`torchsym.viz.write_artifacts`'s.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import json
import math
import typing
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import torch

__all__ = ["ArraySink", "Result", "from_jsonable", "load_result", "on_input_device", "restore_arrays", "to_jsonable"]

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
        if "score" not in out and isinstance(getattr(type(self), "score", None), property):
            out["score"] = to_jsonable(self.score)  # a derived score: written, recomputed on loading
        return out

    def summary(self) -> str:
        """One line for a person: the type and its headline fields (a normal, the score, how
        many pairs...); result types with a decision to state override it."""
        parts = []
        for key in _SUMMARY_FIELDS:
            if hasattr(self, key):
                parts.append(f"{key}={_brief(getattr(self, key))}")
        return f"{type(self).__name__}: " + ", ".join(parts)

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



#: the fields :meth:`Result.summary` names when a result has them, in this order
_SUMMARY_FIELDS = ("normal", "offset", "found", "score", "n_planes", "hypothesis", "n_superpixels", "converged", "iterations")


def _brief(v: Any) -> Any:
    """A field's value in a few characters: numbers rounded, long tensors as their shape."""
    if isinstance(v, torch.Tensor):
        v = v.detach().cpu()
        if v.dim() == 0:
            return round(float(v), 4) if v.is_floating_point() else v.item()
        if v.dim() == 1 and v.numel() <= 4 and v.is_floating_point():
            return [round(float(x), 4) for x in v]
        return f"({' x '.join(map(str, v.shape))})"
    return round(v, 4) if isinstance(v, float) else v


def _result_types() -> dict[str, type[Result]]:
    """Every :class:`Result` subclass by name (every torchsym module imported first)."""
    import torchsym  # noqa: F401 -- registers every result type

    found: dict[str, type[Result]] = {}
    todo = [Result]
    while todo:
        cls = todo.pop()
        for sub in cls.__subclasses__():
            found.setdefault(sub.__name__, sub)
            todo.append(sub)
    return found


def _tensor(value: Any) -> torch.Tensor:
    """A tensor of JSON lists: integers int64, booleans bool, numbers float32 (``null``, a
    non-finite float written by :func:`to_jsonable`, back to NaN)."""
    arr = np.asarray(value)
    if arr.dtype == object:
        arr = np.asarray(value, dtype=np.float64)  # None -> nan
    if arr.dtype.kind == "f" or arr.size == 0:
        return torch.from_numpy(arr.astype(np.float32))
    return torch.from_numpy(arr.astype(np.bool_ if arr.dtype.kind == "b" else np.int64))


def from_jsonable(data: Mapping[str, Any], arrays: Mapping[str, np.ndarray] | None = None) -> Result:
    """The typed result of ``data``, a :meth:`Result.to_dict` (its ``type`` names the class).

    Tensor fields come back as tensors (floats as float32); nested results as results;
    ``{"$array": ...}`` references from ``arrays`` (the run's ``.npz``). Derived values
    written beside the fields (a property's ``score``) are recomputed, not read.

    Raises:
        InputValueError: no ``type``, an unknown type, a missing field or an array
            reference without its array.
    """
    from torchsym.errors import InputValueError

    if not isinstance(data, Mapping) or "type" not in data:
        raise InputValueError("result: expected a mapping with 'type', as Result.to_dict writes it")
    types = _result_types()
    cls = types.get(str(data["type"]))
    if cls is None:
        raise InputValueError(f"result: unknown type {data['type']!r}")
    data = restore_arrays(dict(data), arrays or {})
    hints = typing.get_type_hints(cls)
    kwargs = {}
    for f in dataclasses.fields(cls):
        if f.name not in data:
            if f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING:
                continue
            raise InputValueError(f"result: {cls.__name__} needs field {f.name!r}")
        kwargs[f.name] = _field_value(data[f.name], hints.get(f.name, Any), f.name)
    return cls(**kwargs)


def _field_value(value: Any, hint: Any, name: str) -> Any:
    from torchsym.errors import InputValueError

    if isinstance(value, dict) and "$array" in value:
        raise InputValueError(f"result: field {name!r} is stored in an array file that was not given")
    args = typing.get_args(hint)
    options = args if args else (hint,)
    if any(isinstance(o, type) and issubclass(o, Result) for o in options) and isinstance(value, Mapping):
        return from_jsonable(value)
    if torch.Tensor in options and value is not None:
        return torch.from_numpy(value) if isinstance(value, np.ndarray) else _tensor(value)
    if float in options and value is None:
        return math.nan
    if typing.get_origin(hint) is tuple and isinstance(value, list):
        return tuple(value)
    return value


def load_result(path: str | Path) -> Result:
    """The typed result saved in a JSON file: a ``torchsym detect`` record (``result``
    inside) or :meth:`Result.to_json`'s text; a run record's arrays from the ``.npz`` the
    record names (``arrays``), when present.

    Raises:
        InputFileError: the file is missing or not JSON.
        InputValueError: it holds no result (see :func:`from_jsonable`).
    """
    from torchsym.errors import InputFileError

    p = Path(path)
    try:
        data = json.loads(p.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputFileError(f"path: cannot read {str(p)!r} as JSON ({exc})") from None
    arrays: dict[str, np.ndarray] = {}
    if isinstance(data, dict) and isinstance(data.get("result"), dict):
        npz = data.get("arrays")
        if isinstance(npz, str) and (p.parent / npz).is_file():
            with np.load(p.parent / npz, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
        data = data["result"]
    return from_jsonable(data, arrays)


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
