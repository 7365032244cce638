"""Pictures of reflection axes found in an image.

The photo in colour; the accepted axes (``result.accepted``, at most ``top``) drawn boldly,
numbered by rank with their score beside; further candidates faint and dashed; the mirror
pairs only of the best accepted axis. A photo with no accepted axis says so on the picture.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.image.results import ReflectionAxesBatch, ReflectionAxesResult
from torchsym.viz import artifact_writer

__all__ = ["draw_axes", "plot_axes"]

# colours of the ranked axes (best first), readable on photographs
COLOURS = ("#ff3b30", "#ffcc00", "#34c3ff", "#7CFC00", "#ff66ff")


def _rgb(image: Any) -> np.ndarray:
    """``(H, W, 3)`` float RGB in [0, 1] of a ``(C, H, W)``, ``(1, C, H, W)`` or ``(H, W)`` image."""
    img = image if isinstance(image, torch.Tensor) else torch.as_tensor(np.asarray(image))
    img = img.detach().cpu().float()
    if img.dim() == 4:
        img = img[0]
    if img.dim() == 2:
        img = img[None]
    if img.shape[0] == 1:
        img = img.expand(3, -1, -1)
    if img.max() > 1.5:  # 0..255
        img = img / 255.0
    return img.clamp(0, 1).permute(1, 2, 0).numpy()


def _figure(rgb: np.ndarray, result: ReflectionAxesResult, top: int, faint: int, n_pairs: int, title: bool):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.patheffects as pe
    import matplotlib.pyplot as plt

    h, w = rgb.shape[:2]
    scale = max(1.0, 900 / max(h, w))  # small images are drawn larger, so the labels stay legible
    dpi = 100
    fig = plt.figure(figsize=(w * scale / dpi, h * scale / dpi + (0.35 if title else 0.0)), dpi=dpi)
    ax = fig.add_axes((0.0, 0.0, 1.0, h * scale / dpi / fig.get_figheight()))
    ax.imshow(0.85 * rgb + 0.05, extent=(-0.5, w - 0.5, h - 0.5, -0.5), interpolation="antialiased")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.axis("off")
    axes = result.axes.detach().cpu().double().numpy()
    scores = result.scores.detach().cpu().double().numpy()
    k = len(axes)
    top = min(top, int(result.accepted.sum()))  # accepted axes come first (best first)
    lw = 2.5 * max(h, w) * scale / 900 + 1.0
    outline = [pe.Stroke(linewidth=lw + 2.5, foreground="black", alpha=0.8), pe.Normal()]
    for i in range(min(k, top + faint) - 1, top - 1, -1):  # the faint ones first, underneath
        x1, y1, x2, y2 = axes[i]
        ax.plot([x1, x2], [y1, y2], color="white", lw=1.0, alpha=0.45, ls=(0, (4, 3)))
    if top and n_pairs:
        pairs = result.pairs.detach().cpu().double().numpy()[(result.pair_axis == 0).cpu().numpy()]
        if len(pairs) > n_pairs:
            pairs = pairs[np.linspace(0, len(pairs) - 1, n_pairs).round().astype(int)]
        for x1, y1, x2, y2 in pairs:
            ax.plot([x1, x2], [y1, y2], color=COLOURS[0], lw=0.8, alpha=0.55)
        ax.scatter(pairs[:, [0, 2]].ravel(), pairs[:, [1, 3]].ravel(), s=9 * scale, color=COLOURS[0],
                   edgecolors="black", linewidths=0.4, zorder=3)
    for i in range(min(k, top) - 1, -1, -1):  # the best last, on top
        x1, y1, x2, y2 = axes[i]
        ax.plot([x1, x2], [y1, y2], color=COLOURS[i % len(COLOURS)], lw=lw * (1.4 if i == 0 else 1.0),
                solid_capstyle="round", path_effects=outline, zorder=4)
    for i, (lx, ly) in enumerate(_label_positions(axes[:top], w, h, scale)):
        colour = COLOURS[i % len(COLOURS)]
        ax.annotate(f"{i + 1}", (lx, ly), color="black", fontsize=11, fontweight="bold", ha="center", va="center",
                    bbox=dict(boxstyle="circle,pad=0.25", fc=colour, ec="black", lw=1.0), zorder=6)
        ax.annotate(f"{_fmt(scores[i])}", (lx, ly), xytext=(10, 9), textcoords="offset points", color="white",
                    fontsize=10, va="center", path_effects=[pe.withStroke(linewidth=2.5, foreground="black")], zorder=6)
    if title:
        shown = min(k, top)
        text = (f"{result.method}: {shown} accepted of {k} axes, numbered by rank (score beside)"
                + (f", {min(k, top + faint) - shown} more candidates dashed" if k > top and faint else "")
                + ("; mirror pairs of axis 1" if shown and n_pairs else ""))
        fig.text(0.01, 1.0 - 0.175 / fig.get_figheight(), text if k else f"{result.method}: no axis found",
                 fontsize=10, va="center")
    if not top:
        ax.text(w / 2, h / 2, "no axis accepted" if k else "no axis found", color="white", fontsize=16,
                fontweight="bold", ha="center", va="center", zorder=7,
                path_effects=[pe.withStroke(linewidth=3.5, foreground="black")])
    return fig, plt


def _label_positions(axes: np.ndarray, w: int, h: int, scale: float) -> list[tuple[float, float]]:
    """Where to put each axis's number: on its segment ``axes (K, 4)``, from the upper end
    down, at the first place whose label box (number and score, in drawn pixels) is inside
    the picture and clear of the labels placed before."""
    box_l, box_r, box_h = 14 / scale, 75 / scale, 22 / scale  # extent around the anchor, image px
    placed: list[tuple[float, float]] = []
    for x1, y1, x2, y2 in axes:
        if y1 > y2:
            x1, y1, x2, y2 = x2, y2, x1, y1
        best = None
        for t in np.linspace(0.0, 1.0, 21):
            x, y = x1 + t * (x2 - x1), y1 + t * (y2 - y1)
            inside = box_l <= x + 0.5 and x + box_r <= w - 0.5 and box_h <= y + 0.5 and y + box_h <= h - 0.5
            clear = all(abs(y - py) > 2 * box_h or x + box_r < px - box_l or x - box_l > px + box_r for px, py in placed)
            if inside and clear:
                best = (x, y)
                break
            if best is None and clear:
                best = (x, y)
        placed.append(best if best is not None else (x1, y1))
    return placed


def _fmt(score: float) -> str:
    return f"{score:.0f}" if score >= 100 or float(score).is_integer() else f"{score:.2g}" if score < 0.1 else f"{score:.2f}"


def draw_axes(image: Any, result: ReflectionAxesResult, *, top: int = 3, faint: int = 5, n_pairs: int = 40,
              title: bool = False) -> np.ndarray:
    """``(H', W', 3)`` uint8 RGB picture of ``result``'s axes on ``image`` (see :func:`plot_axes`)."""
    fig, plt = _figure(_rgb(image), result, top, faint, n_pairs, title)
    fig.canvas.draw()
    arr = np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()
    plt.close(fig)
    return arr


