"""Checks of what the runner is given: its options, its output path and every record it scores.

:func:`check_run_options` runs before anything starts (a local cluster of 0 workers
waits for ever); :func:`check_record` before a record is scored (a record read from a
file or passed in may be anything JSON holds), naming the record and its input;
:func:`scored_means` averages the figures of the records that could be scored and counts
the others, so no NaN reaches a summary.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from torchsym.errors import InputFileError, InputValueError

__all__ = ["STATUSES", "check_record", "check_run_options", "scored_means"]

STATUSES = ("ok", "error", "crashed")


def _count(value: Any, name: str, minimum: int, maximum: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputValueError(f"{name}: expected an integer >= {minimum}, got {value!r}")
    if maximum is not None and value > maximum:
        raise InputValueError(f"{name}: expected at most {maximum} (4 x this machine's {os.cpu_count()} cores), got {value!r}")
    return int(value)


def default_threads(concurrent: int = 1) -> int:
    """Torch threads per task when the user sets none: this machine's cores shared among
    the ``concurrent`` tasks that run at once (at least 1). ``torchsym detect`` runs one
    task at a time; ``torchsym run`` runs one per local worker."""
    return max(1, (os.cpu_count() or 1) // max(1, int(concurrent)))


def check_threads(threads: Any, name: str = "threads") -> int:
    """``threads`` if it is a count from 1 to 4 x this machine's cores (more would only
    oversubscribe; 1e9 threads crashed OpenMP); :class:`InputValueError` otherwise."""
    return _count(threads, name, 1, 4 * (os.cpu_count() or 1))


def check_run_options(
    *,
    out: str | Path,
    workers: Any,
    threads_per_worker: Any,
    retries: Any,
    max_in_flight: Any,
    connect_timeout: Any,
    figures: Any = None,
) -> None:
    """Raise :class:`InputValueError` for options of :func:`torchsym.run` that would hang
    or fail late (``workers=0``: a cluster with nothing to run on; ``threads_per_worker``
    of 1e9: a crash in OpenMP; both at most 4 x the machine's cores) and
    :class:`InputFileError` for an ``out`` that is a folder or lies under a file (a missing
    folder is made)."""
    most = 4 * (os.cpu_count() or 1)  # more would only oversubscribe; 1e9 threads crashed OpenMP
    _count(workers, "workers", 1, most)
    if threads_per_worker is not None:
        check_threads(threads_per_worker, "threads_per_worker")
    _count(retries, "retries", 0)
    if max_in_flight is not None:
        _count(max_in_flight, "max_in_flight", 1)
    ok = isinstance(connect_timeout, (int, float)) and not isinstance(connect_timeout, bool)
    if not ok or not math.isfinite(connect_timeout) or connect_timeout <= 0:
        raise InputValueError(f"connect_timeout: expected a finite number of seconds > 0, got {connect_timeout!r}")
    if not isinstance(out, (str, Path)) or not str(out):
        raise InputValueError(f"out: expected the path of a results file, got {out!r}")
    p = Path(out)
    if p.is_dir():
        raise InputFileError(f"out: expected the path of a results file, got the folder {str(p)!r}")
    _folder_path(p.parent, "out", "the results file")
    if figures is not None:
        if not isinstance(figures, (str, Path)) or not str(figures):
            raise InputValueError(f"figures: expected the path of a folder for the pictures, got {figures!r}")
        _folder_path(Path(figures), "figures", "the picture folder")


def _folder_path(folder: Path, name: str, what: str) -> None:
    """Raise :class:`InputFileError` when ``folder``, or a folder above it, is a file (a
    missing folder is made when the run starts; a file in the way is not)."""
    blocked = next((q for q in (folder, *folder.parents) if q.exists() and not q.is_dir()), None)
    if blocked is not None:
        raise InputFileError(f"{name}: {str(blocked)!r} in the path of {what} is a file, not a folder")


def _numbers(value: Any, where: str, shape: tuple[int | None, ...], *, finite: bool = True) -> np.ndarray:
    """``value`` as a float64 array of ``shape`` (None: any length); raise naming ``where``."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise InputValueError(f"{where}: expected numbers, got {type(value).__name__} {str(value)[:60]}") from None
    if a.ndim == 1 and len(shape) == 2 and a.size == 0:
        a = a.reshape(0, shape[1] or 0)
    if a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape)):
        want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise InputValueError(f"{where}: expected an array of shape {want}, got shape {a.shape}")
    if finite and not np.isfinite(a).all():
        raise InputValueError(f"{where}: expected finite numbers, got {str(value)[:60]}")
    return a


