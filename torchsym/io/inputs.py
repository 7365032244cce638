"""From the paths a user gives to the inputs of a run: the one input expansion and the one
output naming rule of ``torchsym.detect``, ``torchsym detect`` and ``torchsym run``.

A pattern is a file, a folder or a glob (``scans/**/*.ply``). What an input is depends on
the kind the pipeline takes (:data:`torchsym.core.registry.INPUT_KINDS`):

- one file per input (point clouds, meshes, images): a folder gives its files of the
  kind, a glob its matching files;
- several files per input (``multiview``, the photos of one scene): a folder of photos
  is one scene, a folder of folders one scene per folder, and the loose photos of all
  the patterns together one scene.

A folder's hidden files, the files of another kind (``K.txt`` beside the photos) and the
outputs an earlier run wrote there (:data:`MANIFEST`) are skipped, each with a note.
"""

from __future__ import annotations

import dataclasses
import glob
import hashlib
import json
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

from torchsym.core.registry import IMAGE_SUFFIXES, INPUT_KINDS, POINT_SUFFIXES
from torchsym.errors import InputFileError, InputValueError

__all__ = ["MANIFEST", "Source", "expand_inputs", "own_outputs", "unique_stems"]

#: the file in an output folder listing what torchsym wrote there; a folder given as input
#: skips the files it names, so a second run over its own output folder reads the same inputs
MANIFEST = ".torchsym-outputs.json"


@dataclasses.dataclass(frozen=True)
class Source:
    """One input of a run, as found on disk.

    Attributes:
        name: the input as a user names it: the file, or the folder of a scene's photos.
        files: the files read: one, or the photos of the scene (sorted).
        stem: the file-name stem of its outputs, unique in the run (:func:`unique_stems`).
        notes: what the expansion skipped for it.
    """

    name: str
    files: tuple[str, ...]
    stem: str = ""
    notes: tuple[str, ...] = ()


def own_outputs(folder: Path) -> set[str]:
    """Names that earlier runs wrote into ``folder`` (its :data:`MANIFEST`; none if unreadable)."""
    try:
        names = json.loads((folder / MANIFEST).read_text()).get("outputs", [])
    except (OSError, ValueError, AttributeError):
        return set()
    return {n for n in names if isinstance(n, str)}


def _listing(folder: Path) -> list[Path]:
    """``folder``'s entries, sorted, without hidden ones and earlier outputs."""
    skip = own_outputs(folder)
    try:
        return sorted(q for q in folder.iterdir() if not q.name.startswith(".") and q.name not in skip)
    except OSError as exc:
        raise InputFileError(f"inputs: cannot list the folder '{folder}' ({exc.strerror or exc})") from None


def _skipped(files: Sequence[Path], what: str) -> tuple[str, ...]:
    if not files:
        return ()
    names = ", ".join(q.name for q in files[:3]) + (", ..." if len(files) > 3 else "")
    return (f"skipped {len(files)} file(s) that hold no {what}: {names}",)


def _matches(pattern: str) -> list[Path]:
    """The entries a pattern names: itself when it exists, else its glob matches (sorted)."""
    if not pattern.strip():
        raise InputFileError(f"inputs: expected a file, folder or glob pattern, got {pattern!r}")
    p = Path(pattern)
    if p.is_symlink() and not p.exists():
        raise InputFileError(f"inputs: {pattern!r} is a symbolic link to nothing (a loop or a missing target)")
    if p.exists():
        return [p]
    hits = sorted(Path(q) for q in glob.glob(pattern, recursive=True))
    if not hits:
        what = "matches no file" if glob.has_magic(pattern) else "does not exist"
        raise InputFileError(f"inputs: {pattern!r} {what}")
    return hits


