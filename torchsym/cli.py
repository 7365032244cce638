"""The ``torchsym`` command line: ``detect``, ``demo`` and ``bench``.

    torchsym detect INPUT... [--config FILE] [--out DIR] [--set KEY=VALUE]...
    torchsym demo [--out DIR]
    torchsym bench [--n N] [--repeats R]
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import re
import sys
import threading
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, NoReturn

from torchsym.core.registry import USER_KINDS

__all__ = ["detect_files", "main"]

_INPUTS_HELP = (
    "point clouds (.ply .obj .off .stl .xyz .txt .pts .npy), meshes (.off .obj .ply .stl with "
    "triangles), images (.png .jpg ...), folders or glob patterns of them; for a multiview config, "
    "a folder of photos (or the photos) is one scene and a folder of folders one scene per folder"
)


def _fail(message: str) -> None:
    """Print ``torchsym: error: message`` as one line on stderr: the one error format of
    every sub-command."""
    print("torchsym: error: " + " ".join(str(message).splitlines()), file=sys.stderr)


def _resolve(p: Path) -> Path:
    """``p`` resolved, or made absolute where it cannot be (a symlink loop)."""
    try:
        return p.resolve()
    except (OSError, RuntimeError):
        return p.absolute()


def _out_dir(text: str) -> Path:
    """The ``--out`` folder, created; an empty name (which would mean the current folder) is refused."""
    from torchsym.errors import InputFileError

    if not text.strip():
        raise InputFileError(f"--out: expected a folder, got {text!r}")
    out = Path(text)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputFileError(f"--out: cannot create the folder '{out}' ({exc.strerror or exc})") from None
    return out


def _place(record: dict[str, Any], staging: Path, out: Path, stem: str, protected: frozenset[Path], written: set[Path]) -> list[str]:
    """Write ``<stem>.json`` beside the pictures the task wrote into ``staging`` and move
    them into ``out``; return the paths written.

    A file that would replace one of this run's inputs (``protected``; e.g. an input named
    ``chair_plane.ply`` beside ``chair.ply`` with ``--out`` on their folder) or a file this
    run already wrote (``written``, updated here) is refused with :class:`InputFileError`
    before anything of this input is moved.
    """
    import shutil

    from torchsym.errors import InputFileError
    from torchsym.io.inputs import MANIFEST, own_outputs
    from torchsym.io.write import write_json

    names = [Path(q).name for q in record.get("artifacts") or []]
    record["artifacts"] = [str(out / name) for name in names]
    try:
        write_json(record, staging / f"{stem}.json")
        names.insert(0, f"{stem}.json")
        for name in (n for n in names if (out / n).resolve() in protected):
            raise InputFileError(
                f"--out: writing the results of '{stem}' into '{out}' would overwrite the input '{out / name}'; choose another --out"
            )
        for name in (n for n in names if (out / n).resolve() in written):
            raise InputFileError(
                f"--out: writing the results of '{stem}' into '{out}' would overwrite '{out / name}', written earlier in this run"
            )
        for name in names:
            if (out / name).is_dir():  # a folder an earlier run wrote (a scene's COLMAP model)
                shutil.rmtree(out / name)
            (staging / name).replace(out / name)
            written.add((out / name).resolve())
        write_json({"outputs": sorted(own_outputs(out) | set(names))}, out / MANIFEST)
    except OSError as exc:
        raise InputFileError(f"--out: cannot write the results of '{stem}' into '{out}' ({exc.strerror or exc})") from None
    finally:  # what was not moved (a refused input's files) goes
        for q in staging.iterdir():
            shutil.rmtree(q) if q.is_dir() else q.unlink()
    return [str(out / name) for name in names]


def _error_line(source: str, error: dict[str, Any]) -> str:
    """A failed input's line: its :class:`TorchsymError` message, or an internal error."""
    import torchsym.errors

    cls = getattr(torchsym.errors, str(error.get("type")), None)
    if isinstance(cls, type) and issubclass(cls, torchsym.errors.TorchsymError):
        return error["message"] if source in error["message"] else f"{source}: {error['message']}"
    return f"{source}: internal error {error.get('type')}: {error.get('message')} (at {error.get('where')})"


@contextlib.contextmanager
def _ticking(bar: Any, every: float = 1.0) -> Iterator[None]:
    """Redraw ``bar`` every ``every`` seconds while the body runs, so a long input shows
    its name and elapsed time as it runs (a terminal only: a disabled bar draws nothing)."""
    stop = threading.Event()

    def tick() -> None:
        while not stop.wait(every):
            bar.refresh()

    thread = threading.Thread(target=tick, name="torchsym-progress", daemon=True)
    if not bar.disable:
        thread.start()
    try:
        yield
    finally:
        stop.set()
        if thread.is_alive():
            thread.join()