def plot_axes(image: Any, result: ReflectionAxesResult, path: str | Path, *, top: int = 3, faint: int = 5,
              n_pairs: int = 40) -> Path:
    """PNG of ``result``'s axes on ``image``, the photo dimmed beneath.

    Args:
        image: ``(C, H, W)`` or ``(1, C, H, W)`` image the result was found on.
        result: a :class:`~torchsym.image.results.ReflectionAxesResult`.
        path: the PNG to write.
        top: axes drawn boldly, numbered by rank with their score beside (default 3).
        faint: further axes drawn as thin dashed lines (default 5).
        n_pairs: the most mirror pairs of the best axis drawn (default 40; 0: none).
    """
    fig, plt = _figure(_rgb(image), result, top, faint, n_pairs, True)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path


@artifact_writer(ReflectionAxesResult)
def write_axes(result: ReflectionAxesResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """``{stem}_axes.png``: the axes on the image."""
    return [plot_axes(data, result, Path(out_dir) / f"{stem}_axes.png")]


@artifact_writer(ReflectionAxesBatch)
def write_axes_batch(result: ReflectionAxesBatch, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """One ``{stem}_{b}_axes.png`` per image of ``data (B, C, H, W)``."""
    return [p for b, res in enumerate(result.results) for p in write_axes(res, data[b], out_dir, f"{stem}_{b}")]
