"""Synthetic photographs with planted mirror-symmetric objects and their true axes.

Used by the tests and the benchmark (targets: every planted axis found). Each object is a
textured patch whose left half is drawn at random and whose right half is its mirror
image, cut out by a mirror-symmetric polygon, rotated by a random angle and pasted on a
non-symmetric background.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from torchsym.core.checks import check_int
from torchsym.core.random import numpy_rng

__all__ = ["mirrored_objects_image", "mirrored_texture_image"]


def _half_texture(rng: np.random.Generator, size: int) -> np.ndarray:
    import cv2

    base = rng.random((size // 24 + 2, size // 24 + 2, 3)).astype(np.float32)
    tex = cv2.resize(base, (size, size), interpolation=cv2.INTER_CUBIC)
    for _ in range(8):  # irregular triangles: no symmetry of their own
        col = tuple(float(c) for c in rng.random(3))
        centre = rng.uniform([0, 0], [size / 2, size])
        r = rng.uniform(size / 14, size / 6)
        ang = np.sort(rng.uniform(0, 2 * math.pi, 3))
        rad = r * rng.uniform(0.5, 1.0, 3)
        tri = centre + np.stack([rad * np.cos(ang), rad * np.sin(ang)], 1)
        cv2.fillPoly(tex, [np.round(tri * 16).astype(np.int32)], col, cv2.LINE_AA, shift=4)
    return np.clip(tex, 0, 1)


def _object(rng: np.random.Generator, size: int) -> tuple[np.ndarray, np.ndarray]:
    import cv2

    tex = _half_texture(rng, size)
    half = size // 2
    tex[:, size - half :] = tex[:, :half][:, ::-1]  # mirror about column (size - 1) / 2
    n = int(rng.integers(4, 8))
    ys = np.sort(rng.uniform(0.05, 0.95, n)) * (size - 1)
    xs = rng.uniform(0.05, 0.45, n) * (size - 1)
    c = (size - 1) / 2
    poly = np.concatenate([np.stack([xs, ys], 1), np.stack([2 * c - xs, ys], 1)[::-1]])
    mask = np.zeros((size, size), np.uint8)
    cv2.fillPoly(mask, [np.round(poly * 16).astype(np.int32)], 255, cv2.LINE_AA, shift=4)
    return tex, mask.astype(np.float32) / 255.0


def mirrored_objects_image(
    n_objects: int = 2,
    *,
    height: int = 360,
    width: int = 480,
    generator: torch.Generator | None = None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """An RGB image with ``n_objects`` mirror-symmetric objects at random angles.

    Args:
        n_objects: objects to plant (1 to 4), side by side without overlap.
        height: image height in pixels.
        width: image width in pixels.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        ``image (3, H, W)`` float in [0, 1] and ``axes (n_objects, 4)`` true axes
        ``x1, y1, x2, y2`` in pixels.
    """
    import cv2

    n_objects = check_int(n_objects, "n_objects", minimum=1)
    if n_objects > 4:
        from torchsym.errors import InputValueError

        raise InputValueError(f"n_objects: expected an integer in [1, 4], got {n_objects}")
    rng = numpy_rng(generator)
    bg = cv2.resize(rng.random((6, 8, 3)).astype(np.float32), (width, height), interpolation=cv2.INTER_CUBIC)
    bg = np.clip(0.25 + 0.5 * bg + 0.03 * rng.standard_normal((height, width, 3)).astype(np.float32), 0, 1)
    cols = 2 if n_objects > 1 else 1
    rows = 2 if n_objects > 2 else 1
    cell_w, cell_h = width / cols, height / rows
    size = int(0.8 * min(cell_w, cell_h) / 0.72)  # object patch; the rotated object fits the cell
    axes = []
    cells = rng.permutation(cols * rows)[:n_objects]
    for cell in cells:
        r, cc = divmod(int(cell), cols)
        cx = (cc + 0.5) * cell_w + rng.uniform(-0.05, 0.05) * cell_w
        cy = (r + 0.5) * cell_h + rng.uniform(-0.05, 0.05) * cell_h
        tex, mask = _object(rng, size)
        ang = rng.uniform(-90, 90)
        m = cv2.getRotationMatrix2D(((size - 1) / 2, (size - 1) / 2), ang, 0.72)
        m[:, 2] += [cx - (size - 1) / 2, cy - (size - 1) / 2]
        obj = cv2.warpAffine(tex, m, (width, height), flags=cv2.INTER_LINEAR)
        alpha = cv2.warpAffine(mask, m, (width, height), flags=cv2.INTER_LINEAR)[..., None]
        bg = alpha * obj + (1 - alpha) * bg
        ys = np.nonzero(mask.max(1) > 0.5)[0]
        c = (size - 1) / 2
        ends = np.array([[c, ys.min(), 1.0], [c, ys.max(), 1.0]]) @ m.T  # (2, 2)
        axes.append([ends[0, 0], ends[0, 1], ends[1, 0], ends[1, 1]])
    image = torch.from_numpy(np.ascontiguousarray(bg.transpose(2, 0, 1))).float()
    return image, torch.tensor(axes, dtype=torch.float32)


def mirrored_texture_image(
    *,
    height: int = 480,
    width: int = 640,
    angle: float | None = None,
    generator: torch.Generator | None = None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """A whole image mirror symmetric about a line through its centre: a smooth random
    texture with shapes on one side, reflected onto the other.

    Args:
        height, width: image size in pixels.
        angle: the axis normal's angle in degrees; None draws it at random.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        ``image (3, H, W)`` float in [0, 1] and ``axis (3,)`` float64 ``(n_x, n_y,
        offset)``: the axis is ``n . (x, y) + offset = 0`` in pixels.
    """
    import cv2

    rng = numpy_rng(generator)
    base = cv2.resize(rng.random((height // 24 + 2, width // 24 + 2, 3)).astype(np.float32), (width, height), interpolation=cv2.INTER_CUBIC)
    base = np.clip(base, 0, 1)
    for _ in range(12):
        colour = tuple(float(v) for v in rng.random(3))
        x, y, r = int(rng.integers(0, width)), int(rng.integers(0, height)), int(rng.integers(8, 40))
        cv2.circle(base, (x, y), r, colour, -1) if rng.random() < 0.5 else cv2.rectangle(base, (x, y), (x + r, y + 2 * r), colour, -1)
    t = math.radians(rng.uniform(0, 180) if angle is None else angle)
    n = np.array([math.cos(t), math.sin(t)])
    b = -float(n @ [(width - 1) / 2, (height - 1) / 2])
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    d = xs * n[0] + ys * n[1] + b
    mx, my = (xs - 2 * d * n[0]).astype(np.float32), (ys - 2 * d * n[1]).astype(np.float32)
    mirrored = cv2.remap(base, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    img = np.where((d > 0)[..., None], mirrored, base)
    return torch.from_numpy(np.ascontiguousarray(img.transpose(2, 0, 1))).float(), torch.tensor([n[0], n[1], b], dtype=torch.float64)
