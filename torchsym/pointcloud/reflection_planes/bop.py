"""BOP's ``models_info.json``: a model's extent and its symmetries, as the 6D pose
benchmarks store them (Hodan et al., BOP).

``symmetries_discrete`` lists the proper rotations that leave the model's look unchanged,
each a 4 x 4 transform in the model's units flattened row-major to 16 numbers;
``symmetries_continuous`` lists axes of revolution as ``{"axis": [3], "offset": [3]}``
(a point on the axis). Reflections are not rigid motions and are not listed.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.errors import InputFileError, InputValueError
from torchsym.pointcloud.reflection_planes.group import SymmetryGroup, check_group_args, group_from_generators

__all__ = ["bop_symmetries", "group_from_bop", "models_info_entry", "read_models_info", "write_models_info"]


def bop_symmetries(group: SymmetryGroup) -> dict[str, Any]:
    """The group's ``symmetries_discrete`` and ``symmetries_continuous`` fields (each left
    out when empty, as in BOP's files)."""
    out: dict[str, Any] = {}
    if group.rotations.shape[0]:
        out["symmetries_discrete"] = [[float(v) for v in t.reshape(-1)] for t in group.rotations.to(torch.float64)]
    if group.continuous_axes.shape[0]:
        out["symmetries_continuous"] = [
            {"axis": [float(v) for v in d], "offset": [float(v) for v in p]}
            for d, p in zip(group.continuous_axes.to(torch.float64), group.axis_points.to(torch.float64))
        ]
    return out


def models_info_entry(points: torch.Tensor, group: SymmetryGroup) -> dict[str, Any]:
    """One model's ``models_info.json`` entry: ``diameter`` (largest distance between two
    of ``points (N, 3)``, e.g. the mesh's vertices), ``min_x/y/z``, ``size_x/y/z`` and
    :func:`bop_symmetries`."""
    p = points.detach().to(torch.float64).cpu().numpy()
    lo, hi = p.min(0), p.max(0)
    entry: dict[str, Any] = {"diameter": _diameter(p)}
    for k, axis in enumerate("xyz"):
        entry[f"min_{axis}"] = float(lo[k])
    for k, axis in enumerate("xyz"):
        entry[f"size_{axis}"] = float(hi[k] - lo[k])
    entry.update(bop_symmetries(group))
    return entry


def _diameter(p: np.ndarray) -> float:
    """Largest pairwise distance of ``p (N, 3)``, over its convex hull's vertices (Qhull's
    joggle option ``QJ`` also takes flat and collinear sets)."""
    from scipy.spatial import ConvexHull, QhullError

    if p.shape[0] > 4:
        try:
            p = p[ConvexHull(p, qhull_options="QJ").vertices]  # (H, 3), H << N
        except QhullError:  # every point the same, or fewer than 4 distinct: any 2 of them
            p = np.unique(p, axis=0)
    best = 0.0
    for start in range(0, p.shape[0], 2048):
        d = np.linalg.norm(p[start : start + 2048, None, :] - p[None, :, :], axis=-1)
        best = max(best, float(d.max()))
    return best


def write_models_info(path: str | Path, entries: Mapping[int, Mapping[str, Any]]) -> Path:
    """Write ``{obj_id: entry}`` as ``models_info.json`` (object ids as strings, as BOP),
    atomically: to a temporary file beside ``path``, then renamed over it, so that a
    reader never sees half a file.

    Raises:
        InputValueError: an id that is not an integer, an entry that is not a mapping, a
            value JSON cannot hold or a NaN or infinite number (strict JSON has none:
            other readers refuse a bare ``NaN``).
        InputFileError: the folder does not exist or cannot be written, or ``path`` is a folder.
    """
    import os
    import tempfile

    path = Path(path)
    if not isinstance(entries, Mapping):
        raise InputValueError(f"entries: expected a mapping of object ids to entries, got {type(entries).__name__}")
    data = {}
    for k, v in entries.items():
        if isinstance(k, bool) or not isinstance(k, (int, np.integer, str)) or not str(k).lstrip("-").isdigit():
            raise InputValueError(f"entries: expected integer object ids, got {k!r}")
        if not isinstance(v, Mapping):
            raise InputValueError(f"entries[{k!r}]: expected a mapping, got {type(v).__name__}")
        data[str(int(k))] = dict(v)
    try:
        text = json.dumps(data, indent=2, allow_nan=False)
    except (ValueError, TypeError, RecursionError) as exc:
        raise InputValueError(f"entries: expected finite numbers, lists and strings only ({exc})") from None
    if path.is_dir():
        raise InputFileError(f"path: expected a file name, got the folder {str(path)!r}")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:100]}.", suffix=".tmp", dir=path.parent)
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except OSError as exc:
        raise InputFileError(f"path: cannot write {str(path)!r} ({exc.strerror or exc})") from None
    return path


def read_models_info(path: str | Path) -> dict[int, dict[str, Any]]:
    """Read a ``models_info.json``: ``{obj_id: entry}``.

    Raises:
        InputFileError: the file does not exist, is a folder or cannot be read.
        InputValueError: the file is not a JSON object of objects keyed by integer ids
            (nested too deeply for the JSON reader included).
    """
    try:
        text = Path(path).read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(f"path: cannot read a BOP models_info.json at {str(path)!r} ({exc})") from None
    try:
        data = json.loads(text)
        if not isinstance(data, dict) or not all(isinstance(v, dict) for v in data.values()):
            raise TypeError("not an object of objects")
        return {int(k): dict(v) for k, v in data.items()}
    except (ValueError, TypeError, AttributeError, RecursionError) as exc:
        raise InputValueError(f"path: expected a BOP models_info.json, got {str(path)!r} ({exc})") from None


