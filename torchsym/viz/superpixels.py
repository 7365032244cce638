"""Pictures of SymmSLIC: superpixel borders, each mirror pair in one colour, the mask."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import numpy as np
import torch

from torchsym.core.checks import check_image
from torchsym.image.symmslic.result import SymmSlicResult
from torchsym.metrics.superpixels import boundary_map
from torchsym.viz import artifact_writer
from torchsym.viz.annotate import banner, titled

__all__ = ["draw_superpixels", "write_symmslic_artifacts"]


def _bgr(image: Any) -> np.ndarray:
    img = check_image(image, "image")[0].detach().float().cpu().clamp(0, 1)
    img = img.expand(3, -1, -1) if img.shape[0] == 1 else img
    return (img.permute(1, 2, 0).numpy()[:, :, ::-1] * 255).round().astype(np.uint8).copy()


def draw_superpixels(result: SymmSlicResult, image: Any) -> np.ndarray:
    """BGR picture: each mirror superpixel pair tinted in one colour with white borders,
    the unpaired superpixels faded to grey with grey borders, the axes in red; a line at the
    top says when no pair was found."""
    out = _bgr(image)
    lbl = result.labels.numpy()
    rng = np.random.default_rng(0)
    tint = np.zeros((result.n_superpixels, 3), np.float64)
    has = np.zeros(result.n_superpixels, bool)
    for p, q in result.pairs.tolist():
        colour = rng.integers(40, 255, 3)
        tint[p], tint[q], has[p], has[q] = colour, colour, True, True
    m = has[lbl]  # (H, W) pixels of paired superpixels
    grey = out[~m].mean(axis=1, keepdims=True)
    out[~m] = (0.35 * out[~m] + 0.4 * grey + 0.25 * 200).astype(np.uint8)
    out[m] = (0.3 * out[m] + 0.7 * tint[lbl[m]]).astype(np.uint8)
    edge = boundary_map(lbl)
    out[edge & ~m] = (150, 150, 150)
    out[edge & m] = (255, 255, 255)
    h, w = lbl.shape
    for n, b in zip(result.normals.tolist(), result.offsets.tolist()):
        d = np.array([-n[1], n[0]])
        c = -b * np.array(n)
        p0, p1 = c - 2 * (h + w) * d, c + 2 * (h + w) * d
        ok, a, z = cv2.clipLine((0, 0, w, h), tuple(int(v) for v in p0), tuple(int(v) for v in p1))
        if ok:
            cv2.line(out, a, z, (0, 0, 255), 2, cv2.LINE_AA)
    if len(result.pairs) == 0:
        banner(out, "no mirror superpixel pairs found")
    return out


@artifact_writer(SymmSlicResult)
def write_symmslic_artifacts(result: SymmSlicResult, data: Any, out_dir: Path, stem: str) -> list[Path]:
    """``<stem>_superpixels.png`` (borders, pairs in one colour, axes, under a title and a
    legend), ``<stem>_labels.png``
    (16-bit labels), ``<stem>_labels.npy`` and ``<stem>_mask.png`` (the symmetric object)."""
    out_dir = Path(out_dir)
    paths = [out_dir / f"{stem}_superpixels.png", out_dir / f"{stem}_labels.png", out_dir / f"{stem}_labels.npy", out_dir / f"{stem}_mask.png"]
    picture = titled(
        draw_superpixels(result, data),
        f"{stem}: SymmSLIC, {result.n_superpixels} superpixels, {len(result.pairs)} mirror pairs, "
        f"covering {result.score:.0%} of the image",
        "A mirror pair of superpixels shares a tint (white borders); unpaired superpixels are faded grey; "
        "red: the symmetry axis.",
    )
    cv2.imwrite(str(paths[0]), picture)
    cv2.imwrite(str(paths[1]), result.labels.numpy().astype(np.uint16))
    np.save(paths[2], result.labels.numpy())
    cv2.imwrite(str(paths[3]), result.mask.numpy().astype(np.uint8) * 255)
    return paths
