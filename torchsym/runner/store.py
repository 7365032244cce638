"""The results file of a dataset run: JSON lines, one record per finished input.

Only the driver writes it, one line per record, flushed and ``fsync``-ed before the next
one, so a driver killed at any moment leaves every finished record on disk and at most a
torn last line, which reopening cuts. A record::

    {"input": "/data/chair.ply", "size": 81234, "mtime_ns": 1733212345000000000,
     "config_hash": "3f2a...", "status": "ok", "kind": "pointcloud", "files": [...],
     "config": {...}, "result": {...}, "arrays": "chair-5d41402abc4b.npz", "error": null,
     "seconds": 0.41, "notes": [], "attempts": 1, "artifacts": []}

``torchsym detect`` writes the same record (:func:`make_record`) as ``<stem>.json``, so
``torchsym evaluate`` and :func:`torchsym.load_result` read both.

``status`` is ``"ok"`` (``result`` holds the solver's ``to_dict()``), ``"error"`` (a
:class:`~torchsym.errors.TorchsymError` or another exception raised by the task: final,
never retried; ``error`` holds ``{"type", "message"}``) or ``"crashed"`` (the worker
running it died on every attempt). An input is done when its latest record has status
``ok`` or ``error`` and the same path, size, mtime and config hash: reopening the file
skips it; a crashed input, a changed file or another config runs again and its new
record is appended (the latest record of an input wins).

The result's large arrays (per-point pairs, per-vertex maps: more elements than the run's
``max_inline``) are not in the line: they are in one ``.npz`` per input in the folder
``<file stem>_arrays`` beside the file, named by ``arrays``, written and fsync-ed before
the record, and referenced in ``result`` as ``{"$array": name, "shape", "dtype"}``;
:func:`read_results` puts them back.

A lock (``fcntl.flock`` on ``<file>.lock``, released by the kernel when the driver dies,
even by SIGKILL) stops a second driver appending to the same file.
"""

from __future__ import annotations

import dataclasses
import errno
import fcntl
import hashlib
import json
import logging
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from torchsym.core.results import restore_arrays, to_jsonable
from torchsym.errors import InputFileError

__all__ = [
    "FINAL_STATUSES", "InputKey", "ResultsStore", "arrays_dir", "config_hash", "input_key", "make_record", "read_results",
]

logger = logging.getLogger(__name__)

#: statuses after which an input is not run again (with the same key)
FINAL_STATUSES = ("ok", "error")


def config_hash(config: Mapping[str, Any]) -> str:
    """SHA-256 (hex, first 16 digits) of a config's ``input`` and ``steps``, keys sorted."""
    core = {"input": config.get("input"), "steps": config.get("steps")}
    return hashlib.sha256(json.dumps(core, sort_keys=True, default=str).encode()).hexdigest()[:16]


@dataclasses.dataclass(frozen=True)
class InputKey:
    """What makes a record current: the input's resolved path, size, mtime and the config hash."""

    input: str
    size: int
    mtime_ns: int
    config_hash: str

    def as_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def input_key(path: str | Path, config_digest: str, files: Sequence[str | Path] = ()) -> InputKey:
    """The :class:`InputKey` of the input at ``path``: the file's size and mtime, or for an
    input of several ``files`` (a scene's photos) their total size and latest mtime
    (``InputFileError`` if one is gone)."""
    p = Path(path).resolve()
    size, mtime = 0, 0
    for f in files or (p,):
        try:
            st = Path(f).stat()
        except OSError as exc:
            raise InputFileError(f"inputs: cannot read {str(f)!r} ({exc.strerror or exc})") from None
        size, mtime = size + int(st.st_size), max(mtime, int(st.st_mtime_ns))
    return InputKey(str(p), size, mtime, config_digest)


