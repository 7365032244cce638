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

from torchsym.errors import InputValueError
from torchsym.pointcloud.reflection_planes.group import SymmetryGroup, group_from_generators, rotation_axis_angle

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
    """Largest pairwise distance of ``p (N, 3)``, over its convex hull's vertices."""
    if p.shape[0] > 4:
        try:
            from scipy.spatial import ConvexHull

            p = p[ConvexHull(p).vertices]
        except Exception:  # flat or degenerate sets: every point
            pass
    best = 0.0
    for start in range(0, p.shape[0], 2048):
        d = np.linalg.norm(p[start : start + 2048, None, :] - p[None, :, :], axis=-1)
        best = max(best, float(d.max()))
    return best


def write_models_info(path: str | Path, entries: Mapping[int, Mapping[str, Any]]) -> Path:
    """Write ``{obj_id: entry}`` as ``models_info.json`` (object ids as strings, as BOP)."""
    path = Path(path)
    path.write_text(json.dumps({str(int(k)): dict(v) for k, v in entries.items()}, indent=2))
    return path


def read_models_info(path: str | Path) -> dict[int, dict[str, Any]]:
    """Read a ``models_info.json``: ``{obj_id: entry}``.

    Raises:
        InputValueError: the file is not a JSON object of objects keyed by integer ids.
    """
    try:
        data = json.loads(Path(path).read_text())
        return {int(k): dict(v) for k, v in data.items()}
    except (ValueError, TypeError, AttributeError) as exc:
        raise InputValueError(f"path: expected a BOP models_info.json, got {str(path)!r} ({exc})") from None


def group_from_bop(entry: Mapping[str, Any], *, tol: float = 0.05) -> SymmetryGroup:
    """The proper symmetry group of one ``models_info.json`` entry: its discrete rotations
    (closed under products) about their common fixed point, and its continuous axes.

    Raises:
        InputValueError: a discrete symmetry is not 16 numbers of a rotation.
    """
    rots = []
    for k, flat in enumerate(entry.get("symmetries_discrete", [])):
        t = torch.tensor(flat, dtype=torch.float64)
        if t.numel() != 16:
            raise InputValueError(f"symmetries_discrete[{k}]: expected 16 numbers, got {t.numel()}")
        t = t.reshape(4, 4)
        if float((t[:3, :3] @ t[:3, :3].T - torch.eye(3, dtype=torch.float64)).norm()) > 1e-3:
            raise InputValueError(f"symmetries_discrete[{k}]: expected a rotation, got a non-orthogonal matrix")
        rots.append(t)
    cont = entry.get("symmetries_continuous", [])
    dirs = torch.tensor([c["axis"] for c in cont], dtype=torch.float64).reshape(-1, 3)
    pts = torch.tensor([c["offset"] for c in cont], dtype=torch.float64).reshape(-1, 3)
    if dirs.shape[0]:
        dirs = dirs / dirs.norm(dim=1, keepdim=True)
    center = _fixed_point(rots, dirs, pts)
    gens = torch.stack([t[:3, :3] for t in rots]) if rots else torch.zeros(0, 3, 3, dtype=torch.float64)
    return group_from_generators(gens, center, continuous_axes=dirs, axis_points=pts, tol=tol)


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