def expand_inputs(patterns: str | Path | Sequence[str | Path], kind: str | None = None) -> list[Source]:
    """The inputs that ``patterns`` name for a pipeline taking ``kind``, each once, stems set.

    Args:
        patterns: files, folders or glob patterns (``**`` recurses).
        kind: the pipeline's input kind; None reads every file torchsym knows (points,
            meshes, images), one input per file; a folder then gives the kind most of its
            files are, photos or 3D files, and skips the others with a note (a folder of
            photos with its ``axes.txt``).

    Returns:
        :class:`Source` per input, in the order the patterns give them (a folder's and a
        glob's entries sorted).

    Raises:
        InputFileError: a pattern that names nothing, or a folder that cannot be listed.
        InputValueError: no input found.
    """
    if isinstance(patterns, (str, Path)):
        patterns = [patterns]
    info = INPUT_KINDS[kind] if kind is not None else None
    suffixes = info.suffixes if info is not None else POINT_SUFFIXES + IMAGE_SUFFIXES
    what = f"{kind} input ({' '.join(suffixes)})" if kind else "input torchsym reads"
    grouped = info is not None and info.grouped
    sources: list[Source] = []
    loose: list[Path] = []  # grouped: the photos given as files, together one scene
    loose_skipped: list[Path] = []
    skipped_notes: tuple[str, ...] = ()  # for the error when nothing is found
    for pat in patterns:
        for p in _matches(str(pat)):
            if p.is_dir():
                entries = _listing(p)
                files = [q for q in entries if q.is_file() and q.suffix.lower() in suffixes]
                skipped = [q for q in entries if q.is_file() and q.suffix.lower() not in suffixes]
                mixed: tuple[str, ...] = ()
                if kind is None:  # a folder holds one kind: its photos, or its 3D files, the more
                    photos = [q for q in files if q.suffix.lower() in IMAGE_SUFFIXES]
                    shapes = [q for q in files if q.suffix.lower() not in IMAGE_SUFFIXES]
                    if photos and shapes:
                        files, other = (photos, shapes) if len(photos) >= len(shapes) else (shapes, photos)
                        most = "photos" if files is photos else "3D files"
                        mixed = _skipped(other, f"input of the folder's kind (most of its files are {most})")
                if not grouped:
                    notes = _skipped(skipped, what) + mixed
                    skipped_notes += notes
                    sources += [Source(str(q), (str(q),), notes=notes if i == 0 else ()) for i, q in enumerate(files)]
                elif files:
                    sources.append(Source(str(p), tuple(map(str, files)), notes=_skipped(skipped, what)))
                else:  # a folder of scenes
                    for sub in (q for q in entries if q.is_dir()):
                        inner = _listing(sub)
                        photos = [q for q in inner if q.is_file() and q.suffix.lower() in suffixes]
                        if photos:
                            others = [q for q in inner if q.is_file() and q.suffix.lower() not in suffixes]
                            sources.append(Source(str(sub), tuple(map(str, photos)), notes=_skipped(others, what)))
            elif not grouped:
                sources.append(Source(str(p), (str(p),)))
            elif p.suffix.lower() in suffixes:
                loose.append(p)
            else:
                loose_skipped.append(p)
    if loose:
        parents = {str(q.parent) for q in loose}
        name = parents.pop() if len(parents) == 1 else str(Path(*_common_parts([q.parent for q in loose])) or ".")
        sources.append(Source(name, tuple(map(str, loose)), notes=_skipped(loose_skipped, what)))
    sources = _once(sources)
    if not sources:
        why = f" ({'; '.join(skipped_notes + _skipped(loose_skipped, what))})" if skipped_notes or loose_skipped else ""
        raise InputValueError(f"inputs: no {what} found in {', '.join(map(str, patterns)) or 'no patterns'}{why}")
    stems = unique_stems([Path(s.name) for s in sources])
    return [dataclasses.replace(s, stem=stem) for s, stem in zip(sources, stems)]


def _common_parts(folders: Sequence[Path]) -> list[str]:
    parts = [f.resolve().parts for f in folders]
    out = []
    for column in zip(*parts):
        if len(set(column)) != 1:
            break
        out.append(column[0])
    return out


def _once(sources: list[Source]) -> list[Source]:
    """``sources`` without repeats of the same files (first kept)."""
    seen: set[tuple[str, ...]] = set()
    out = []
    for s in sources:
        key = tuple(sorted(_resolved(f) for f in s.files))
        if key not in seen:
            seen.add(key)
            out.append(s)
    return out


def _resolved(path: str) -> str:
    try:
        return str(Path(path).resolve())
    except (OSError, RuntimeError):  # a symlink loop: read later, and refused there
        return str(Path(path).absolute())


def unique_stems(paths: Sequence[Path]) -> list[str]:
    """Output names for ``paths``: the file's stem (a folder's name), with its suffix
    added where two inputs share a stem (``chair.png``, ``chair.xyz`` -> ``chair_png``,
    ``chair_xyz``) and a count where they still clash (the same name in two folders).
    A name longer than :data:`MAX_STEM` characters keeps its start and a hash of the
    whole (:func:`short_stem`), so that ``<stem>_<picture>.png`` fits a file system's
    255-byte names."""
    counts = Counter(p.stem for p in paths)
    taken = {p.stem for p in paths if counts[p.stem] == 1}
    out = []
    for p in paths:
        if counts[p.stem] == 1:
            out.append(short_stem(p.stem))
            continue
        base = f"{p.stem}_{p.suffix.lstrip('.').lower()}" if p.suffix else p.stem
        stem, k = base, 1
        while stem in taken:
            k += 1
            stem = f"{base}_{k}"
        taken.add(stem)
        out.append(short_stem(stem))
    return out


#: the longest output stem, in UTF-8 bytes: room for the longest picture suffix a writer
#: adds (``_symmetry_map_axis12_nmrf.npy``...) within 255 bytes
MAX_STEM = 120


def short_stem(stem: str) -> str:
    """``stem`` if it fits :data:`MAX_STEM` bytes, else its first characters, ``_`` and 10
    hex digits of its SHA-1 (distinct long names stay distinct)."""
    if len(stem.encode()) <= MAX_STEM:
        return stem
    digest = hashlib.sha1(stem.encode()).hexdigest()[:10]
    head = stem.encode()[: MAX_STEM - 11].decode(errors="ignore")
    return f"{head}_{digest}"
