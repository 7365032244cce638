"""Pictures of an intrinsic symmetry map on its mesh: symmetric vertices share a colour."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from torchsym.geometry.mesh import Mesh
from torchsym.io.write import write_mesh
from torchsym.mesh.intrinsic.result import IntrinsicSymmetryResult
from torchsym.viz import artifact_writer

__all__ = ["plot_mesh_symmetry", "symmetry_colors", "write_mesh_symmetry"]


def symmetry_colors(vertices: np.ndarray, vertex_map: np.ndarray) -> np.ndarray:
    """Per-vertex RGB ``(V, 3)`` in [0, 1], the same for a vertex and its symmetric vertex.

    The colour is the position averaged with the mirror's, scaled to the box of those
    midpoints; vertices without a mirror (``vertex_map == -1``) are grey.

    Args:
        vertices: ``(V, 3)`` positions.
        vertex_map: ``(V,)`` int symmetric vertex of each vertex, ``-1`` for none.
    """
    v = np.asarray(vertices, dtype=np.float64)
    ok = vertex_map >= 0  # (V,)
    mid = v.copy()
    mid[ok] = 0.5 * (v[ok] + v[vertex_map[ok]])  # (V, 3)
    lo, hi = mid[ok].min(axis=0) if ok.any() else v.min(axis=0), mid[ok].max(axis=0) if ok.any() else v.max(axis=0)
    rgb = (mid - lo) / np.maximum(hi - lo, np.finfo(float).tiny)  # (V, 3)
    rgb = 0.15 + 0.7 * np.clip(rgb, 0.0, 1.0)
    rgb[~ok] = 0.5
    return rgb


def _views(v: np.ndarray, vertex_map: np.ndarray) -> tuple[np.ndarray, list[tuple[str, np.ndarray]]]:
    """The picture's up direction ``(3,)`` and two opposite viewing directions, each seeing
    both halves of the symmetry side by side.

    The mirror direction is the principal axis of the displacements ``v - v[map]`` (the
    normal of the mirror plane of an extrinsic symmetry); up is the widest spread of ``v``
    across it, and the views look along the third direction, from the front and the back.
    Without a mapped vertex, the views look along the least principal axis of ``v``.
    """
    centred = v - v.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)  # rows: axes by decreasing spread
    ok = vertex_map >= 0
    moved = v[ok] - v[vertex_map[ok]]  # (M, 3)
    if not ok.any() or np.linalg.norm(moved) == 0:
        return vt[0], [("one side", vt[2]), ("the other side", -vt[2])]
    mirror = np.linalg.svd(moved, full_matrices=False)[2][0]  # (3,)
    across = centred - np.outer(centred @ mirror, mirror)
    up = np.linalg.svd(across, full_matrices=False)[2][0]
    up = up - (up @ mirror) * mirror
    up /= np.linalg.norm(up)
    front = np.cross(mirror, up)
    return up, [("front", front), ("back", -front)]


def plot_mesh_symmetry(mesh: Mesh, vertex_map: np.ndarray, path: str | Path, *, title: str = "") -> Path:
    """PNG with two views of ``mesh`` (front and back across its symmetry, see :func:`_views`),
    faces coloured by :func:`symmetry_colors` of ``vertex_map (V,)`` and shaded by their
    angle to the view, drawn far to near (matplotlib, Agg)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    v = mesh.vertices.detach().cpu().double().numpy()  # (V, 3)
    f = mesh.faces.detach().cpu().numpy()  # (F, 3)
    colors = symmetry_colors(v, vertex_map)[f].mean(axis=1)  # (F, 3)
    normals = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), np.finfo(float).tiny)  # (F, 3)
    up, views = _views(v, vertex_map)
    fig, panes = plt.subplots(1, 2, figsize=(10, 6), dpi=110)
    for pane, (label, d) in zip(panes, views):
        side = np.cross(up, d)  # keeps the picture unmirrored from either side
        xy = np.stack([v @ side, v @ up], axis=1)  # (V, 2)
        order = np.argsort(v[f].mean(axis=1) @ d)  # far to near
        shade = 0.35 + 0.65 * np.abs(normals[order] @ d)[:, None]
        pane.add_collection(PolyCollection(xy[f[order]], facecolors=np.clip(colors[order] * shade, 0, 1), edgecolors="none"))
        pane.set_xlim(xy[:, 0].min(), xy[:, 0].max())
        pane.set_ylim(xy[:, 1].min(), xy[:, 1].max())
        pane.set_aspect("equal")
        pane.set_axis_off()
        pane.set_title(label)
    fig.suptitle(title or "intrinsic symmetry: symmetric vertices share a colour (grey: no partner)")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path


@artifact_writer(IntrinsicSymmetryResult)
def write_mesh_symmetry(result: IntrinsicSymmetryResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """``{stem}_symmetry.ply`` and ``{stem}_symmetry.png`` (symmetric vertices share a colour) and ``{stem}_map.npy``."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    vmap = result.map.detach().cpu().numpy()
    paths = []
    if isinstance(data, Mesh):
        colors = symmetry_colors(data.vertices.detach().cpu().double().numpy(), vmap)
        paths.append(write_mesh(out_dir / f"{stem}_symmetry.ply", data, colors=colors))
        paths.append(plot_mesh_symmetry(data, vmap, out_dir / f"{stem}_symmetry.png", title=f"{stem}: {result.hypothesis}"))
    npy = out_dir / f"{stem}_map.npy"
    np.save(npy, vmap)
    paths.append(npy)
    return paths
