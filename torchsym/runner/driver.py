"""``torchsym.run``: one config over a whole dataset, resumable, on any engine.

The driver expands the input patterns, checks them against the config, opens the results
file (:mod:`torchsym.runner.store`: lock, resume), hands the inputs not yet done to an
engine (:mod:`torchsym.runner.engine`) and writes one record per input as it completes.
"""

from __future__ import annotations

import dataclasses
import importlib
import logging
import os
import sys
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from torchsym.core.config import PipelineConfig, load_config
from torchsym.core.registry import INPUT_KINDS
from torchsym.core.results import Result
from torchsym.errors import ConfigError, InputValueError
from torchsym.io.inputs import Source, expand_inputs
from torchsym.runner.engine import ENGINES, open_engine
from torchsym.runner.store import InputKey, ResultsStore, config_hash, input_key, make_record, read_results
from torchsym.runner.task import TaskSpec
from torchsym.runner.validate import check_run_options, default_threads

__all__ = ["EngineOptions", "RunSummary", "expand_inputs", "run"]

logger = logging.getLogger(__name__)

#: the automatic engine runs this many pending inputs or fewer in the driver (workers pay
#: seconds to import torch)
SERIAL_MAX = 4


@dataclasses.dataclass(frozen=True)
class RunSummary(Result):
    """What a run did.

    Attributes:
        out: the results file.
        engine: the engine used (``"serial"``, ``"local"`` or ``"dask"``).
        n_inputs: inputs matched by the patterns.
        n_skipped: inputs already done in the results file (same file, same config).
        n_ok, n_error, n_crashed: records written by this run, by status.
        seconds: wall time of the run, engine start-up and shut-down included.
        engine_seconds: of which starting the engine (cluster up, workers set up) and
            stopping it.
    """

    out: str
    engine: str
    n_inputs: int
    n_skipped: int
    n_ok: int
    n_error: int
    n_crashed: int
    seconds: float
    engine_seconds: float

    @property
    def n_run(self) -> int:
        """Records written by this run."""
        return self.n_ok + self.n_error + self.n_crashed


def _check_kinds(cfg: PipelineConfig, sources: Sequence[Source]) -> None:
    """Refuse, before anything runs, a file given by name that the config's input kind
    cannot read (a folder's other files are skipped by :func:`expand_inputs`)."""
    kind = INPUT_KINDS[cfg.input]
    wrong = [s.name for s in sources if len(s.files) == 1 and Path(s.files[0]).suffix.lower() not in kind.suffixes]
    if wrong:
        raise ConfigError(
            f"config: pipeline {cfg.source!r} takes {cfg.input!r} input ({' '.join(kind.suffixes)}), but "
            f"{wrong[0]!r} is not one ({len(wrong)} of {len(sources)} inputs)"
        )


def _record(store: ResultsStore, key: InputKey, outcome: Mapping[str, Any], attempts: int) -> dict[str, Any]:
    arrays = store.write_arrays(key, outcome["arrays"]) if outcome.get("arrays") else None
    return make_record(key, outcome, attempts=attempts, arrays=arrays)


def _choose_engine(engine: str, n_todo: int, address: str | None) -> str:
    if engine not in ENGINES:
        raise InputValueError(f"engine: expected one of {', '.join(ENGINES)}, got {engine!r}")
    if engine != "auto":
        return engine
    if address is not None or os.environ.get("DASK_SCHEDULER_ADDRESS"):
        return "dask"
    return "serial" if n_todo <= SERIAL_MAX else "local"


