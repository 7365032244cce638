"""One input of a dataset run, as a worker runs it: read, build, solve, draw.

:func:`run_task` is the function the engines call (in the driver for the serial engine,
on a Dask worker otherwise). It never raises for a bad input: a
:class:`~torchsym.errors.TorchsymError` or any other exception becomes an ``"error"``
outcome, final and recorded. Only the death of the process (a crash) escapes it, and the
engine tells that apart.
"""

from __future__ import annotations

import dataclasses
import importlib
import time
import traceback
from pathlib import Path
from typing import Any

from torchsym.core.results import ArraySink

__all__ = ["TaskSpec", "run_task"]


@dataclasses.dataclass(frozen=True)
class TaskSpec:
    """Everything a worker needs for one input (plain Python, cheap to send).

    Attributes:
        index: the input's position in the run.
        input: the input as the run names it: the file, or the folder of a scene's photos.
        config: the pipeline config as :meth:`PipelineConfig.to_dict` gives it, with the
            run's overrides applied; None chooses the default pipeline of each input's
            kind (``torchsym detect`` without ``--config``).
        threads: torch and OpenCV threads for the solve.
        figures_dir: folder for the result's pictures, or None for none.
        stem: file-name stem of the pictures.
        imports: modules imported before the config is read (they register solvers).
        max_inline: arrays of the result with more elements than this travel and are kept
            apart from the record (:class:`~torchsym.core.results.ArraySink`); None keeps
            every array in the record.
        files: the files read (:attr:`torchsym.io.inputs.Source.files`); empty: ``input``.
        kind: the input kind forced (``--kind``), or None.
        overrides: settings applied to a default pipeline (``config`` None).
        notes: what the input expansion skipped for this input.
    """

    index: int
    input: str
    config: dict[str, Any] | None
    threads: int = 1
    figures_dir: str | None = None
    stem: str = ""
    imports: tuple[str, ...] = ()
    max_inline: int | None = 1024
    files: tuple[str, ...] = ()
    kind: str | None = None
    overrides: dict[str, Any] = dataclasses.field(default_factory=dict)
    notes: tuple[str, ...] = ()


def _error(exc: BaseException) -> dict[str, Any]:
    tb = traceback.extract_tb(exc.__traceback__)
    where = f"{Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
    return {"type": type(exc).__name__, "message": str(exc), "where": where}


def run_task(spec: TaskSpec) -> dict[str, Any]:
    """Run one input; returns ``{"status", "kind", "result", "arrays", "error", "seconds",
    "artifacts", "notes", "config", "stages"}``: the one way torchsym runs an input from
    files, for ``torchsym detect`` (in its process) and ``torchsym run`` (on any engine).

    ``status`` is ``"ok"`` (``result`` is the solver result's ``to_dict()``, its arrays
    of more than ``spec.max_inline`` elements in ``arrays`` as NumPy arrays and a
    reference in their place) or ``"error"`` (``error`` is ``{"type", "message",
    "where"}``). ``seconds`` is the wall time of reading, building and solving (pictures
    excluded). ``notes`` say what :func:`torchsym.api.prepare` decided (files skipped, a
    mesh sampled on its surface, the pipeline chosen for it); ``config`` is the pipeline
    run, as :meth:`PipelineConfig.to_dict` gives it; ``stages`` the wall seconds of
    ``read`` (reading and checking the input), ``solve``, ``record`` (``to_dict``) and
    ``figures``, for the engine's breakdown; ``summary`` the result's one line
    (:meth:`Result.summary`).
    """
    import cv2
    import torch

    if torch.get_num_threads() != spec.threads:
        torch.set_num_threads(spec.threads)
    if cv2.getNumThreads() != spec.threads:
        cv2.setNumThreads(spec.threads)
    out: dict[str, Any] = {
        "status": "error", "kind": None, "result": None, "arrays": {}, "error": None, "seconds": 0.0, "artifacts": [],
        "notes": [], "config": None, "summary": None, "files": list(spec.files or ()),
    }
    stages = out["stages"] = {}
    t0 = time.perf_counter()
    try:
        for name in spec.imports:
            importlib.import_module(name)
        from torchsym.api import prepare, solve
        from torchsym.core.config import load_config
        from torchsym.io.inputs import Source

        source = Source(spec.input, spec.files or (spec.input,), spec.stem, spec.notes)
        cfg = load_config(spec.config) if spec.config is not None else None
        prepared = prepare(source, cfg, kind=spec.kind, overrides=spec.overrides)
        out["kind"], out["notes"], out["config"] = prepared.kind, list(prepared.notes), prepared.config.to_dict()
        stages["read"] = time.perf_counter() - t0
        result = solve(prepared)
        data = prepared.data
        out["seconds"] = time.perf_counter() - t0
        stages["solve"] = out["seconds"] - stages["read"]
        out["summary"] = result.summary()
        if spec.max_inline is None:
            out["result"] = result.to_dict()
        else:
            sink = ArraySink(spec.max_inline)
            out["result"] = result.to_dict(sink)
            out["arrays"] = sink.arrays
        stages["record"] = time.perf_counter() - t0 - out["seconds"]
        if spec.figures_dir is not None:
            from torchsym.viz import write_artifacts

            folder = Path(spec.figures_dir)
            folder.mkdir(parents=True, exist_ok=True)
            out["artifacts"] = [str(p) for p in write_artifacts(result, data, folder, spec.stem)]
            stages["figures"] = time.perf_counter() - t0 - out["seconds"] - stages["record"]
        out["status"] = "ok"
    except Exception as exc:  # every exception is the input's final outcome, recorded
        out["seconds"] = time.perf_counter() - t0
        out["result"] = None
        out["arrays"] = {}
        out["error"] = _error(exc)
    return out