def make_record(key: InputKey, outcome: Mapping[str, Any], *, attempts: int = 1, arrays: str | None = None) -> dict[str, Any]:
    """The record of one input, for ``torchsym run``'s results file and ``torchsym detect``'s
    ``<stem>.json`` alike: ``key``'s fields, then the task's ``outcome``
    (:func:`~torchsym.runner.task.run_task`): status, kind, files, config, result, the
    ``.npz`` of its large ``arrays``, error, seconds, notes, ``attempts`` and artifacts."""
    rec = key.as_dict()
    for name in ("status", "kind", "files", "config", "result"):
        rec[name] = outcome.get(name)
    rec["arrays"] = arrays
    for name in ("error", "seconds"):
        rec[name] = outcome.get(name)
    rec["notes"] = list(outcome.get("notes") or [])
    rec["attempts"] = attempts
    rec["artifacts"] = list(outcome.get("artifacts") or [])
    return rec


def _parse_lines(path: Path, keep: Callable[[dict[str, Any]], dict[str, Any]] | None = None) -> tuple[list[dict[str, Any]], int]:
    """Records of the file (each passed through ``keep`` if given, so that only what is
    kept stays in memory) and the byte length of its intact part (to cut a torn last
    line). The file is read a line at a time.

    Raises:
        InputFileError: a line other than the last is not a JSON record.
    """
    records: list[dict[str, Any]] = []
    good = 0
    size = path.stat().st_size
    with open(path, "rb") as fh:
        lineno = 0
        while line := fh.readline():
            lineno += 1
            try:
                rec = json.loads(line) if line.strip() else None
            except (json.JSONDecodeError, UnicodeDecodeError):
                rec = False
            complete = line.endswith(b"\n")
            if rec is False or (rec is not None and not isinstance(rec, dict)) or not complete:
                if not complete or fh.tell() >= size:
                    break  # torn last line (no newline, or cut inside the JSON): dropped
                raise InputFileError(
                    f"results: line {lineno} of {str(path)!r} is not a JSON record; the file is not a torchsym results file"
                )
            if rec is not None:
                records.append(rec if keep is None else keep(rec))
            good = fh.tell()
    return records, good


def _summary(record: Mapping[str, Any]) -> dict[str, Any]:
    """What the store keeps of a record: its key fields, status and attempts (not the result)."""
    return {name: record.get(name) for name in (*InputKey.__dataclass_fields__, "status", "attempts") if name in record}


def arrays_dir(path: str | Path) -> Path:
    """The folder of a results file's arrays: ``<file stem>_arrays`` beside it."""
    p = Path(path)
    return p.with_name(p.stem + "_arrays")


