"""A BOP dataset's ``models_info.json`` from its ``models/`` folder, in one command:

    python -m torchsym.pointcloud.symmetry.bop_export path/to/models

Each mesh (``obj_000001.ply``, or any ``.ply .obj .off .stl``; the object id is the
number in its name) is sampled on its surface, its whole symmetry group found
(:func:`~torchsym.pointcloud.detect_symmetry`) and written as BOP's fields:
``diameter``, ``min_x/y/z``, ``size_x/y/z`` from the vertices, ``symmetries_discrete``
(the proper rotations, 4 x 4 row-major in the model's units) and ``symmetries_continuous``
(axes of revolution). The file is written atomically; a picture of each model's planes
and axes, orders labelled, goes beside it (``models_info_pictures/obj_000001.png``).
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path
from typing import Any

import torch

from torchsym.errors import InputFileError, TorchsymError
from torchsym.io import read_mesh
from torchsym.pointcloud.reflection_planes.bop import models_info_entry, write_models_info
from torchsym.pointcloud.symmetry.detect import detect_symmetry

__all__ = ["export_models_info", "main"]

_SUFFIXES = (".ply", ".obj", ".off", ".stl")


def _object_id(path: Path) -> int | None:
    """The object id in a model's file name (``obj_000005.ply``: 5), or None."""
    found = re.findall(r"\d+", path.stem)
    return int(found[-1]) if found else None


def export_models_info(
    models: str | Path,
    out: str | Path | None = None,
    *,
    pictures: str | Path | None = None,
    n_points: int = 20000,
    settings: Any = None,
    seed: int = 0,
) -> Path:
    """Write ``models_info.json`` for every mesh in the folder ``models``; returns its path.

    Args:
        models: a BOP ``models/`` folder (meshes named with their object id).
        out: the file to write; default ``models/models_info.json``.
        pictures: folder of one PNG per model; default ``models_info_pictures`` beside
            ``out``; ``""`` for none.
        n_points: surface samples per model.
        settings: :class:`~torchsym.pointcloud.SymmetrySettings` or a mapping.
        seed: the sampling's and the detector's seed.

    Raises:
        InputFileError: ``models`` is not a folder, or holds no mesh with an id.
    """
    from torchsym.geometry.sampling import sample_surface

    models = Path(models)
    if not models.is_dir():
        raise InputFileError(f"models: expected a folder of meshes, got {str(models)!r}")
    files = sorted(p for p in models.iterdir() if p.suffix.lower() in _SUFFIXES and _object_id(p) is not None)
    if not files:
        raise InputFileError(f"models: no mesh named with an object id ({', '.join(_SUFFIXES)}) in {str(models)!r}")
    out = Path(out) if out is not None else models / "models_info.json"
    pics = None if pictures == "" else Path(pictures) if pictures is not None else out.parent / "models_info_pictures"
    entries = {}
    for path in files:
        mesh = read_mesh(path, dtype=torch.float64)
        pts = sample_surface(mesh, n_points, generator=seed)
        res = detect_symmetry(pts, settings, generator=seed)
        entries[_object_id(path)] = models_info_entry(mesh.vertices, res.group)
        if pics is not None:
            from torchsym.viz.symmetry import plot_symmetry_group

            plot_symmetry_group(pts, res.group, pics / f"{path.stem}.png", title=path.name)
        orders = sorted((int(o) for o in res.group.orders), reverse=True)
        print(f"{path.name}: {res.group.rotations.shape[0]} rotation(s), axes {orders or 'none'}, "
              f"{res.group.continuous_axes.shape[0]} axis/axes of revolution", flush=True)
    return write_models_info(out, entries)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m torchsym.pointcloud.symmetry.bop_export", description=__doc__.split("\n")[0])
    ap.add_argument("models", help="a BOP models/ folder")
    ap.add_argument("--out", default=None, help="models_info.json to write (default: inside the folder)")
    ap.add_argument("--pictures", default=None, help="folder of one picture per model ('' for none)")
    ap.add_argument("--points", type=int, default=20000, help="surface samples per model")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    try:
        path = export_models_info(args.models, args.out, pictures=args.pictures, n_points=args.points, seed=args.seed)
    except TorchsymError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
