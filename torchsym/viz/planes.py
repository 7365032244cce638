"""Pictures of every reflection plane of a shape: each plane drawn on the shape,
numbered by rank, and its axes of revolution."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.io.write import write_ply
from torchsym.pointcloud.reflection_planes import ReflectionPlanesResult
from torchsym.viz import artifact_writer
from torchsym.viz.pointcloud import plane_quad

__all__ = ["frame_view", "plot_reflection_planes", "reflection_planes_ply", "write_reflection_planes"]

_COLORS = np.array(
    [[0.12, 0.47, 0.71], [1.0, 0.5, 0.05], [0.17, 0.63, 0.17], [0.84, 0.15, 0.16], [0.58, 0.4, 0.74],
     [0.55, 0.34, 0.29], [0.89, 0.47, 0.76], [0.5, 0.5, 0.5], [0.74, 0.74, 0.13], [0.09, 0.75, 0.81]]
)


def _points(data: Any) -> torch.Tensor:
    """``(N, 3)`` points of the input: a cloud, or a mesh's vertices."""
    pts = data.vertices if hasattr(data, "vertices") else data
    return torch.as_tensor(pts).detach().cpu().double()[:, :3]


def _shrunk_quad(points: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor) -> np.ndarray:
    """The plane's patch over the cloud, at 85 % of :func:`plane_quad`'s size (which pads by 20 %)."""
    quad = plane_quad(points, normal, offset)
    return quad.mean(0) + 0.85 * (quad - quad.mean(0)) / 1.2


def frame_view(ax: Any, mid: np.ndarray, half: float, elev: float, azim: float) -> None:
    """A 3D ``ax`` looking at the cube of half-width ``half`` about ``mid`` from
    ``(elev, azim)``, equal aspect, no ticks."""
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_zticks([])


def reflection_planes_ply(data: Any, result: ReflectionPlanesResult, path: str | Path) -> Path:
    """PLY: the points in grey, each plane as two triangles in its rank's colour, each axis
    of revolution as an edge (open in MeshLab or CloudCompare)."""
    pts = _points(data)
    verts, colors, faces, edges = [pts], [np.full((pts.shape[0], 3), 0.7)], [], []
    n0 = pts.shape[0]
    for p in range(result.n_planes):
        quad = torch.from_numpy(_shrunk_quad(pts, result.normals[p].double(), result.offsets[p].double()))
        base = n0 + 4 * p
        verts.append(quad)
        colors.append(np.tile(_COLORS[p % len(_COLORS)], (4, 1)))
        faces += [[base, base + 1, base + 2], [base, base + 2, base + 3]]
    base = n0 + 4 * result.n_planes
    half = 0.6 * float((pts.max(0).values - pts.min(0).values).norm())
    for a in range(result.continuous_axes.shape[0]):
        d, c = result.continuous_axes[a].double(), result.axis_points[a].double()
        verts.append(torch.stack([c - half * d, c + half * d]))
        colors.append(np.zeros((2, 3)))
        edges.append([base + 2 * a, base + 2 * a + 1])
    return write_ply(
        path, torch.cat(verts), colors=np.concatenate(colors),
        faces=torch.tensor(faces, dtype=torch.int64) if faces else None,
        edges=torch.tensor(edges, dtype=torch.int64) if edges else None,
    )


def plot_reflection_planes(data: Any, result: ReflectionPlanesResult, path: str | Path, *, max_points: int = 6000) -> Path:
    """PNG: the shape (grey points) from two viewpoints with every plane as a translucent
    patch in its own colour, numbered by rank (1: the best) at the patch's corner, and
    each axis of revolution as a black line; the legend gives each plane's score and
    distance ratio."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    pts = _points(data)
    p = pts.numpy()
    idx = np.linspace(0, len(p) - 1, min(max_points, len(p))).astype(int)
    lo, hi = p.min(0), p.max(0)
    mid, half = 0.5 * (lo + hi), 0.6 * float((hi - lo).max())
    fig = plt.figure(figsize=(12, 6))
    for v, (elev, azim) in enumerate([(20, -60), (60, 30)]):
        ax = fig.add_subplot(1, 2, v + 1, projection="3d")
        ax.scatter(p[idx, 0], p[idx, 1], p[idx, 2], s=0.6, c="0.45", linewidths=0, alpha=0.6)
        for k in range(result.n_planes):
            quad = _shrunk_quad(pts, result.normals[k].double(), result.offsets[k].double())
            color = _COLORS[k % len(_COLORS)]
            ax.add_collection3d(Poly3DCollection([quad], facecolors=[(*color, 0.22)], edgecolors=[(*color, 0.9)], linewidths=1.2))
            label = quad[2] + 0.05 * (quad[2] - quad.mean(0))
            ax.text(*label, str(k + 1), color=color, fontsize=12, fontweight="bold")
        for a in range(result.continuous_axes.shape[0]):
            d, c = result.continuous_axes[a].double().numpy(), result.axis_points[a].double().numpy()
            seg = np.stack([c - half * d, c + half * d])
            ax.plot(seg[:, 0], seg[:, 1], seg[:, 2], color="k", lw=2.5)
            ax.text(*seg[1], f"axis {a + 1}", color="k", fontsize=10)
        frame_view(ax, mid, half, elev, azim)
    lines = [
        f"{k + 1}: score {float(result.scores[k]):.2f}, ratio {float(result.ratios[k]):.2f}" for k in range(result.n_planes)
    ]
    lines += [f"axis {a + 1}: revolution (ratio {float(result.axis_ratios[a]):.2f})" for a in range(result.continuous_axes.shape[0])]
    fig.suptitle(
        f"{result.n_planes} reflection plane(s), {result.continuous_axes.shape[0]} axis/axes of revolution, best first"
        + ("".join(("\n" if i % 4 == 0 else "; ") + t for i, t in enumerate(lines[:12])) if lines else "\nno symmetry found"),
        fontsize=10,
    )
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


@artifact_writer(ReflectionPlanesResult)
def write_reflection_planes(result: ReflectionPlanesResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """``<stem>_planes.ply`` (see :func:`reflection_planes_ply`) and ``<stem>_planes.png``
    (see :func:`plot_reflection_planes`) of ``result`` on its input ``data`` (a cloud
    ``(N, 3)`` or a mesh)."""
    out_dir = Path(out_dir)
    return [
        reflection_planes_ply(data, result, out_dir / f"{stem}_planes.ply"),
        plot_reflection_planes(data, result, out_dir / f"{stem}_planes.png"),
    ]
