"""The ``run`` and ``evaluate`` sub-commands of ``torchsym``.

    torchsym run CONFIG --inputs GLOB [GLOB ...] --out results.jsonl [--engine serial|local|dask]
                 [--address tcp://host:8786 | scheduler.json] [--workers N] [--retries N]
                 [--no-resume] [--set KEY=VALUE ...] [--figures DIR] [--max-inline N]
    torchsym evaluate results.jsonl --truth FILE [--json summary.json]

Exit status, as ``torchsym detect``'s: 0 when every input is ``ok`` (or every scored input
evaluated), 1 when some inputs ended ``error`` or ``crashed``, 2 for bad arguments (a
pattern matching nothing, a config for another kind of input, an unreachable scheduler, a
locked results file), reported as one line ``torchsym: error: ...`` by :func:`torchsym.cli.main`.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

__all__ = ["add_parsers"]


def _cmd_run(args: argparse.Namespace) -> int:
    from torchsym.core.config import parse_overrides
    from torchsym.runner.driver import EngineOptions, run

    options = EngineOptions(engine=args.engine, address=args.address, workers=args.workers,
                            threads_per_worker=args.threads, retries=args.retries)
    summary = run(
        args.config, args.inputs, args.out, options=options, resume=not args.no_resume,
        overrides=parse_overrides(args.set or []), figures=args.figures, progress=not args.quiet,
        max_inline=None if args.max_inline < 0 else args.max_inline,
    )
    print(
        f"{summary.out}: {summary.n_inputs} inputs, {summary.n_skipped} already done; ran {summary.n_run} on the "
        f"{summary.engine} engine: {summary.n_ok} ok, {summary.n_error} error, {summary.n_crashed} crashed "
        f"({summary.seconds:.1f} s)"
    )
    return 1 if summary.n_error or summary.n_crashed else 0


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from torchsym.runner.scoring import evaluate, format_evaluation

    ev = evaluate(args.results, args.truth)
    print(format_evaluation(ev))
    if args.json is not None:
        Path(args.json).write_text(json.dumps(ev.to_dict(), indent=2))
        print(f"wrote {args.json}")
    return 0


def add_parsers(sub: Any) -> None:
    """Add the ``run`` and ``evaluate`` sub-commands to ``sub`` (``add_subparsers()``'s result)."""
    r = sub.add_parser(
        "run",
        help="run one config over a whole dataset, resumably, serially or on a Dask cluster",
        description=(
            "Run a pipeline config over every input and append one JSON record per input to --out. "
            "Rerunning skips the inputs done with the same file and config, and re-runs crashed ones."
        ),
    )
    r.add_argument("config", metavar="CONFIG", help="an installed config's name (`torchsym configs` lists them) or a YAML pipeline file")
    r.add_argument("--inputs", nargs="+", required=True, metavar="GLOB",
                   help="files, folders or glob patterns (quote them: 'scans/**/*.ply'); for a multiview config, "
                        "a folder of photos is one scene and a folder of folders one scene per folder")
    r.add_argument("--out", required=True, help="the JSON-lines results file")
    r.add_argument("--engine", choices=["auto", "serial", "local", "dask"], default="auto",
                   help="serial: in this process; local: a Dask LocalCluster; dask: the scheduler at --address "
                        "(default auto: dask with --address or DASK_SCHEDULER_ADDRESS, serial for at most 4 pending inputs, else local)")
    r.add_argument("--address", help="Dask scheduler: tcp://host:8786 or a scheduler.json (default: DASK_SCHEDULER_ADDRESS)")
    r.add_argument("--workers", type=int, default=2, help="worker processes of the local cluster (default: %(default)s)")
    r.add_argument("--threads", type=int, default=None,
                   help="torch threads per task (default: the machine's cores shared among the workers)")
    r.add_argument("--retries", type=int, default=2, help="resubmissions of an input whose worker died (default: %(default)s)")
    r.add_argument("--no-resume", action="store_true", help="start --out afresh instead of skipping what is done")
    r.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a setting of the last solver (repeatable)")
    r.add_argument("--figures", metavar="DIR", help="write each result's pictures into DIR")
    r.add_argument("--max-inline", type=int, default=1024, metavar="N",
                   help="arrays of a result with more than N elements go to one .npz per input in <out stem>_arrays/, "
                        "referenced from the record; -1 keeps every array in the record (default: %(default)s)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=_cmd_run)

    e = sub.add_parser(
        "evaluate",
        help="score a results file against ground truth",
        description=(
            "Score a run with the library's metrics: axes.txt-style files for photos (both axis criteria), "
            "planes in JSON lines for point clouds, BCICP .vts/.sym.vts folders for meshes."
        ),
    )
    e.add_argument("results", help="the JSON-lines results file of torchsym run, or the --out folder of torchsym detect")
    e.add_argument("--truth", required=True, help="ground-truth file or folder (formats: the docstring of torchsym.runner.truth)")
    e.add_argument("--json", metavar="FILE", help="also write the figures, per input too, as JSON")
    e.set_defaults(func=_cmd_evaluate)
