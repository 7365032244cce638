"""Pictures of PointSymm results: a d-dimensional point set with its mirror plane, and the
symmetry axis of an image's corner points (thesis Ch. 7)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.image.pointsymm_axis import ImageAxisResult
from torchsym.pointset.solver import PointSymmResult
from torchsym.viz import artifact_writer

__all__ = ["plot_image_axis", "plot_point_symm", "symmetry_frame"]

_SIDE = ("#d95f02", "#1b76b4")  # the two sides of the plane
_ON_PLANE = "#1a9850"
_UNMATCHED = "#9a9a9a"
_PLANE = "#222222"


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def symmetry_frame(points: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """``(N, 3)`` coordinates in the plane's own frame: the signed distance to the plane, then
    the first two principal axes of the points projected onto the plane (PCA), for any ``D >= 2``
    (the third column is 0 when ``D = 2``)."""
    dist = points @ normal + offset  # (N,)
    proj = points - np.outer(dist, normal)  # (N, D) on the plane
    centred = proj - proj.mean(0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    axes = vt[:2] - np.outer(vt[:2] @ normal, normal)  # in-plane principal directions
    cols = [dist]
    for a in axes:
        length = np.linalg.norm(a)
        cols.append(centred @ (a / length) if length > 1e-12 else np.zeros(len(points)))
    while len(cols) < 3:
        cols.append(np.zeros(len(points)))
    return np.stack(cols[:3], 1)


def _pairs(perm: np.ndarray, max_pairs: int) -> np.ndarray:
    """``(P, 2)`` distinct mirror pairs ``i < perm[i]``, at most ``max_pairs`` spread evenly."""
    i = np.nonzero(perm > np.arange(len(perm)))[0]
    pairs = np.stack([i, perm[i]], 1)
    if len(pairs) > max_pairs:
        pairs = pairs[np.linspace(0, len(pairs) - 1, max_pairs).astype(int)]
    return pairs


def _classes(coords: np.ndarray, matched: np.ndarray, on_plane: np.ndarray) -> list[tuple[np.ndarray, str, str, str]]:
    """``(mask, colour, marker, label)`` of each class of point: the two sides, on the plane, unmatched."""
    side = coords[:, 0] >= 0
    return [
        (matched & ~on_plane & side, _SIDE[0], "o", "matched, + side"),
        (matched & ~on_plane & ~side, _SIDE[1], "o", "matched, - side"),
        (on_plane, _ON_PLANE, "D", "its own mirror"),
        (~matched, _UNMATCHED, "x", "unmatched"),
    ]


def _edge_on(ax, coords: np.ndarray, classes, pairs: np.ndarray, size: float) -> None:
    """The plane edge-on (a vertical line at 0): distance to the plane against the first in-plane axis."""
    for a, b in pairs:
        ax.plot(coords[[a, b], 0], coords[[a, b], 1], color="#555555", lw=0.6, alpha=0.5, zorder=1)
    for mask, colour, marker, label in classes:
        if mask.any():
            ax.scatter(coords[mask, 0], coords[mask, 1], s=size, c=colour, marker=marker, label=label, zorder=2, linewidths=1)
    ax.axvline(0.0, color=_PLANE, lw=2.0, label="mirror plane", zorder=3)
    span = np.abs(coords[:, 0]).max() * 1.08 or 1.0
    ax.set_xlim(-span, span)
    ax.set_xlabel("signed distance to the plane")
    ax.set_ylabel("in-plane principal axis 1")
    ax.set_title("plane edge-on: mirrors sit level across the line", fontsize=10)
    ax.grid(alpha=0.25)


def _view_3d(ax, coords: np.ndarray, classes, pairs: np.ndarray, size: float, labels: tuple[str, str, str]) -> None:
    """A 3-D view of ``coords`` with the plane ``coords[:, 0] = 0`` as a translucent square."""
    for a, b in pairs[:: max(1, len(pairs) // 50)]:  # fewer lines than the flat view: depth crowds them
        ax.plot(coords[[a, b], 0], coords[[a, b], 1], coords[[a, b], 2], color="#333333", lw=0.7, alpha=0.6)
    for mask, colour, marker, _ in classes:
        if mask.any():
            ax.scatter(coords[mask, 0], coords[mask, 1], coords[mask, 2], s=size * 0.7, c=colour, marker=marker, depthshade=False)
    lo, hi = coords[:, 1:].min(0), coords[:, 1:].max(0)
    pad = 0.05 * (hi - lo)
    yy, zz = np.meshgrid([lo[0] - pad[0], hi[0] + pad[0]], [lo[1] - pad[1], hi[1] + pad[1]])
    ax.plot_surface(np.zeros_like(yy), yy, zz, color="#888888", alpha=0.25, shade=False)
    ax.set_xlabel(labels[0], fontsize=8)
    ax.set_ylabel(labels[1], fontsize=8)
    ax.set_zlabel(labels[2], fontsize=8)
    ax.view_init(elev=18, azim=-60)
    ax.set_title("3-D view, the plane in grey", fontsize=10)


def plot_point_symm(points: Any, result: PointSymmResult, path: str | Path, *, max_points: int = 4000, max_pairs: int = 150) -> Path:
    """PNG of a PointSymm result on ``points (N, D)``: the plane edge-on (distance to the plane
    against the first in-plane principal axis), and for ``D >= 3`` a 3-D view in the frame
    (normal, two in-plane principal axes); pairs joined, points coloured by side, on the
    plane, or unmatched (grey crosses). At most ``max_points`` points and ``max_pairs`` pairs drawn."""
    plt = _pyplot()
    p = torch.as_tensor(points).detach().cpu().double().numpy()
    n, d = p.shape
    normal = result.normal.detach().cpu().double().numpy()
    coords = symmetry_frame(p, normal, float(result.offset))
    perm = result.permutation.detach().cpu().numpy()
    shown = np.unique(np.linspace(0, n - 1, min(n, max_points)).astype(int))  # (M,) drawn points
    remap = np.full(n, -1)
    remap[shown] = np.arange(len(shown))
    both = np.where((perm >= 0) & (remap[np.clip(perm, 0, None)] >= 0), perm, -1)  # pairs with both ends drawn
    pairs = remap[_pairs(both, max_pairs)]  # (P, 2) in drawn indices
    sub = coords[shown]
    classes = _classes(sub, perm[shown] >= 0, perm[shown] == shown)
    size = float(np.clip(3000.0 / len(shown), 4.0, 36.0))
    fig = plt.figure(figsize=(12.5, 5.6) if d >= 3 else (7.0, 5.8), dpi=110)
    ax = fig.add_subplot(1, 2 if d >= 3 else 1, 1)
    _edge_on(ax, sub, classes, pairs, size)
    ax.legend(loc="best", fontsize=8, framealpha=0.85)
    if d >= 3:
        ax3 = fig.add_subplot(1, 2, 2, projection="3d")
        _view_3d(ax3, sub, classes, pairs, size, ("normal", "in-plane PC 1", "in-plane PC 2"))
    n_matched = int((perm >= 0).sum())
    fig.suptitle(
        f"PointSymm: {n} points in {d}-D, score {result.score:.3f}, {n_matched} matched, {n - n_matched} unmatched"
        + ("" if d <= 3 else " (PCA projection)"),
        fontsize=11,
    )
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return Path(path)


def _image_array(image: Any) -> np.ndarray:
    """``(H, W)`` or ``(H, W, 3)`` float image in [0, 1] for display."""
    img = torch.as_tensor(image).detach().cpu().float()
    while img.dim() > 3:
        img = img[0]
    if img.dim() == 3:
        img = img.permute(1, 2, 0) if img.shape[0] in (1, 3) else img
        img = img[..., 0] if img.shape[-1] == 1 else img
    arr = img.numpy()
    if arr.max() > 1.0:
        arr = arr / 255.0
    return np.clip(arr, 0.0, 1.0)


def plot_image_axis(image: Any, result: ImageAxisResult, path: str | Path, *, max_pairs: int = 60) -> Path:
    """PNG of the axis found by :func:`~torchsym.image.point_symm_image`: the image dimmed,
    the axis segment, its inlier corners joined to their mirrors (at most ``max_pairs``),
    the other corners as grey crosses."""
    plt = _pyplot()
    arr = _image_array(image)
    h, w = arr.shape[:2]
    fig, ax = plt.subplots(figsize=(8.0, 8.0 * h / w + 0.6), dpi=110)
    ax.imshow(arr, cmap="gray" if arr.ndim == 2 else None, vmin=0, vmax=1, alpha=0.75)
    corners = result.corners.detach().cpu().double().numpy()
    inl = result.inliers.detach().cpu().numpy().astype(bool)
    perm = result.permutation.detach().cpu().numpy()
    for a, b in _pairs(np.where(inl, perm, -1), max_pairs):
        ax.plot(corners[[a, b], 0], corners[[a, b], 1], color="#00e5ff", lw=1.2, alpha=0.9)
    if (~inl).any():
        ax.scatter(corners[~inl, 0], corners[~inl, 1], s=18, marker="x", c="#ff3030", linewidths=1.1, alpha=0.75, label="corner, no mirror")
    if inl.any():
        ax.scatter(corners[inl, 0], corners[inl, 1], s=30, c="#00e5ff", edgecolors="black", linewidths=0.6, label="corner with a mirror")
    seg = result.segment.detach().cpu().double().numpy()
    if np.isfinite(seg).all():
        ax.plot(seg[:, 0], seg[:, 1], color="black", lw=5.0, solid_capstyle="round")
        ax.plot(seg[:, 0], seg[:, 1], color="#ffd400", lw=3.0, solid_capstyle="round", label="symmetry axis")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_axis_off()
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower right", fontsize=8, framealpha=0.85)
    if np.isfinite(seg).all() and inl.any():
        head = f"PointSymm on Harris corners: score {result.score:.2f} ({int(inl.sum())} of {len(inl)} corners mirrored)"
    else:
        head = f"PointSymm on Harris corners: no symmetry axis found ({len(inl)} corners, none mirrored)"
    ax.set_title(head, fontsize=11)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return Path(path)


@artifact_writer(PointSymmResult)
def _write_point_symm(result: PointSymmResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    return [plot_point_symm(data, result, out_dir / f"{stem}_pointsymm.png")]


@artifact_writer(ImageAxisResult)
def _write_image_axis(result: ImageAxisResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    return [plot_image_axis(data, result, out_dir / f"{stem}_axis.png")]
