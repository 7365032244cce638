"""The ``torchsym`` command line: ``detect``, ``demo`` and ``bench``.

    torchsym detect INPUT... [--config FILE] [--out DIR] [--set KEY=VALUE]...
    torchsym demo [--out DIR]
    torchsym bench [--n N] [--repeats R]
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path
from typing import Any, NoReturn, Sequence

import yaml

__all__ = ["main"]

_INPUTS_HELP = (
    "point clouds (.ply .obj .off .stl .xyz .txt .pts .npy), meshes (.off .obj .ply .stl with "
    "triangles), images (.png .jpg ...), or folders of them"
)


#: the file in an output folder listing what torchsym wrote there; a folder given as input
#: skips the files it names, so a second run over its own output folder reads the same inputs
MANIFEST = ".torchsym-outputs.json"


def _fail(message: str) -> None:
    """Print ``torchsym: error: message`` as one line on stderr."""
    print("torchsym: error: " + " ".join(str(message).splitlines()), file=sys.stderr)


def _yaml_value(key: str, text: str) -> Any:
    """``text`` read as one plain YAML value: no anchors or aliases, nesting at most 8 deep."""
    from torchsym.errors import ConfigError

    where = f"--set: {key}={text!r}"
    try:
        depth = 0
        for event in yaml.parse(text, Loader=yaml.SafeLoader):
            if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None):
                raise ConfigError(f"{where}: expected a plain value, got a YAML anchor or alias")
            depth += isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent))
            depth -= isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent))
            if depth > 8:
                raise ConfigError(f"{where}: expected a value nested at most 8 deep")
        return yaml.safe_load(text)
    except (yaml.YAMLError, RecursionError) as exc:
        problem = " ".join(str(exc).split()) or type(exc).__name__
        raise ConfigError(f"{where} is not a valid YAML value ({problem})") from None


def _parse_set(items: Sequence[str]) -> dict[str, Any]:
    from torchsym.errors import ConfigError

    out: dict[str, Any] = {}
    for item in items:
        key, eq, value = item.partition("=")
        if not eq or not key.strip():
            raise ConfigError(f"--set: expected KEY=VALUE, got {item!r}")
        out[key.strip()] = _yaml_value(key.strip(), value)
    return out


def _resolve(p: Path) -> Path:
    """``p`` resolved, or made absolute where it cannot be (a symlink loop)."""
    try:
        return p.resolve()
    except (OSError, RuntimeError):
        return p.absolute()


def _own_outputs(folder: Path) -> set[str]:
    """Names that earlier runs wrote into ``folder`` (its manifest; none if unreadable)."""
    try:
        names = json.loads((folder / MANIFEST).read_text()).get("outputs", [])
    except (OSError, ValueError, AttributeError):
        return set()
    return {n for n in names if isinstance(n, str)}


def _expand(inputs: Sequence[str]) -> list[Path]:
    """Files of ``inputs``: files as given, folders' files with a known suffix, except
    hidden files and the outputs a torchsym run wrote there (:data:`MANIFEST`)."""
    from torchsym.errors import InputFileError
    from torchsym.io.read import IMAGE_SUFFIXES, POINT_SUFFIXES

    paths: list[Path] = []
    for item in inputs:
        if not item.strip():
            raise InputFileError("INPUT: expected a file or folder, got ''")
        p = Path(item)
        if not p.is_dir():
            paths.append(p)
            continue
        skip = _own_outputs(p)
        try:
            found = sorted(q for q in p.iterdir() if q.suffix.lower() in IMAGE_SUFFIXES + POINT_SUFFIXES
                           and not q.name.startswith(".") and q.name not in skip)
        except OSError as exc:
            raise InputFileError(f"INPUT: cannot list the folder '{p}' ({exc.strerror or exc})") from None
        paths += found
    return paths


def _unique_stems(paths: Sequence[Path]) -> list[str]:
    """Output names for ``paths``: the file's stem, with its suffix added where two inputs
    share a stem (``chair.png``, ``chair.xyz`` -> ``chair_png``, ``chair_xyz``) and a count
    where they still clash (the same name in two folders)."""
    from collections import Counter

    counts = Counter(p.stem for p in paths)
    taken = {p.stem for p in paths if counts[p.stem] == 1}
    out = []
    for p in paths:
        if counts[p.stem] == 1:
            out.append(p.stem)
            continue
        base = f"{p.stem}_{p.suffix.lstrip('.').lower()}"
        stem, k = base, 1
        while stem in taken:
            k += 1
            stem = f"{base}_{k}"
        taken.add(stem)
        out.append(stem)
    return out


def _summary(result: Any) -> str:
    d = result.to_dict()
    keys = [k for k in ("normal", "offset", "score", "scores", "axes", "map", "pairs", "converged", "iterations") if k in d]
    parts = []
    for k in keys:
        v = d[k]
        if isinstance(v, float):
            v = round(v, 4)
        elif isinstance(v, list) and v and isinstance(v[0], float):
            v = [round(x, 4) for x in v]
        elif isinstance(v, list) and len(v) > 4:
            v = f"[{len(v)} entries]"
        parts.append(f"{k}={v}")
    return f"{d['type']}: " + ", ".join(parts)


def _out_dir(text: str) -> Path:
    """The ``--out`` folder; an empty name (which would mean the current folder) is refused."""
    from torchsym.errors import InputFileError

    if not text.strip():
        raise InputFileError(f"--out: expected a folder, got {text!r}")
    return Path(text)


def _make_out(out: Path) -> None:
    from torchsym.errors import InputFileError

    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputFileError(f"--out: cannot create the folder '{out}' ({exc.strerror or exc})") from None


def _write_outputs(
    result: Any,
    data: Any,
    record: dict[str, Any],
    out: Path,
    stem: str,
    figures: bool,
    protected: frozenset[Path],
    written: set[Path],
) -> list[str]:
    """Write ``<stem>.json`` and the result's pictures into ``out``; return the paths written.

    Everything is written into a fresh folder inside ``out`` first and then moved into
    place, so a file that would replace one of this run's inputs (``protected``; e.g. an
    input named ``chair_plane.ply`` beside ``chair.ply`` with ``--out`` on their folder)
    or a file this run already wrote (``written``, updated here) is refused with
    :class:`InputFileError` before anything is overwritten.
    """
    import shutil
    import tempfile

    from torchsym.errors import InputFileError, TorchsymError
    from torchsym.io.write import write_json

    _make_out(out)
    try:
        staging = Path(tempfile.mkdtemp(prefix=f".{stem}-", dir=out))
    except OSError as exc:
        raise InputFileError(f"--out: cannot write into '{out}' ({exc.strerror or exc})") from None
    try:
        from torchsym.viz import write_artifacts

        names = [Path(q).name for q in write_artifacts(result, data, staging, stem)] if figures else []
        record["artifacts"] = [str(out / name) for name in names]
        write_json(record, staging / f"{stem}.json")
        names.insert(0, f"{stem}.json")
        clash = [name for name in names if (out / name).resolve() in protected]
        if clash:
            raise InputFileError(
                f"--out: writing the results of '{stem}' into '{out}' would overwrite the input "
                f"'{out / clash[0]}'; choose another --out"
            )
        clash = [name for name in names if (out / name).resolve() in written]
        if clash:
            raise InputFileError(
                f"--out: writing the results of '{stem}' into '{out}' would overwrite '{out / clash[0]}', "
                "written earlier in this run"
            )
        for name in names:
            (staging / name).replace(out / name)
            written.add((out / name).resolve())
        _record_outputs(out, names)
    except TorchsymError:
        raise
    except OSError as exc:
        raise InputFileError(f"--out: cannot write the results of '{stem}' into '{out}' ({exc.strerror or exc})") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return [str(out / name) for name in names]


def _record_outputs(out: Path, names: Sequence[str]) -> None:
    """Add ``names`` to the manifest of ``out`` (see :data:`MANIFEST`)."""
    from torchsym.io.write import write_json

    write_json({"outputs": sorted(_own_outputs(out) | set(names))}, out / MANIFEST)


def _run_one(
    path: Path | Any,
    stem: str,
    args: argparse.Namespace,
    overrides: dict[str, Any],
    bar: Any = None,
    protected: frozenset[Path] = frozenset(),
    written: set[Path] | None = None,
) -> dict[str, Any]:
    """Read, solve, write one input; ``bar`` (a tqdm bar, optional) advances one step per stage.
    No file in ``protected`` (the run's inputs, resolved) or in ``written`` (the files the
    run wrote before) is ever written."""
    from torchsym.api import prepare
    from torchsym.core.config import build_pipeline

    def stage(name: str) -> None:
        if bar is not None:
            bar.set_description_str(f"{stem}: {name}")

    stage("reading")
    kind, data, cfg = prepare(path, args.config, kind=args.kind)
    pipeline = build_pipeline(cfg, **overrides)
    if bar is not None:
        bar.update(1)
    stage(f"solving ({kind})")
    t0 = time.perf_counter()
    result = pipeline(data)
    seconds = time.perf_counter() - t0
    if bar is not None:
        bar.update(1)
    stage("writing")
    record = {"input": str(path) if isinstance(path, Path) else stem, "kind": kind, "config": pipeline.config.to_dict(),
              "seconds": seconds, "result": result.to_dict()}
    paths_out: list[str] = []
    if args.out is not None:
        paths_out = _write_outputs(
            result, data, record, _out_dir(args.out), stem, not args.no_figures, protected, set() if written is None else written
        )
    if bar is not None:
        bar.update(1)
        bar.clear()
    print(f"{stem}: {_summary(result)} ({seconds:.3f} s)")
    for w in paths_out:
        print(f"  wrote {w}")
    return record


def _cmd_detect(args: argparse.Namespace) -> int:
    """Run every input; a failing input is reported on one line and the run goes on.
    Exit code 0 when all succeed, 2 when any failed."""
    from tqdm import tqdm

    from torchsym.errors import TorchsymError

    overrides = _parse_set(args.set or [])
    _make_out(_out_dir(args.out))
    paths = _expand(args.inputs)
    if not paths:
        _fail("detect: no inputs found (folders are searched for " + _INPUTS_HELP.split(", or")[0] + ")")
        return 2
    # never written: the inputs and the config file
    protected = frozenset([_resolve(p) for p in paths] + ([_resolve(Path(args.config))] if args.config else []))
    stems = _unique_stems(paths)
    written: set[Path] = set()
    failures = 0
    # three steps per input (read, solve, write), so a single input shows its stages too
    with tqdm(total=3 * len(paths), unit="step", disable=True if args.quiet else None, file=sys.stderr, leave=False) as bar:
        for p, stem in zip(paths, stems):
            done = bar.n
            try:
                _run_one(p, stem, args, overrides, bar, protected, written)
            except TorchsymError as exc:
                failures += 1
                bar.clear()
                _fail(f"{p}: {exc}")
            except Exception as exc:  # noqa: BLE001 -- a folder run goes on past a bug in one input
                if args.verbose:
                    raise
                failures += 1
                bar.clear()
                _fail(f"{p}: internal error {type(exc).__name__}: {exc} (rerun with -v for the traceback)")
            bar.update(done + 3 - bar.n)
    if failures and len(paths) > 1:
        _fail(f"{failures} of {len(paths)} inputs failed")
    return 2 if failures else 0


def _cmd_demo(args: argparse.Namespace) -> int:
    import math

    from torchsym import data
    from torchsym.geometry import plane_angle

    path = data.sample_path("chair.ply")
    print(f"torchsym demo: reflection plane of the embedded sample {path.name} (4,000 points, known plane)")
    from tqdm import tqdm

    args.config, args.kind, args.no_figures = None, None, False
    with tqdm(total=3, unit="step", file=sys.stderr, leave=False) as bar:
        record = _run_one(path, "chair", args, {}, bar, frozenset([path.resolve()]))
    n_true, b_true = data.sample_plane()
    import torch

    n = torch.tensor(record["result"]["normal"])
    err = float(plane_angle(n, n_true)) * 180 / math.pi
    print(f"angle to the true plane: {err:.5f} degrees; symmetry score {record['result']['score']:.3f}")
    return 0 if err < 1.0 else 1


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
            "(point cloud: reflection plane; mesh: intrinsic symmetry map; image: symmetry axes) "
            "unless --config names a YAML pipeline (see configs/)."
        ),
    )
    d.add_argument("inputs", nargs="+", metavar="INPUT", help=_INPUTS_HELP)
    d.add_argument("--config", help="YAML pipeline file (input kind, steps with solver names and params)")
    d.add_argument("--out", default="torchsym-out", help="folder for <name>.json and the pictures (default: %(default)s)")
    d.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a setting of the last solver (repeatable)")
    d.add_argument("--kind", choices=["pointcloud", "points", "image", "mesh"], help="treat inputs as this kind (e.g. a mesh's vertices as a point cloud)")
    d.add_argument("--no-figures", action="store_true", help="write JSON only")
    d.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
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