def detect_files(
    inputs: Sequence[str],
    out: Path,
    *,
    config: str | None = None,
    kind: str | None = None,
    overrides: dict[str, Any] | None = None,
    figures: bool = True,
    quiet: bool = False,
    threads: int | None = None,
) -> tuple[int, list[dict[str, Any]]]:
    """Run each input of ``inputs`` and write ``<stem>.json`` and its pictures into ``out``:
    the serial case of ``torchsym run``, with the same input expansion
    (:func:`torchsym.io.inputs.expand_inputs`) and the same task
    (:func:`torchsym.runner.task.run_task` on the serial engine). A failing input is
    reported on one line and the run goes on. ``threads``: torch threads (None: the
    machine's cores, :func:`~torchsym.runner.validate.default_threads`).

    Returns:
        ``(failures, records)``: the number of inputs that failed and the records written.
    """
    import shutil
    import tempfile

    from tqdm import tqdm

    from torchsym.core.config import load_config
    from torchsym.errors import ConfigError, InputFileError
    from torchsym.io.inputs import expand_inputs
    from torchsym.runner.engine import serial_outcomes
    from torchsym.runner.store import config_hash, input_key, make_record
    from torchsym.runner.validate import check_threads, default_threads
    from torchsym.runner.task import TaskSpec

    overrides = dict(overrides or {})
    threads = default_threads() if threads is None else check_threads(threads)
    cfg = load_config(config).with_overrides(overrides) if config else None
    sources = expand_inputs(list(inputs), kind or (cfg.input if cfg is not None else None))
    # never written: the inputs and the config file
    protected = frozenset([_resolve(Path(f)) for s in sources for f in s.files] + ([_resolve(Path(config))] if config else []))
    try:
        staging = Path(tempfile.mkdtemp(prefix=".torchsym-staging-", dir=out))
    except OSError as exc:
        raise InputFileError(f"--out: cannot write into '{out}' ({exc.strerror or exc})") from None
    specs = [
        TaskSpec(i, s.name, cfg.to_dict() if cfg is not None else None, threads, str(staging) if figures else None, s.stem,
                 max_inline=None, files=s.files, kind=kind, overrides={} if cfg is not None else overrides, notes=s.notes)
        for i, s in enumerate(sources)
    ]
    written: set[Path] = set()
    records: list[dict[str, Any]] = []
    failures = 0
    try:
        with tqdm(total=len(specs), unit="input", disable=True if quiet else None, file=sys.stderr, leave=False) as bar, \
                _ticking(bar):
            bar.set_description_str(specs[0].stem if specs else "")
            for spec, outcome, _ in serial_outcomes(specs, threads=threads):
                bar.clear()
                if spec.index + 1 < len(specs):
                    bar.set_description_str(specs[spec.index + 1].stem, refresh=False)
                source = sources[spec.index]
                for note in outcome.get("notes") or []:
                    print(f"torchsym: note: {source.name}: {note}", file=sys.stderr)
                bar.update(1)
                if outcome["status"] != "ok" and overrides and cfg is None and (outcome["error"] or {}).get("type") == "ConfigError":
                    raise ConfigError(_error_line(source.name, outcome["error"]))  # a bad --set: exit 2, as with --config
                if outcome["status"] != "ok":
                    failures += 1
                    _fail(_error_line(source.name, outcome["error"]))
                    continue
                key = input_key(source.name, config_hash(outcome["config"] or {}), source.files)
                record = make_record(key, {**outcome, "files": list(source.files)})
                try:
                    paths = _place(record, staging, out, spec.stem, protected, written)
                except InputFileError as exc:
                    failures += 1
                    _fail(f"{source.name}: {exc}")
                    continue
                records.append(record)
                print(f"{spec.stem}: {outcome['summary']} ({outcome['seconds']:.3f} s)")
                for w in paths:
                    print(f"  wrote {w}")
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    if failures and len(specs) > 1:
        _fail(f"{failures} of {len(specs)} inputs failed")
    return failures, records


def _cmd_detect(args: argparse.Namespace) -> int:
    """Exit code 0 when every input succeeds, 1 when some failed (as ``torchsym run``)."""
    from torchsym.core.config import parse_overrides

    failures, _ = detect_files(
        args.inputs, _out_dir(args.out), config=args.config, kind=args.kind, overrides=parse_overrides(args.set or []),
        figures=not args.no_figures, quiet=args.quiet, threads=args.threads,
    )
    return 1 if failures else 0