def _numbers(value: Any, count: int, name: str) -> torch.Tensor:
    """``value`` as ``count`` finite float64 numbers, or a typed error naming it."""
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, (list, tuple)):
        raise InputValueError(f"{name}: expected a list of {count} numbers, got {type(value).__name__}")
    if len(value) != count or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise InputValueError(f"{name}: expected {count} numbers, got {str(value)[:80]}")
    t = torch.tensor([float(v) for v in value], dtype=torch.float64)
    if not bool(torch.isfinite(t).all()):
        raise InputValueError(f"{name}: expected finite numbers, got NaN or inf")
    return t


def group_from_bop(entry: Mapping[str, Any], *, tol: float = 0.05, max_order: int = 1000) -> SymmetryGroup:
    """The proper symmetry group of one ``models_info.json`` entry: its discrete rotations
    (closed under products) about their common fixed point, and its continuous axes.

    Two elements are one within ``tol`` (Frobenius), lowered to half the distance of the
    nearest generator from the identity, so that a 300-fold entry closes to 300 elements
    rather than merging neighbours.

    Raises:
        InputValueError: ``entry`` is not a mapping; a discrete symmetry is not 16 finite
            numbers of a rigid motion (a rotation, det +1, last row ``0 0 0 1``); a
            continuous one is not ``{"axis": 3 numbers, nonzero, "offset": 3 numbers}``;
            ``tol`` or ``max_order`` out of range.
    """
    max_order, tol = check_group_args(max_order, tol)
    if not isinstance(entry, Mapping):
        raise InputValueError(f"entry: expected a models_info.json entry (a mapping), got {type(entry).__name__}")
    discrete = entry.get("symmetries_discrete", [])
    continuous = entry.get("symmetries_continuous", [])
    for name, value in (("symmetries_discrete", discrete), ("symmetries_continuous", continuous)):
        if not isinstance(value, (list, tuple)):
            raise InputValueError(f"{name}: expected a list, got {type(value).__name__}")
    rots = []
    for k, flat in enumerate(discrete):
        t = _numbers(flat, 16, f"symmetries_discrete[{k}]").reshape(4, 4)
        if float((t[3] - torch.tensor([0.0, 0.0, 0.0, 1.0], dtype=torch.float64)).abs().max()) > 1e-6:
            raise InputValueError(f"symmetries_discrete[{k}]: expected a last row 0 0 0 1, got {t[3].tolist()}")
        if float((t[:3, :3] @ t[:3, :3].T - torch.eye(3, dtype=torch.float64)).norm()) > 1e-3:
            raise InputValueError(f"symmetries_discrete[{k}]: expected a rotation, got a non-orthogonal matrix")
        if float(torch.linalg.det(t[:3, :3])) < 0:
            raise InputValueError(f"symmetries_discrete[{k}]: expected a rotation, got a reflection (determinant -1)")
        rots.append(t)
    dirs, pts = [], []
    for k, c in enumerate(continuous):
        if not isinstance(c, Mapping) or "axis" not in c or "offset" not in c:
            raise InputValueError(f"symmetries_continuous[{k}]: expected {{'axis': [3], 'offset': [3]}}, got {str(c)[:80]}")
        d = _numbers(c["axis"], 3, f"symmetries_continuous[{k}].axis")
        if float(d.norm()) < 1e-12:
            raise InputValueError(f"symmetries_continuous[{k}].axis: expected a nonzero direction, got {d.tolist()}")
        dirs.append(d / d.norm())
        pts.append(_numbers(c["offset"], 3, f"symmetries_continuous[{k}].offset"))
    dirs_t = torch.stack(dirs) if dirs else torch.zeros(0, 3, dtype=torch.float64)
    pts_t = torch.stack(pts) if pts else torch.zeros(0, 3, dtype=torch.float64)
    center = _fixed_point(rots, dirs_t, pts_t)
    gens = torch.stack([t[:3, :3] for t in rots]) if rots else torch.zeros(0, 3, 3, dtype=torch.float64)
    gap = (gens - torch.eye(3, dtype=torch.float64)).flatten(1).norm(dim=1)
    gap = gap[gap > 1e-9]
    if gap.numel():
        tol = min(tol, 0.5 * float(gap.min()))
    return group_from_generators(gens, center, continuous_axes=dirs_t, axis_points=pts_t, max_order=max_order, tol=tol)


def _fixed_point(rots: list[torch.Tensor], dirs: torch.Tensor, pts: torch.Tensor) -> torch.Tensor:
    """The least-squares point fixed by every rotation ``(I - R) x = t`` and on every axis."""
    rows, rhs = [], []
    for t in rots:
        rows.append(torch.eye(3, dtype=torch.float64) - t[:3, :3])
        rhs.append(t[:3, 3])
    for d, p in zip(dirs, pts):
        proj = torch.eye(3, dtype=torch.float64) - torch.outer(d, d)
        rows.append(proj)
        rhs.append(proj @ p)
    if not rows:
        return torch.zeros(3, dtype=torch.float64)
    return torch.linalg.pinv(torch.cat(rows), rtol=1e-2) @ torch.cat(rhs)
