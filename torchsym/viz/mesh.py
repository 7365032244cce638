"""Pictures of an intrinsic symmetry map on its mesh (thesis Ch. 6).

A vertex and its mirror partner share a colour; thin lines join a sample of partners
across the symmetry; vertices whose partner is inconsistent (the map of the map lands far
from the vertex) are dark grey, vertices without a partner light grey. The shape is drawn
in a fixed orientation (:func:`mesh_frame`) so the same file always looks the same.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from torchsym.geometry.mesh import Mesh
from torchsym.io.write import write_mesh
from torchsym.mesh.intrinsic.result import IntrinsicSymmetryResult
from torchsym.viz import artifact_writer

__all__ = ["mesh_frame", "partner_residual", "plot_mesh_symmetry", "symmetry_colors", "write_mesh_symmetry"]

_NO_PARTNER = 0.82  # light grey
_POOR = 0.32  # dark grey
_AXES = "xyz"


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
    box = mid[ok] if ok.any() else v
    lo, hi = box.min(axis=0), box.max(axis=0)
    rgb = (mid - lo) / np.maximum(hi - lo, np.finfo(float).tiny)  # (V, 3)
    rgb = 0.15 + 0.7 * np.clip(rgb, 0.0, 1.0)
    rgb[~ok] = 0.5
    return rgb


def partner_residual(vertices: np.ndarray, vertex_map: np.ndarray, faces: np.ndarray | None = None) -> np.ndarray:
    """``(V,)`` how far the map ``T`` is from a symmetry at each vertex, in units of ``vertices``.

    The larger of the involution residual ``|x_v - x_T(T(v))|`` (a symmetry's map is its own
    inverse) and, with ``faces (F, 3)``, the tear ``max_u |x_T(u) - x_T(v)| - |x_u - x_v|``
    over the neighbours ``u`` of ``v`` (an isometry keeps neighbours' partners together);
    ``inf`` where ``T(v)`` or ``T(T(v))`` is missing (``-1``).
    """
    v = np.asarray(vertices, dtype=np.float64)
    vmap = np.asarray(vertex_map)
    res = np.full(len(v), np.inf)
    ok = vmap >= 0
    back = np.full(len(v), -1)
    back[ok] = vmap[vmap[ok]]
    both = back >= 0
    res[both] = np.linalg.norm(v[both] - v[back[both]], axis=1)
    if faces is not None and len(faces):
        f = np.asarray(faces).reshape(-1, 3)
        e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])  # (3F, 2)
        e = e[ok[e[:, 0]] & ok[e[:, 1]]]
        tear = np.linalg.norm(v[vmap[e[:, 0]]] - v[vmap[e[:, 1]]], axis=1) - np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
        worst = np.zeros(len(v))
        np.maximum.at(worst, e[:, 0], tear)
        np.maximum.at(worst, e[:, 1], tear)
        res[both] = np.maximum(res[both], worst[both])
    return res


def _vertex_map(vertex_map: Any, n_vertices: int) -> np.ndarray:
    """``(V,)`` int64 map; a map of another mesh (wrong length or index) as no map (all ``-1``)."""
    vmap = np.asarray(vertex_map).reshape(-1).astype(np.int64)
    if vmap.shape[0] != n_vertices or (vmap >= n_vertices).any():
        return np.full(n_vertices, -1)
    return np.where(vmap < 0, -1, vmap)


def _mesh_area(v: np.ndarray, f: np.ndarray) -> float:
    if len(f) == 0:
        return 0.0
    return float(0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum())


def mesh_frame(vertices: np.ndarray, vertex_map: np.ndarray) -> tuple[np.ndarray, np.ndarray, str]:
    """The picture's ``up (3,)`` and viewing direction ``view (3,)``, and the view's name.

    The mirror normal ``n`` is the principal axis of the displacements ``x_v - x_T(v)``.
    Up is the file's longest coordinate axis (x, y or z) within 30 degrees of the mirror
    plane, in its positive direction (a standing body drawn upright when its file is);
    when no file axis lies near the plane, the plane's longest principal direction, signed
    so its largest coordinate is positive. The view looks along ``up x n``, so the two
    halves of the symmetry sit side by side. Without partners, ``n`` is the shape's least
    principal axis.
    """
    v = np.asarray(vertices, dtype=np.float64)
    centred = v - v.mean(axis=0)
    ok = vertex_map >= 0
    moved = v[ok] - v[vertex_map[ok]]  # (M, 3)
    if ok.any() and np.linalg.norm(moved) > 0:
        normal = np.linalg.svd(moved, full_matrices=False)[2][0]
    else:
        normal = np.linalg.svd(centred, full_matrices=False)[2][-1]
    extent = v.max(axis=0) - v.min(axis=0)  # (3,)
    in_plane = np.abs(normal) < np.sin(np.radians(30.0))
    if in_plane.any():
        axis = int(np.argmax(np.where(in_plane, extent, -1.0)))
        up = np.eye(3)[axis]
    else:
        across = centred - np.outer(centred @ normal, normal)
        up = np.linalg.svd(across, full_matrices=False)[2][0]
        up = up * np.sign(up[np.argmax(np.abs(up))])
    up = up - (up @ normal) * normal
    up /= np.linalg.norm(up)
    view = np.cross(up, normal)
    view /= np.linalg.norm(view)
    # a stated sign for the view too: from the file's positive side of its nearest axis
    k = int(np.argmax(np.abs(view)))
    view = view * np.sign(view[k])
    return up, view, f"seen from {'+' if view[k] > 0 else '-'}{_AXES[k]}"


def _visible(xy: np.ndarray, depth: np.ndarray, radius: float) -> np.ndarray:
    """``(V,)`` bool: the vertex is (nearly) the nearest to the viewer among the vertices
    drawn around it (``depth`` grows towards the viewer): a depth buffer of cells of side
    ``radius``, each cell compared with the nearest depth in it and its 8 neighbours."""
    from scipy.ndimage import maximum_filter

    cell = np.floor((xy - xy.min(axis=0)) / max(radius, np.finfo(float).tiny)).astype(np.int64)  # (V, 2)
    front = np.full(tuple(cell.max(axis=0) + 1), -np.inf)
    np.maximum.at(front, (cell[:, 0], cell[:, 1]), depth)
    front = maximum_filter(front, size=3, mode="constant", cval=-np.inf)
    return depth >= front[cell[:, 0], cell[:, 1]] - radius


def _sample_pairs(xy: np.ndarray, candidates: np.ndarray, cells: int) -> np.ndarray:
    """At most one candidate vertex per cell of a ``cells x cells`` grid over ``xy``."""
    if len(candidates) == 0:
        return candidates
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    cell = np.floor((xy[candidates] - lo) / np.maximum(hi - lo, 1e-12) * (cells - 1e-9)).astype(int)
    _, first = np.unique(cell[:, 0] * cells + cell[:, 1], return_index=True)
    return candidates[np.sort(first)]


def _draw_view(pane, v, f, rgb, normals, up, view, vmap, good, tol, max_pairs) -> int:
    """One pane: faces far to near, shaded by their angle to the view; lines join a sample of
    visible good partners. Returns the number of lines drawn."""
    from matplotlib.collections import LineCollection, PolyCollection

    side = np.cross(up, view)  # screen x: keeps the picture unmirrored
    xy = np.stack([v @ side, v @ up], axis=1)  # (V, 2)
    depth = v @ view
    if len(f):
        colors = rgb[f].mean(axis=1)  # (F, 3)
        order = np.argsort(depth[f].mean(axis=1))  # far to near
        shade = 0.45 + 0.55 * np.abs(normals[order] @ view)[:, None]
        pane.add_collection(PolyCollection(xy[f[order]], facecolors=np.clip(colors[order] * shade, 0, 1), edgecolors="none"))
    else:
        pane.scatter(xy[:, 0], xy[:, 1], c=rgb, s=4)
    span = float(np.ptp(xy, axis=0).max()) if len(xy) > 1 else 1.0
    drawn = 0
    if good.any() and max_pairs > 0:
        seen = _visible(xy, depth, 0.015 * span)
        apart = np.zeros(len(v), bool)
        apart[good] = np.linalg.norm(v[good] - v[vmap[good]], axis=1) > 2 * tol
        cand = np.nonzero(good & apart & seen)[0]
        cand = cand[seen[vmap[cand]] & (xy[cand, 0] < xy[vmap[cand], 0])]  # both ends seen, left end first
        cells = max(2, int(np.sqrt(max_pairs) * 2.2))
        pick = _sample_pairs(xy, cand, cells)[:max_pairs]
        if len(pick):
            segs = np.stack([xy[pick], xy[vmap[pick]]], axis=1)  # (P, 2, 2)
            pane.add_collection(LineCollection(segs, colors="black", linewidths=0.7, alpha=0.75))
            ends = segs.reshape(-1, 2)
            pane.scatter(ends[:, 0], ends[:, 1], s=6, c="black", linewidths=0)
            drawn = len(pick)
    if len(xy):
        pad = 0.03 * span
        pane.set_xlim(xy[:, 0].min() - pad, xy[:, 0].max() + pad)
        pane.set_ylim(xy[:, 1].min() - pad, xy[:, 1].max() + pad)
    pane.set_aspect("equal")
    pane.set_axis_off()
    return drawn


def plot_mesh_symmetry(
    mesh: Mesh, vertex_map: np.ndarray, path: str | Path, *, title: str = "", score: float | None = None, max_pairs: int = 40
) -> Path:
    """PNG of a symmetry map ``vertex_map (V,)`` (``-1``: no partner) on ``mesh``.

    Two views from opposite sides (:func:`mesh_frame`), faces coloured by
    :func:`symmetry_colors` and shaded by their angle to the view, drawn far to near; up to
    ``max_pairs`` visible partners joined by lines in each; vertices whose partner is
    inconsistent (:func:`partner_residual` above ``sqrt(area / 20 pi)``, the tolerance of
    the landmark protocol, thesis Sec. 6.3) dark grey, without a partner light grey. The
    title gives ``title`` (the file), ``score`` when given and the share of consistent
    partners; a caption says what the colours mean (matplotlib, Agg).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    v = mesh.vertices.detach().cpu().double().numpy()  # (V, 3)
    f = mesh.faces.detach().cpu().numpy().reshape(-1, 3)  # (F, 3)
    vmap = _vertex_map(vertex_map, v.shape[0])
    tol = np.sqrt(_mesh_area(v, f) / (20.0 * np.pi))
    residual = partner_residual(v, vmap, f)
    good = residual <= tol  # (V,)
    has = vmap >= 0
    rgb = symmetry_colors(v, np.where(good, vmap, -1))
    rgb[has & ~good] = _POOR
    rgb[~has] = _NO_PARTNER
    normals = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]) if len(f) else np.zeros((0, 3))
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), np.finfo(float).tiny)  # (F, 3)
    fig, panes = plt.subplots(1, 2, figsize=(10, 6.6), dpi=100)
    if len(v) == 0:
        for pane in panes:
            pane.set_axis_off()
        fig.text(0.5, 0.5, "empty mesh: nothing to draw", ha="center", va="center", fontsize=14)
    else:
        up, view, name = mesh_frame(v, np.where(good, vmap, -1))
        for pane, d, label in ((panes[0], view, name), (panes[1], -view, name.replace("+", "*").replace("-", "+").replace("*", "-"))):
            n = _draw_view(pane, v, f, rgb, normals, up, d, vmap, good, tol, max_pairs)
            pane.set_title(f"{label}" + (f" ({n} partners joined)" if n else ""), fontsize=10)
    share = float(good.mean()) if len(v) else 0.0
    head = title or "mesh"
    if score is not None:
        head += f": symmetry score {score:.2f}"
    if not has.any():
        head += " (no vertex has a mirror partner)"
    else:
        head += f", {100 * share:.0f} % of vertices with a consistent partner"
    fig.suptitle(head, fontsize=12)
    caption = (
        "A vertex and its mirror partner share a colour; black lines join a sample of partners.\n"
        f"Dark grey: partner inconsistent (the partner's partner, or a neighbour's partner, lands over sqrt(area / 20 pi) = {tol:.3g} away); "
        "light grey: no partner."
    )
    fig.text(0.5, 0.015, caption, ha="center", va="bottom", fontsize=9, color="#333333")
    fig.tight_layout(rect=(0, 0.07, 1, 0.96))
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path


@artifact_writer(IntrinsicSymmetryResult)
def write_mesh_symmetry(result: IntrinsicSymmetryResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """``{stem}_symmetry.ply`` and ``{stem}_symmetry.png`` (see :func:`plot_mesh_symmetry`)
    and ``{stem}_map.npy``."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    vmap = result.map.detach().cpu().numpy()
    paths = []
    if isinstance(data, Mesh):
        colors = symmetry_colors(data.vertices.detach().cpu().double().numpy(), _vertex_map(vmap, data.vertices.shape[0]))
        paths.append(write_mesh(out_dir / f"{stem}_symmetry.ply", data, colors=colors))
        score = getattr(result, "score", None)
        paths.append(plot_mesh_symmetry(data, vmap, out_dir / f"{stem}_symmetry.png", title=stem, score=None if score is None else float(score)))
    npy = out_dir / f"{stem}_map.npy"
    np.save(npy, vmap)
    paths.append(npy)
    return paths
