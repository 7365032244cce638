"""Pictures of dense reflection symmetry maps and of their stylization (thesis Secs. 3.3.1, 3.4)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.image.symmetry_map.result import StylizedResult, SymmetryMapResult
from torchsym.metrics.symmetry_map import reconstruct_mirror
from torchsym.viz import artifact_writer
from torchsym.viz.annotate import banner, titled

__all__ = ["nmrf_hsv", "write_stylized", "write_symmetry_map"]


def nmrf_hsv(nmrf: torch.Tensor, ssm: torch.Tensor) -> np.ndarray:
    """The thesis's picture of an NMRF (Sec. 3.3.1): ``(H, W, 3)`` uint8 BGR whose hue is the
    direction of ``p - f(p)``, saturation its length (over the longest in the map) and value the score."""
    import cv2

    h, w = ssm.shape
    ys, xs = torch.meshgrid(torch.arange(h), torch.arange(w), indexing="ij")
    v = torch.stack([xs, ys], -1).float() - nmrf.detach().cpu().float()  # (H, W, 2)
    ang = torch.remainder(torch.atan2(v[..., 1], v[..., 0]), 2 * np.pi)
    mag = v.norm(dim=-1)
    hsv = np.stack(
        [
            (ang / (2 * np.pi) * 180).numpy(),
            (mag / mag.max().clamp_min(1e-6) * 255).numpy(),
            (ssm.detach().cpu().float().clamp(0, 1) * 255).numpy(),
        ],
        -1,
    ).round().astype(np.uint8)
    return cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)


def _bgr(image: torch.Tensor) -> np.ndarray:
    a = (image.detach().cpu().float().clamp(0, 1) * 255).round().byte().permute(1, 2, 0).numpy()
    return np.ascontiguousarray(a[..., ::-1] if a.shape[2] == 3 else np.repeat(a, 3, 2))


def _pairs_picture(result: SymmetryMapResult, max_pairs: int = 40) -> np.ndarray:
    """The image with each axis and at most ``max_pairs`` of its cluster's pairs in the
    axis's colour, end points dotted; pairs of no cluster are left out."""
    import cv2

    img = _bgr(result.image).copy()
    colours = [(0, 0, 255), (0, 200, 0), (255, 0, 0), (0, 200, 255), (255, 0, 255), (255, 255, 0)]
    pairs = result.pairs.detach().cpu().numpy()  # (P, 4)
    cluster = result.pair_cluster.detach().cpu().numpy()  # (P,)
    h, w = img.shape[:2]
    for k, (a, b, c) in enumerate(result.lines.cpu().tolist()):
        col = colours[k % len(colours)]
        d = np.array([-b, a])
        p0 = -c * np.array([a, b])
        ends = [p0 + t * d for t in (-2 * (h + w), 2 * (h + w))]
        cv2.line(img, tuple(np.round(ends[0]).astype(int)), tuple(np.round(ends[1]).astype(int)), col, 2, cv2.LINE_AA)
        mine = pairs[cluster == k]
        if len(mine) > max_pairs:
            mine = mine[np.linspace(0, len(mine) - 1, max_pairs).round().astype(int)]
        for x1, y1, x2, y2 in mine:
            p, q = (round(x1), round(y1)), (round(x2), round(y2))
            cv2.line(img, p, q, col, 1, cv2.LINE_AA)
            cv2.circle(img, p, 3, col, -1, cv2.LINE_AA)
            cv2.circle(img, q, 3, col, -1, cv2.LINE_AA)
        label = f"axis {k + 1}: {int((cluster == k).sum())} pairs"
        (tw, th), _ = cv2.getTextSize(label, cv2.FONT_HERSHEY_SIMPLEX, 0.6, 1)
        cv2.rectangle(img, (4, 6 + 24 * k), (12 + tw, 12 + th + 24 * k), (255, 255, 255), -1)
        cv2.putText(img, label, (8, 8 + th + 24 * k), cv2.FONT_HERSHEY_SIMPLEX, 0.6, col, 1, cv2.LINE_AA)
    if len(result.lines) == 0:
        banner(img, "no symmetry axis found")
    return img


@artifact_writer(SymmetryMapResult)
def write_symmetry_map(result: SymmetryMapResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """Per axis ``h``: ``{stem}_nmrf{h}.png`` (HSV picture), ``{stem}_ssm{h}.png`` (grey),
    ``{stem}_im{h}.png`` (``Im = S I(f)``) and ``{stem}_nmrf{h}.npy`` (``(H, W, 2)`` float32
    ``x, y``); ``{stem}_pairs.png`` (each axis with up to 40 of its
    cluster's pairs in its colour). The pictures carry a title and a legend above them. With no axis: ``{stem}_pairs.png`` says so and
    ``{stem}_ssm.png`` is all black."""
    import cv2

    out = Path(out_dir)
    paths = [out / f"{stem}_pairs.png"]
    cv2.imwrite(str(paths[0]), titled(
        _pairs_picture(result), f"{stem}: dense symmetry map, {len(result)} axes, mean score {result.score:.2f}",
        "Each axis in its colour with a sample of the mirror pairs that found it (a dot at each end)."))
    if len(result) == 0:
        p = out / f"{stem}_ssm.png"
        cv2.imwrite(str(p), np.zeros(tuple(result.image.shape[-2:]), np.uint8))
        return paths + [p]
    for h in range(len(result)):
        nmrf, ssm = result.nmrf[h], result.ssm[h]
        p_hsv, p_ssm, p_im, p_npy = (out / f"{stem}_{k}{h}.{e}" for k, e in (("nmrf", "png"), ("ssm", "png"), ("im", "png"), ("nmrf", "npy")))
        cv2.imwrite(str(p_hsv), titled(
            nmrf_hsv(nmrf, ssm), f"{stem}: mirror of every pixel about axis {h + 1}",
            "Hue: the direction to the mirror pixel; saturation: its distance; brightness: the symmetry score."))
        cv2.imwrite(str(p_ssm), titled(
            (ssm.detach().cpu().clamp(0, 1) * 255).round().byte().numpy(), f"{stem}: symmetry score, axis {h + 1}",
            "White: the pixel and its mirror look alike (score 1); black: they do not (0)."))
        cv2.imwrite(str(p_im), _bgr(reconstruct_mirror(result.image, nmrf, ssm)))
        np.save(p_npy, nmrf.detach().cpu().numpy().astype(np.float32))
        paths += [p_hsv, p_ssm, p_im, p_npy]
    return paths


@artifact_writer(StylizedResult)
def write_stylized(result: StylizedResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """``{stem}_stylized.png``: the stylized image."""
    import cv2

    p = Path(out_dir) / f"{stem}_stylized.png"
    cv2.imwrite(str(p), _bgr(result.image))
    return [p]