def _array(result: Mapping[str, Any], name: str, where: str) -> None:
    value = result.get(name)
    if value is None or isinstance(value, Mapping):  # absent, or its .npz is missing: scoring says which
        return
    try:
        a = np.asarray(value)
    except (TypeError, ValueError):
        raise InputValueError(f"{where}.{name}: expected an array, got {type(value).__name__}") from None
    if a.dtype == object or a.ndim != 2 or not (np.issubdtype(a.dtype, np.number) or a.dtype == np.bool_):
        raise InputValueError(f"{where}.{name}: expected a 2-D numeric array, got shape {a.shape} of {a.dtype}")
    if np.issubdtype(a.dtype, np.floating) and not np.isfinite(a).all():
        raise InputValueError(f"{where}.{name}: expected finite values")


def _check_result(result: Mapping[str, Any], kind: str, where: str) -> None:
    """The fields the scorer of ``kind`` reads, where present."""
    if kind == "image":
        if "axes" in result:
            axes = _numbers(result["axes"], f"{where}.axes", (None, 4))
            _numbers(result.get("scores"), f"{where}.scores", (axes.shape[0],))
        elif result.get("segment") is not None:
            seg = result["segment"]
            if not isinstance(seg, Sequence) or isinstance(seg, str):
                raise InputValueError(f"{where}.segment: expected two points, got {type(seg).__name__}")
            if result.get("score") is not None:
                _numbers(result["score"], f"{where}.score", ())
        if result.get("image_size"):
            size = _numbers(result["image_size"], f"{where}.image_size", (None,))
            if size.size < 2 or (size[:2] < 1).any() or (size[:2] != np.round(size[:2])).any():
                raise InputValueError(f"{where}.image_size: expected (height, width) >= 1, got {result['image_size']!r}")
    elif kind == "pointcloud":
        normal = _numbers(result.get("normal"), f"{where}.normal", (3,))
        if not np.linalg.norm(normal) > 0:
            raise InputValueError(f"{where}.normal: expected a non-zero vector, got {result.get('normal')!r}")
        _numbers(result.get("offset"), f"{where}.offset", ())
        if result.get("score") is not None:
            _numbers(result["score"], f"{where}.score", ())
    elif kind == "mesh":
        m = _numbers(result.get("map"), f"{where}.map", (None,))
        if (m != np.round(m)).any() or (m < 0).any():
            raise InputValueError(f"{where}.map: expected vertex indices >= 0")
    elif kind == "superpixels":
        _array(result, "labels", where)
    elif kind == "segmentation":
        _array(result, "mask", where)
        _array(result, "score_map", where)


def check_record(record: Any, where: str, kind: str | None = None) -> Mapping[str, Any]:
    """``record`` if it is a run's record that the scorer of ``kind`` can read.

    A record is a mapping with a string ``input``, a ``status`` in :data:`STATUSES` and,
    when ``"ok"``, a mapping ``result`` whose fields for ``kind`` (``"image"``,
    ``"pointcloud"``, ``"mesh"``, ``"superpixels"``, ``"segmentation"``) have their types,
    shapes and finite values. Raises :class:`InputValueError` naming ``where`` and the
    record's input otherwise.
    """
    if not isinstance(record, Mapping):
        raise InputValueError(f"{where}: expected a record (a mapping), got {type(record).__name__}")
    name = record.get("input")
    if not isinstance(name, str) or not name:
        raise InputValueError(f"{where}: expected the input's path in 'input', got {name!r}")
    where = f"{where} ({name!r})"
    status = record.get("status")
    if status not in STATUSES:
        raise InputValueError(f"{where}.status: expected one of {STATUSES}, got {status!r}")
    if status == "ok":
        result = record.get("result")
        if not isinstance(result, Mapping):
            raise InputValueError(f"{where}.result: expected a mapping for an 'ok' record, got {type(result).__name__}")
        if kind is not None:
            _check_result(result, kind, f"{where}.result")
    return record


def scored_means(rows: list[dict[str, Any]], keys: Sequence[str]) -> dict[str, float]:
    """Mean of each of ``keys`` over the rows where all of them are finite numbers, and
    ``n_unscored``: the rows where one is not (undefined, e.g. the AUC of an all-zero
    mask). Those rows' non-finite figures become None (JSON ``null``, not ``NaN``)."""
    def ok(v: Any) -> bool:
        return isinstance(v, (int, float, np.number)) and math.isfinite(float(v))

    good = [r for r in rows if all(ok(r.get(k)) for k in keys)]
    for r in rows:
        for k in keys:
            if k in r and not ok(r[k]) and not isinstance(r[k], bool):
                r[k] = None
    out = {k: float(np.mean([r[k] for r in good])) for k in keys} if good else {}
    out["n_unscored"] = float(len(rows) - len(good))
    return out
