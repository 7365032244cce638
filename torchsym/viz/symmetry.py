"""Pictures of a shape's symmetry group: its mirror planes, its rotation axes with their
orders labelled, its axes of revolution (for :class:`~torchsym.pointcloud.SymmetryResult`
and for the BOP ``models_info.json`` export)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.pointcloud.reflection_planes.group import SymmetryGroup
from torchsym.pointcloud.symmetry.result import SymmetryResult
from torchsym.viz import artifact_writer
from torchsym.viz.planes import _COLORS, _points, _shrunk_quad, frame_view

__all__ = ["plot_symmetry_group", "write_symmetry"]


def plot_symmetry_group(data: Any, group: SymmetryGroup, path: str | Path, *, title: str = "", max_points: int = 6000) -> Path:
    """PNG: the shape (grey points, or a mesh's vertices) from two viewpoints with each of
    ``group``'s mirror planes as a translucent patch, each rotation axis as a coloured
    line labelled with its order (``n-fold``) and each axis of revolution in black
    (``inf``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    pts = _points(data)
    p = pts.numpy()
    idx = np.linspace(0, len(p) - 1, min(max_points, len(p))).astype(int)
    lo, hi = p.min(0), p.max(0)
    mid, half = 0.5 * (lo + hi), 0.6 * float((hi - lo).max())
    c = group.center.double()
    normals = []
    for t in group.reflections.double():
        w, v = torch.linalg.eigh(t[:3, :3])
        normals.append(v[:, 0])  # eigenvalue -1
    fig = plt.figure(figsize=(12, 6))
    for view, (elev, azim) in enumerate([(20, -60), (60, 30)]):
        ax = fig.add_subplot(1, 2, view + 1, projection="3d")
        ax.scatter(p[idx, 0], p[idx, 1], p[idx, 2], s=0.6, c="0.45", linewidths=0, alpha=0.5)
        for k, n in enumerate(normals[:12]):
            quad = _shrunk_quad(pts, n, -(n @ c))
            color = _COLORS[k % len(_COLORS)]
            ax.add_collection3d(Poly3DCollection([quad], facecolors=[(*color, 0.12)], edgecolors=[(*color, 0.6)], linewidths=0.8))
        for k in range(group.axes.shape[0]):
            d = group.axes[k].double().numpy()
            seg = np.stack([c.numpy() - half * d, c.numpy() + half * d])
            color = _COLORS[(k + 3) % len(_COLORS)]
            ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color=color, lw=2.0)
            ax.text(*seg[1], f"{int(group.orders[k])}-fold", color=color, fontsize=10, fontweight="bold")
        for a in range(group.continuous_axes.shape[0]):
            d, q = group.continuous_axes[a].double().numpy(), group.axis_points[a].double().numpy()
            seg = np.stack([q - half * d, q + half * d])
            ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color="k", lw=2.5)
            ax.text(*seg[1], "inf", color="k", fontsize=11, fontweight="bold")
        frame_view(ax, mid, half, elev, azim)
    orders = sorted((int(o) for o in group.orders), reverse=True)
    fig.suptitle(
        (title + "\n" if title else "")
        + f"group of order {group.order}{'' if group.closed else ' (not closed)'}: {len(normals)} plane(s), "
        + f"axes {orders or 'none'}, {group.continuous_axes.shape[0]} axis/axes of revolution",
        fontsize=10,
    )
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


@artifact_writer(SymmetryResult)
def write_symmetry(result: SymmetryResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """``<stem>_symmetry.png`` (see :func:`plot_symmetry_group`) of ``result.group`` on
    its input ``data`` (a cloud ``(N, 3)`` or a mesh)."""
    return [plot_symmetry_group(data, result.group, Path(out_dir) / f"{stem}_symmetry.png")]
