"""Pictures of a multi-view plane: its trace in every photo, a 3D view, the model."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import numpy as np
import torch

from torchsym.multiview.result import MultiviewPlaneResult
from torchsym.multiview.views import as_views
from torchsym.viz import artifact_writer
from torchsym.viz.pointcloud import plane_quad

__all__ = ["draw_plane_in_photos", "plot_multiview_plane", "write_multiview_artifacts"]


def _photo(views: Any, name: str, index: int) -> np.ndarray | None:
    """The photo ``name`` as a BGR uint8 array (None when it cannot be found)."""
    v = as_views(views)
    if v.paths:
        by_name = dict(zip(v.names, v.paths))
        return cv2.imread(str(by_name[name])) if name in by_name else None
    names = v.names
    if name not in names:
        return None
    img = v.images[names.index(name)].detach().float().clamp(0, 1).cpu()
    img = img.expand(3, -1, -1) if img.shape[0] == 1 else img
    return (img.permute(1, 2, 0).numpy()[:, :, ::-1] * 255).round().astype(np.uint8)


def _project(result: MultiviewPlaneResult, cam: int, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates ``(N, 2)`` of world points ``x (N, 3)`` in camera ``cam`` and
    whether each lies in front of it."""
    r = result.cameras.rotations[cam].double().numpy()
    t = result.cameras.translations[cam].double().numpy()
    k = result.cameras.intrinsics[cam].double().numpy()
    c = x @ r.T + t
    uv = c @ k.T
    return uv[:, :2] / np.maximum(uv[:, 2:], 1e-9), c[:, 2] > 1e-6


