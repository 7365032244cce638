"""Pictures of dense reflection symmetry maps and of their stylization (thesis Secs. 3.3.1, 3.4)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.image.symmetry_map.result import StylizedResult, SymmetryMapResult
from torchsym.metrics.symmetry_map import reconstruct_mirror
from torchsym.viz import artifact_writer

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


def _pairs_picture(result: SymmetryMapResult) -> np.ndarray:
    import cv2

    img = _bgr(result.image).copy()
    colours = [(0, 0, 255), (0, 200, 0), (255, 0, 0), (0, 200, 255), (255, 0, 255), (255, 255, 0)]
    for (x1, y1, x2, y2), c in zip(result.pairs.cpu().tolist(), result.pair_cluster.cpu().tolist()):
        col = colours[c % len(colours)] if c >= 0 else (160, 160, 160)
        cv2.line(img, (round(x1), round(y1)), (round(x2), round(y2)), col, 1 if c >= 0 else 1, cv2.LINE_AA)
    h, w = img.shape[:2]
    for k, (a, b, c) in enumerate(result.lines.cpu().tolist()):
        d = np.array([-b, a])
        p0 = -c * np.array([a, b])
        ends = [p0 + t * d for t in (-2 * (h + w), 2 * (h + w))]
        cv2.line(img, tuple(np.round(ends[0]).astype(int)), tuple(np.round(ends[1]).astype(int)), colours[k % len(colours)], 2, cv2.LINE_AA)
    return img


@artifact_writer(SymmetryMapResult)
def write_symmetry_map(result: SymmetryMapResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """Per axis ``h``: ``{stem}_nmrf{h}.png`` (HSV picture), ``{stem}_ssm{h}.png`` (grey),
    ``{stem}_im{h}.png`` (``Im = S I(f)``) and ``{stem}_nmrf{h}.npy`` (``(H, W, 2)`` float32
    ``x, y``); ``{stem}_pairs.png`` (the candidate pairs coloured by cluster, grey for
    outliers, and the axes). With no axis: ``{stem}_ssm.png``, all black."""
    import cv2

    out = Path(out_dir)
    paths = [out / f"{stem}_pairs.png"]
    cv2.imwrite(str(paths[0]), _pairs_picture(result))
    if len(result) == 0:
        p = out / f"{stem}_ssm.png"
        cv2.imwrite(str(p), np.zeros(tuple(result.image.shape[-2:]), np.uint8))
        return paths + [p]
    for h in range(len(result)):
        nmrf, ssm = result.nmrf[h], result.ssm[h]
        p_hsv, p_ssm, p_im, p_npy = (out / f"{stem}_{k}{h}.{e}" for k, e in (("nmrf", "png"), ("ssm", "png"), ("im", "png"), ("nmrf", "npy")))
        cv2.imwrite(str(p_hsv), nmrf_hsv(nmrf, ssm))
        cv2.imwrite(str(p_ssm), (ssm.detach().cpu().clamp(0, 1) * 255).round().byte().numpy())
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