@dataclasses.dataclass(frozen=True)
class EngineOptions:
    """Where and how :func:`run` runs its tasks (as Open3D groups its criteria).

    Attributes:
        engine: ``"serial"``, ``"local"`` (a Dask ``LocalCluster``), ``"dask"`` (the
            scheduler at ``address``) or ``"auto"``: ``"dask"`` when ``address`` or
            ``DASK_SCHEDULER_ADDRESS`` is given, else serial for at most 4 pending inputs
            and local otherwise.
        address: Dask scheduler, ``tcp://host:8786`` or a ``scheduler.json`` path
            (default ``DASK_SCHEDULER_ADDRESS``).
        workers: worker processes of the local cluster (default 2).
        threads_per_worker: torch threads per task, on every engine; None (default): the
            machine's cores shared among the tasks that run at once
            (:func:`~torchsym.runner.validate.default_threads`: ``workers`` of them on the
            local engine, one serially; 1 on a remote scheduler), as ``torchsym detect``.
        retries: resubmissions of a task whose worker died, before it is recorded as
            ``"crashed"`` (default 2). Errors raised by a task are never retried.
        max_in_flight: tasks in flight on a Dask engine (default: two per live worker
            thread, one running and one waiting, so no worker waits for the driver).
        connect_timeout: seconds to reach a remote scheduler (default 5).
        imports: modules each worker imports first (to register your own solvers).
    """

    engine: str = "auto"
    address: str | None = None
    workers: int = 2
    threads_per_worker: int | None = None
    retries: int = 2
    max_in_flight: int | None = None
    connect_timeout: float = 5.0
    imports: tuple[str, ...] = ()


def _engine_options(options: EngineOptions | None, given: Mapping[str, Any]) -> EngineOptions:
    """``options`` (or the defaults) with the keyword fields ``given`` replacing its own;
    :class:`InputValueError` naming an unknown keyword."""
    if options is not None and not isinstance(options, EngineOptions):
        raise InputValueError(f"options: expected an EngineOptions or None, got {type(options).__name__}")
    names = [f.name for f in dataclasses.fields(EngineOptions)]
    unknown = [k for k in given if k not in names]
    if unknown:
        raise InputValueError(f"{unknown[0]}: not an option of torchsym.run; engine options: {', '.join(names)}")
    if "imports" in given:
        imports = given["imports"]
        given = {**given, "imports": (imports,) if isinstance(imports, str) else tuple(imports)}
    return dataclasses.replace(options or EngineOptions(), **given)


