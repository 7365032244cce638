"""Pictures of a detected reflection plane on its point cloud."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.io.write import write_ply
from torchsym.pointcloud.reflection_plane import ReflectionPlaneResult
from torchsym.viz import artifact_writer

__all__ = ["plane_quad", "plot_reflection_plane", "reflection_plane_ply", "write_reflection_plane"]


def plane_quad(points: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor) -> np.ndarray:
    """``(4, 3)`` corners of a square patch of the plane covering the cloud's projection."""
    p = points.detach().double().cpu().numpy()
    n = normal.detach().double().cpu().numpy()
    b = float(offset)
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, a)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    proj = p - np.outer(p @ n + b, n)
    cu, cv = proj @ u, proj @ v
    c0 = proj.mean(0)
    hu = 0.6 * (cu.max() - cu.min())
    hv = 0.6 * (cv.max() - cv.min())
    c0 = c0 + u * (0.5 * (cu.max() + cu.min()) - c0 @ u) + v * (0.5 * (cv.max() + cv.min()) - c0 @ v)
    return np.stack([c0 - hu * u - hv * v, c0 + hu * u - hv * v, c0 + hu * u + hv * v, c0 - hu * u + hv * v])


def _side_colors(points: torch.Tensor, result: Any) -> np.ndarray:
    p = points.detach().double().cpu().numpy()
    side = p @ result.normal.double().cpu().numpy() + float(result.offset)
    inl = result.inliers.cpu().numpy()
    col = np.where((side >= 0)[:, None], [[0.85, 0.33, 0.10]], [[0.0, 0.45, 0.74]])
    col[~inl] = [0.6, 0.6, 0.6]
    return col


def _signed(axis: np.ndarray) -> np.ndarray:
    """``axis (3,)`` made unit and signed so its largest coordinate is positive: the file's
    ``+y`` stays up in a picture when ``axis`` is near ``y`` (the same cloud always looks the same)."""
    axis = axis / max(float(np.linalg.norm(axis)), np.finfo(float).tiny)
    return axis * (1.0 if axis[np.argmax(np.abs(axis))] >= 0 else -1.0)


def reflection_plane_ply(points: torch.Tensor, result: Any, path: str | Path, *, max_pairs: int = 400) -> Path:
    """PLY: points coloured by side (grey: no mirror found), the plane as two triangles,
    and up to ``max_pairs`` mirror pairs as edges (open in MeshLab or CloudCompare)."""
    pts = points.detach().cpu().double()
    quad = torch.from_numpy(plane_quad(pts, result.normal, result.offset))
    verts = torch.cat([pts, quad])
    colors = np.concatenate([_side_colors(pts, result), np.full((4, 3), 0.9)])
    n = pts.shape[0]
    faces = torch.tensor([[n, n + 1, n + 2], [n, n + 2, n + 3]])
    pairs = result.pairs
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    if pairs.shape[0] > max_pairs:
        pairs = pairs[torch.linspace(0, pairs.shape[0] - 1, max_pairs).long()]
    return write_ply(path, verts, colors=colors, faces=faces, edges=pairs)


def plot_reflection_plane(
    points: torch.Tensor, result: Any, path: str | Path, *, max_points: int = 8000, max_pairs: int = 80, title: str = ""
) -> Path:
    """PNG with three views in the plane's own frame: two with the plane edge-on (a
    vertical line, so the two sides can be compared by eye) and one looking along the
    normal. Points are coloured by side (grey: no mirror found); black segments join a
    few mirror pairs. The title starts with ``title`` (the file) and says when no pair was found."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = points.detach().cpu().double().numpy()
    n = result.normal.detach().cpu().double().numpy()
    b = float(result.offset)
    col = _side_colors(points, result)
    proj = p - np.outer(p @ n + b, n)
    _, _, vt = np.linalg.svd(proj - proj.mean(0), full_matrices=False)
    e2 = _signed(vt[0] - (vt[0] @ n) * n)
    e3 = _signed(np.cross(n, e2))
    coords = np.stack([p @ n + b, p @ e2, p @ e3], 1)  # (N, 3): distance to plane, two in-plane axes
    idx = np.linspace(0, len(p) - 1, min(max_points, len(p))).astype(int)
    pairs = result.pairs.cpu().numpy()
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    if len(pairs) > max_pairs:
        pairs = pairs[np.linspace(0, len(pairs) - 1, max_pairs).astype(int)]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.8))
    views = [(0, 2, "plane edge-on, looking along the long axis", True), (0, 1, "plane edge-on, turned 90 degrees", True), (1, 2, "looking along the plane's normal", False)]
    for ax, (i, j, label, edge) in zip(axes, views):
        ax.scatter(coords[idx, i], coords[idx, j], c=col[idx], s=float(np.clip(3000.0 / len(idx), 1.2, 16.0)), linewidths=0)
        for a_, b_ in pairs:
            ax.plot(coords[[a_, b_], i], coords[[a_, b_], j], color="k", lw=0.4, alpha=0.5)
        if edge:
            ax.axvline(0.0, color="#2ca02c", lw=2, label="detected plane")
            ax.legend(loc="lower right", fontsize=8)
        ax.set_title(label, fontsize=10)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xticks([])
        ax.set_yticks([])
    n_pairs = int((result.pairs[:, 0] != result.pairs[:, 1]).sum()) if len(result.pairs) else 0
    found = f"{n_pairs} mirror pairs, {len(result.pairs) - n_pairs} points on the plane" if n_pairs else "no mirror pairs found"
    key = (
        "orange / blue: the two sides, grey: no mirror; black lines join a sample of pairs"
        if n_pairs
        else "the plane is drawn, no point is matched across it"
    )
    fig.suptitle(
        f"{title + ': ' if title else ''}{len(p)} point{'s' if len(p) != 1 else ''}, symmetry score {result.score:.2f}; {found}\n"
        f"{key}; plane n = ({n[0]:.3f}, {n[1]:.3f}, {n[2]:.3f}), offset {b:.3f}",
        fontsize=10,
    )
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


@artifact_writer(ReflectionPlaneResult)
def write_reflection_plane(result: ReflectionPlaneResult, data: torch.Tensor, out_dir: Path, stem: str) -> list[Path]:
    """``<stem>_plane.ply`` (see :func:`reflection_plane_ply`) and ``<stem>_plane.png``
    (see :func:`plot_reflection_plane`) of ``result`` on the cloud ``data (N, 3)``."""
    out_dir = Path(out_dir)
    return [
        reflection_plane_ply(data, result, out_dir / f"{stem}_plane.ply"),
        plot_reflection_plane(data, result, out_dir / f"{stem}_plane.png", title=stem),
    ]