def draw_plane_in_photos(
    result: MultiviewPlaneResult, views: Any, path: str | Path, *, max_photos: int = 8, max_pairs: int = 60, width: int = 640
) -> Path:
    """PNG: up to ``max_photos`` photos, each with the plane's patch over the supporting
    pairs drawn translucent, its outline, and up to ``max_pairs`` inlier pairs joined
    (green, ends in orange and blue); without a readable photo, a picture that says so."""
    pts = result.points.double()
    inl = result.pairs[result.inliers].numpy()
    if len(inl) > max_pairs:
        inl = inl[np.linspace(0, len(inl) - 1, max_pairs).astype(int)]
    support = pts[torch.from_numpy(np.unique(inl))] if len(inl) else pts
    tiles = []
    for cam, name in enumerate(result.cameras.image_names[:max_photos]):
        img = _photo(views, name, cam)
        if img is None:
            continue
        w, h = (int(s) for s in result.cameras.sizes[cam])
        img = cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA) if img.shape[1] != w else img
        if result.found:
            quad = plane_quad(support, result.normal, result.offset)
            uv, front = _project(result, cam, quad)
            if front.all():
                overlay = img.copy()
                cv2.fillPoly(overlay, [uv.round().astype(np.int32)], (60, 200, 60))
                img = cv2.addWeighted(overlay, 0.3, img, 0.7, 0)
                cv2.polylines(img, [uv.round().astype(np.int32)], True, (40, 160, 40), max(2, w // 400), cv2.LINE_AA)
            for a, b in inl:
                ab, fr = _project(result, cam, pts[[a, b]].numpy())
                if fr.all():
                    p, q = (tuple(int(round(v)) for v in ab[i]) for i in range(2))
                    cv2.line(img, p, q, (0, 230, 0), max(2, w // 500), cv2.LINE_AA)
                    cv2.circle(img, p, max(2, w // 400), (0, 120, 255), -1, cv2.LINE_AA)
                    cv2.circle(img, q, max(2, w // 400), (255, 120, 0), -1, cv2.LINE_AA)
        scale = width / img.shape[1]
        tile = cv2.resize(img, (width, int(round(img.shape[0] * scale))), interpolation=cv2.INTER_AREA)
        cv2.putText(tile, name, (8, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 2, cv2.LINE_AA)
        tiles.append(tile)
    path = Path(path)
    if not tiles:  # no photo to draw on: the picture says why
        tiles = [np.full((240, width, 3), 255, np.uint8)]
        cv2.putText(tiles[0], "no photo of the scene could be read", (8, 120), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (0, 0, 0), 2, cv2.LINE_AA)
    th = max(t.shape[0] for t in tiles)
    tiles = [cv2.copyMakeBorder(t, 0, th - t.shape[0], 0, 0, cv2.BORDER_CONSTANT, value=(255, 255, 255)) for t in tiles]
    cols = min(4, len(tiles))
    while len(tiles) % cols:
        tiles.append(np.full_like(tiles[0], 255))
    rows = [np.concatenate(tiles[i : i + cols], 1) for i in range(0, len(tiles), cols)]
    title = (
        f"plane found: confidence {result.confidence:.1f}, {int(result.inliers.sum())} of {len(result.pairs)} mirror pairs support it"
        if result.found
        else "no symmetry found: " + "; ".join(result.notes)
    )
    sheet = np.concatenate(rows, 0)
    banner = np.full((36, sheet.shape[1], 3), 255, np.uint8)
    cv2.putText(banner, title[:160], (8, 25), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (0, 0, 0), 2, cv2.LINE_AA)
    cv2.imwrite(str(path), np.concatenate([banner, sheet], 0))
    return path


def plot_multiview_plane(result: MultiviewPlaneResult, path: str | Path, *, max_pairs: int = 80) -> Path:
    """PNG: the sparse points in their colours, seen with the plane edge-on (from two
    sides) and along its normal, the supporting pairs joined; with fewer than 3 points, a
    picture that says so."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = result.points.double().numpy().reshape(-1, 3)
    if len(p) < 3:  # too few points for a frame: the title says what was found
        fig, ax = plt.subplots(figsize=(8, 3))
        ax.set_axis_off()
        ax.text(0.5, 0.5, f"{len(p)} reconstructed points: nothing to draw", ha="center", va="center", fontsize=12)
        fig.suptitle(("plane found" if result.found else "no symmetry found: " + "; ".join(result.notes))[:160], fontsize=10)
        path = Path(path)
        fig.savefig(path, dpi=100)
        plt.close(fig)
        return path
    lo, hi = np.quantile(p, 0.02, 0), np.quantile(p, 0.98, 0)
    keep = ((p >= lo) & (p <= hi)).all(1)
    col = result.colors.numpy() / 255.0
    if result.found:
        n = result.normal.double().numpy()
        b = float(result.offset)
    else:
        _, _, vt = np.linalg.svd(p[keep] - p[keep].mean(0), full_matrices=False)
        n, b = vt[2], -float(vt[2] @ p[keep].mean(0))
    q = p - np.outer(p @ n + b, n)
    _, _, vt = np.linalg.svd(q[keep] - q[keep].mean(0), full_matrices=False)
    e2 = vt[0] - (vt[0] @ n) * n
    e2 /= np.linalg.norm(e2)
    e3 = np.cross(n, e2)
    xyz = np.stack([p @ n + b, p @ e2, p @ e3], 1)
    pairs = result.pairs[result.inliers].numpy()[:max_pairs]
    fig, axes = plt.subplots(1, 3, figsize=(15, 5))
    for ax, (i, j, title) in zip(axes, [(0, 1, "plane edge-on"), (0, 2, "plane edge-on, turned"), (1, 2, "along the normal")]):
        ax.scatter(xyz[keep, i], xyz[keep, j], c=col[keep], s=4.0, linewidths=0)
        for a_, b_ in pairs:
            ax.plot(xyz[[a_, b_], i], xyz[[a_, b_], j], color="#2ca02c", lw=0.5, alpha=0.7)
        if result.found and i == 0:
            ax.axvline(0.0, color="#d62728", lw=1.5)
        ax.set_title(title, fontsize=10)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(
        (f"reflection plane, confidence {result.confidence:.1f}; green: the {len(pairs)} supporting pairs shown" if result.found
         else "no symmetry found: " + "; ".join(result.notes))[:160],
        fontsize=10,
    )
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


@artifact_writer(MultiviewPlaneResult)
def write_multiview_artifacts(result: MultiviewPlaneResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """``<stem>_views.png`` (the plane in the photos), ``<stem>_plane3d.png`` and the
    reconstruction in COLMAP's format in ``<stem>_colmap/`` (open with COLMAP's GUI)."""
    paths = [draw_plane_in_photos(result, data, out_dir / f"{stem}_views.png"), plot_multiview_plane(result, out_dir / f"{stem}_plane3d.png")]
    if result.reconstruction is not None:
        model = out_dir / f"{stem}_colmap"
        model.mkdir(exist_ok=True)
        result.reconstruction.write(str(model))
        paths.append(model)
    return [p for p in paths if Path(p).exists()]