def _with_arrays(record: dict[str, Any], folder: Path) -> dict[str, Any]:
    name = record.get("arrays")
    if not name or not isinstance(record.get("result"), dict):
        return record
    try:
        with np.load(folder / name, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
    except (OSError, ValueError) as exc:
        logger.warning("results: arrays of %s not read from %s (%s); references kept", record.get("input"), folder / name, exc)
        return record
    return {**record, "result": restore_arrays(record["result"], arrays)}


def read_results(path: str | Path, *, latest: bool = True, arrays: bool = True) -> list[dict[str, Any]]:
    """The records of a results file (a torn last line is ignored, the file left as it is).

    Args:
        path: a JSON-lines results file written by :func:`torchsym.run`.
        latest: keep only the latest record of each input (the current one), in the
            order the inputs first appear; False returns every line.
        arrays: put the result's large arrays back from ``<file stem>_arrays/`` (as NumPy
            arrays); False leaves their ``{"$array": ...}`` references.

    Raises:
        InputFileError: the file does not exist or a line other than the last is not JSON.
    """
    p = Path(path)
    if not p.is_file():
        raise InputFileError(f"results: file {str(p)!r} does not exist")
    records, _ = _parse_lines(p)
    if latest:
        by_input: dict[str, dict[str, Any]] = {}
        for rec in records:
            by_input[str(rec.get("input"))] = rec  # dicts keep first-insertion order
        records = list(by_input.values())
    if arrays:
        folder = arrays_dir(p)
        records = [_with_arrays(rec, folder) for rec in records]
    return records


class ResultsStore:
    """The results file, opened by one driver: lock, read what is done, append records.

    Use as a context manager::

        with ResultsStore("results.jsonl") as store:
            if not store.is_done(key):
                store.append(record)

    Args:
        path: the JSON-lines file (created with its folder if missing).
        resume: True reads the existing records (done inputs are skipped, a torn last
            line is cut); False starts the file afresh.

    Raises:
        InputFileError: the file is locked by another driver, cannot be created, or is
            not a results file.
    """

    def __init__(self, path: str | Path, *, resume: bool = True) -> None:
        self.path = Path(path)
        self.resume = resume
        self._lock_fd: int | None = None
        self._fh: Any = None
        self._latest: dict[str, dict[str, Any]] = {}
        self.torn_bytes = 0

    def __enter__(self) -> ResultsStore:
        self.open()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def open(self) -> None:
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(str(self.path) + ".lock", os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise InputFileError(f"--out: cannot create {str(self.path)!r} ({exc.strerror or exc})") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                raise InputFileError(
                    f"--out: {str(self.path)!r} is locked by another torchsym run (pid {holder}); "
                    "wait for it to finish or choose another --out"
                ) from None
            raise InputFileError(f"--out: cannot lock {str(self.path)!r} ({exc.strerror or exc})") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        self._lock_fd = fd
        try:
            if self.resume and self.path.is_file():
                records, good = _parse_lines(self.path, _summary)
                size = self.path.stat().st_size
                if good < size:  # cut the torn last line
                    self.torn_bytes = size - good
                    with open(self.path, "r+b") as fh:
                        fh.truncate(good)
                        fh.flush()
                        os.fsync(fh.fileno())
                for rec in records:
                    self._latest[str(rec.get("input"))] = rec
            self._fh = open(self.path, "a" if self.resume else "w", encoding="utf-8")
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None
        if self._lock_fd is not None:
            fcntl.flock(self._lock_fd, fcntl.LOCK_UN)
            os.close(self._lock_fd)
            self._lock_fd = None

    def latest(self, input: str) -> dict[str, Any] | None:
        """The key fields, status and attempts of ``input``'s latest record (its resolved
        path), or None; the store keeps no results in memory (:func:`read_results` reads them)."""
        return self._latest.get(input)

    def is_done(self, key: InputKey) -> bool:
        """Whether ``key``'s input has a final record (``ok`` or ``error``) with this key."""
        rec = self._latest.get(key.input)
        if rec is None or rec.get("status") not in FINAL_STATUSES:
            return False
        return all(rec.get(k) == v for k, v in key.as_dict().items())

    def write_arrays(self, key: InputKey, arrays: Mapping[str, np.ndarray]) -> str:
        """Write one input's arrays to ``<file stem>_arrays/<input stem>-<key hash>.npz``
        (a temporary file, fsync-ed, then renamed); returns the file's name."""
        folder = arrays_dir(self.path)
        digest = hashlib.sha256(json.dumps(key.as_dict(), sort_keys=True).encode()).hexdigest()[:12]
        name = f"{Path(key.input).stem}-{digest}.npz"
        try:
            folder.mkdir(exist_ok=True)
            tmp = folder / (name + ".tmp")
            with open(tmp, "wb") as fh:
                np.savez(fh, **arrays)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, folder / name)
            fd = os.open(folder, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        except OSError as exc:
            raise InputFileError(f"--out: cannot write arrays to {str(folder)!r} ({exc.strerror or exc})") from None
        return name

    def append(self, record: Mapping[str, Any]) -> None:
        """Write one record as a line, flushed and fsync-ed before returning."""
        if self._fh is None:
            raise InputFileError(f"results: {str(self.path)!r} is not open")
        try:
            line = json.dumps(record, allow_nan=False, default=str)
        except ValueError:  # NaN or inf somewhere: written as null
            line = json.dumps(to_jsonable(dict(record)), allow_nan=False, default=str)
        self._fh.write(line + "\n")
        self._fh.flush()
        os.fsync(self._fh.fileno())
        self._latest[str(record.get("input"))] = _summary(record)