def _cmd_demo(args: argparse.Namespace) -> int:
    import math

    from torchsym import data
    from torchsym.geometry import plane_angle

    path = data.sample_path("chair.ply")
    print(f"torchsym demo: reflection plane of the embedded sample {path.name} (4,000 points, known plane)")
    failures, records = detect_files([str(path)], _out_dir(args.out), quiet=True)
    if failures:
        return 1
    record = records[0]
    n_true, b_true = data.sample_plane()
    import torch

    n = torch.tensor(record["result"]["normal"])
    err = float(plane_angle(n, n_true)) * 180 / math.pi
    print(f"angle to the true plane: {err:.5f} degrees; symmetry score {record['result']['score']:.3f}")
    return 0 if err < 1.0 else 1


def _cmd_configs(args: argparse.Namespace) -> int:
    from torchsym.core.config import CONFIG_DIR, list_configs

    configs = list_configs()
    width = max((len(n) for n in configs), default=0)
    for name, text in configs.items():
        head = re.split(r": |\.\s(?=[A-Z])", text)[0].rstrip(".")  # the first clause
        print(f"{name:<{width}}  {head if len(head) <= 100 else head[:99] + '...'}")
    print(f"({len(configs)} configs in {CONFIG_DIR}; give --config a name or a path to a YAML file of your own)")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    from torchsym.bench import quick_pointcloud_benchmark

    quick_pointcloud_benchmark(n=args.n, repeats=args.repeats)
    return 0


class _Parser(argparse.ArgumentParser):
    """Usage errors as one line, ``torchsym: error: ...``, exit code 2."""

    def error(self, message: str) -> NoReturn:
        _fail(message)
        raise SystemExit(2)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="torchsym",
        description="Reflection symmetry detection in point clouds, meshes, images and d-dimensional point sets.",
    )
    p.add_argument("-v", "--verbose", action="store_true", help="log each stage of the solvers with its time")
    sub = p.add_subparsers(dest="command", required=True)

    d = sub.add_parser(
        "detect",
        help="detect the reflection symmetry of inputs and write JSON and pictures",
        description=(
            "Detect reflection symmetry. The pipeline is chosen from each input's kind "
            "(point cloud: reflection plane; mesh: intrinsic symmetry map, or the reflection plane of its surface "
            "when it is not one manifold piece; image: symmetry axes) unless --config names a YAML pipeline "
            "(`torchsym configs` lists them). The serial case of `torchsym run`: exit code 0 when every input succeeds, 1 when "
            "some failed, 2 for bad arguments."
        ),
    )
    d.add_argument("inputs", nargs="+", metavar="INPUT", help=_INPUTS_HELP)
    d.add_argument("--config", help="an installed config's name (see `torchsym configs`) or a YAML pipeline file")
    d.add_argument("--out", default="torchsym-out", help="folder for <name>.json and the pictures (default: %(default)s)")
    d.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a setting of the last solver (repeatable)")
    d.add_argument("--kind", choices=USER_KINDS, help="treat inputs as this kind (e.g. pointcloud: a mesh sampled on its surface; mesh: the intrinsic pipeline)")
    d.add_argument("--no-figures", action="store_true", help="write JSON only")
    d.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    d.add_argument("--threads", type=int, default=None, help="torch threads (default: the machine's cores)")
    d.set_defaults(func=_cmd_detect)

    m = sub.add_parser("demo", help="run the point-cloud pipeline on the embedded sample and check the answer",
                       description="Detect the reflection plane of the chair shipped inside the package and compare it with the true plane.")
    m.add_argument("--out", default="torchsym-demo", help="folder for the JSON, PLY and PNG (default: %(default)s)")
    m.set_defaults(func=_cmd_demo)

    b = sub.add_parser("bench", help="time the point-cloud detector against one kd-tree query (quick)",
                       description="Quick speed and accuracy check on planted symmetric clouds. The full benchmarks with baselines are the scripts in benchmarks/ of the source tree.")
    b.add_argument("--n", type=int, default=30000, help="points per cloud (default: %(default)s)")
    b.add_argument("--repeats", type=int, default=5, help="clouds timed (default: %(default)s)")
    b.set_defaults(func=_cmd_bench)

    c = sub.add_parser("configs", help="list the configs installed with the package, one line each",
                       description="List the pipelines installed with torchsym; --config takes their names.")
    c.set_defaults(func=_cmd_configs)

    from torchsym.runner.cli import add_parsers

    add_parsers(sub)  # run, evaluate
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; every error is one line ``torchsym: error: ...`` and exit code 2
    (a traceback only with ``-v``)."""
    args = _parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, format="%(name)s: %(message)s")
    import torch

    from torchsym.errors import TorchsymError

    torch.set_num_threads(min(2, torch.get_num_threads()))
    try:
        return int(args.func(args))
    except TorchsymError as exc:
        _fail(str(exc))
        return 2
    except KeyboardInterrupt:
        _fail("interrupted")
        return 130
    except Exception as exc:  # noqa: BLE001 -- never a traceback without -v
        if args.verbose:
            raise
        _fail(f"internal error {type(exc).__name__}: {exc} (rerun with -v for the traceback)")
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