def run(
    config: str | Path | Mapping[str, Any] | PipelineConfig,
    inputs: str | Path | Sequence[str | Path],
    out: str | Path,
    *,
    options: EngineOptions | None = None,
    resume: bool = True,
    overrides: Mapping[str, Any] | None = None,
    figures: str | Path | None = None,
    max_inline: int | None = 1024,
    progress: bool = False,
    **engine_options: Any,
) -> RunSummary:
    """Run one pipeline config over every input and record each outcome in ``out``.

    Args:
        config: a YAML path, a mapping or a :class:`PipelineConfig`.
        inputs: paths, folders or glob patterns (``data/**/*.ply``), expanded for the
            config's input kind by :func:`torchsym.io.inputs.expand_inputs` (for
            ``multiview``, one scene per folder).
        out: the JSON-lines results file (:mod:`torchsym.runner.store`); inputs already
            done there with the same file and config are skipped.
        options: where and how the tasks run (:class:`EngineOptions`); its fields may also
            be given as keywords (``engine="local", workers=4``), which replace the same
            fields of ``options``.
        resume: False starts ``out`` afresh.
        overrides: settings of the config's last solver (``{"n_starts": 2}``, dotted keys
            for groups).
        figures: folder for each result's pictures (:func:`torchsym.viz.write_artifacts`)
            and the run's page ``index.html`` (:func:`torchsym.viz.index.write_index`);
            None writes none.
        max_inline: a result's arrays with more elements than this (per-point pairs,
            per-vertex maps) are kept in one ``.npz`` per input in ``<out stem>_arrays/``,
            referenced from the record (:mod:`torchsym.runner.store`); None keeps them all
            in the record (default 1024).
        progress: show a progress bar over completions (skipped inputs counted done).

    Returns:
        :class:`RunSummary`.

    Raises:
        InputFileError: a pattern matches nothing; ``out`` is locked by another run.
        ConfigError: a bad config, or inputs of a kind the config does not take.
        EngineError: the Dask scheduler cannot be reached.
    """
    t0 = time.perf_counter()
    opts = _engine_options(options, engine_options)
    engine, address, workers, threads_per_worker = opts.engine, opts.address, opts.workers, opts.threads_per_worker
    retries, max_in_flight, connect_timeout, imports = opts.retries, opts.max_in_flight, opts.connect_timeout, opts.imports
    check_run_options(out=out, workers=workers, threads_per_worker=threads_per_worker, retries=retries,
                      max_in_flight=max_in_flight, connect_timeout=connect_timeout, figures=figures)
    if max_inline is not None and (isinstance(max_inline, bool) or not isinstance(max_inline, int) or max_inline < 0):
        raise InputValueError(f"max_inline: expected a count >= 0 or None, got {max_inline!r}")
    for name in imports:  # they may register the config's solvers
        importlib.import_module(name)
    cfg = config if isinstance(config, PipelineConfig) else load_config(config)
    cfg = cfg.with_overrides(dict(overrides or {}))
    cfg_dict = cfg.to_dict()
    sources = expand_inputs(inputs, cfg.input)
    _check_kinds(cfg, sources)
    digest = config_hash(cfg_dict)
    keys = [input_key(s.name, digest, s.files) for s in sources]
    fig_dir = None if figures is None else str(Path(figures).resolve())
    counts: Counter[str] = Counter()
    with ResultsStore(out, resume=resume) as store:
        if store.torn_bytes:
            logger.warning("%s: cut a torn last line (%d bytes)", out, store.torn_bytes)
        todo = [i for i, k in enumerate(keys) if not store.is_done(k)]
        specs = [TaskSpec(i, keys[i].input, cfg_dict, 1, fig_dir, sources[i].stem, tuple(imports), max_inline,
                          tuple(str(Path(f).resolve()) for f in sources[i].files), notes=sources[i].notes) for i in todo]
        chosen = _choose_engine(engine, len(specs), address)
        threads = int(threads_per_worker) if threads_per_worker is not None else \
            1 if chosen == "dask" else default_threads(workers if chosen == "local" else 1)
        specs = [dataclasses.replace(spec, threads=threads) for spec in specs]
        skipped = len(sources) - len(specs)
        with _progress(len(sources), skipped, progress) as bar, open_engine(
            chosen, specs, address=address, workers=workers, threads=threads, imports=imports,
            retries=retries, max_in_flight=max_in_flight, connect_timeout=connect_timeout, status=bar.set_description_str,
        ) as (outcomes, engine_seconds):
            for spec, outcome, attempts in outcomes:
                store.append(_record(store, keys[spec.index], outcome, attempts))
                counts[outcome["status"]] += 1
                for note in outcome.get("notes") or []:
                    logger.warning("%s: %s", spec.input, note)
                if outcome["status"] == "crashed":
                    logger.warning("%s: crashed on every attempt (%d)", spec.input, attempts)
                bar.set_postfix(ok=counts["ok"], error=counts["error"], crashed=counts["crashed"], refresh=False)
                bar.update(1)
            last = time.perf_counter()
        stopping = time.perf_counter() - last
    if fig_dir is not None:  # the run's page, over every input of the results file (resumed ones too)
        from torchsym.viz.index import write_index

        write_index(read_results(out, arrays=False), fig_dir, results=out)
    return RunSummary(
        str(out), chosen, len(sources), skipped, counts["ok"], counts["error"], counts["crashed"],
        time.perf_counter() - t0, engine_seconds + stopping,
    )


def _progress(total: int, skipped: int, show: bool) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, initial=skipped, unit="input", disable=not show, file=sys.stderr, dynamic_ncols=True)
