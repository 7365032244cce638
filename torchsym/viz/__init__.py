"""Pictures of results: every picture torchsym makes is drawn here.

One module per family of results registers a writer for its result type with
:func:`artifact_writer`; :func:`write_artifacts` picks the writer by the result's type
(its class, or the nearest base class with a writer) and returns the paths written::

    paths = torchsym.viz.write_artifacts(result, data, "out/", "chair")

Methods never import this package; the CLI and the dataset runner call it.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["artifact_writer", "write_artifacts"]

Writer = Callable[[Any, Any, Path, str], list[Path]]
_WRITERS: dict[type, Writer] = {}


def artifact_writer(result_type: type) -> Callable[[Writer], Writer]:
    """Decorator: register ``fn(result, data, out_dir, stem) -> list[Path]`` as the
    picture writer of ``result_type`` (and of its subclasses without their own)."""

    def deco(fn: Writer) -> Writer:
        _WRITERS[result_type] = fn
        return fn

    return deco


def write_artifacts(result: Any, data: Any, out_dir: str | Path, stem: str) -> list[Path]:
    """Write the pictures of ``result`` on its input ``data`` into ``out_dir``.

    Args:
        result: a solver's result.
        data: the input the solver ran on (tensor, image or mesh).
        out_dir: an existing folder.
        stem: the file-name stem (``chair`` gives ``chair_plane.png``...).

    Returns:
        The paths written (none for a result type without pictures).
    """
    _load_writers()
    out = Path(out_dir)
    for cls in type(result).__mro__:
        fn = _WRITERS.get(cls)
        if fn is not None:
            return list(fn(result, data, out, stem))
    return []


def _load_writers() -> None:
    """Import the writer modules (each registers its result types)."""
    import importlib

    for name in _MODULES:
        importlib.import_module(f"torchsym.viz.{name}")


#: writer modules, one per family of results
_MODULES: tuple[str, ...] = ("image", "mesh", "multiview", "planes", "pointcloud", "pointset", "superpixels", "symmetry", "symmetry_map",)
