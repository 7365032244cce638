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

__all__ = ["mirrored_objects_image", "mirrored_photo", "mirrored_texture_image"]


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


def _mirror_with_polygon(
    rng: np.random.Generator, tile: np.ndarray, n_vertices: tuple[int, int], ys: tuple[float, float],
    xs: tuple[float, float], line_type: int,
) -> np.ndarray:
    """Mirror the square ``tile (S, S, ...)`` in place about its middle column and draw a
    random polygon symmetric about it: ``n_vertices`` (low, high) per side at row and
    column shares ``ys``, ``xs`` of the side; returns the ``(S, S)`` uint8 mask (255 inside)."""
    import cv2

    size = tile.shape[0]
    half = size // 2
    tile[:, size - half :] = tile[:, :half][:, ::-1]  # mirror about column (size - 1) / 2
    n = int(rng.integers(*n_vertices))
    py = np.sort(rng.uniform(ys[0], ys[1], n)) * (size - 1)
    px = rng.uniform(xs[0], xs[1], n) * (size - 1)
    c = (size - 1) / 2
    poly = np.concatenate([np.stack([px, py], 1), np.stack([2 * c - px, py], 1)[::-1]])
    mask = np.zeros((size, size), np.uint8)
    cv2.fillPoly(mask, [np.round(poly * 16).astype(np.int32)], 255, line_type, shift=4)
    return mask


def _object(rng: np.random.Generator, size: int) -> tuple[np.ndarray, np.ndarray]:
    import cv2

    tex = _half_texture(rng, size)
    mask = _mirror_with_polygon(rng, tex, (4, 8), (0.05, 0.95), (0.05, 0.45), cv2.LINE_AA)
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


def _photo_crop(rng: np.random.Generator, photos: list, height: int, width: int, zoom: tuple[float, float] = (1.0, 1.6)) -> np.ndarray:
    """A random ``(height, width, 3)`` float crop of a random photo magnified by ``zoom``, or a synthetic texture."""
    import cv2

    if photos:
        img = cv2.imread(str(photos[int(rng.integers(len(photos)))]), cv2.IMREAD_COLOR)
        if img is not None:
            s = max(height / img.shape[0], width / img.shape[1]) * rng.uniform(*zoom)
            img = cv2.resize(img, (max(width, round(img.shape[1] * s)), max(height, round(img.shape[0] * s))), interpolation=cv2.INTER_AREA)
            y = int(rng.integers(0, img.shape[0] - height + 1))
            x = int(rng.integers(0, img.shape[1] - width + 1))
            return img[y : y + height, x : x + width, ::-1].astype(np.float32) / 255.0
    side = max(height, width)
    tex = np.concatenate([_half_texture(rng, side), _half_texture(rng, side)], 1)[:height, :width]
    fine = cv2.resize(rng.random((height // 4 + 1, width // 4 + 1, 3)).astype(np.float32), (width, height))
    return np.clip(0.8 * tex + 0.2 * fine, 0, 1)


def _mosaic(rng: np.random.Generator, photos: list, height: int, width: int, n: int = 4) -> np.ndarray:
    """An ``n x n`` mosaic of magnified photo crops turned by random quarter turns: a background
    of texture with no whole (symmetric) object in it."""
    th, tw = -(-height // n), -(-width // n)
    side = max(th, tw)
    tiles = [np.rot90(_photo_crop(rng, photos, side, side, (3.0, 6.0)), int(rng.integers(4)))[:th, :tw] for _ in range(n * n)]
    rows = [np.concatenate(tiles[i * n : (i + 1) * n], 1) for i in range(n)]
    return np.ascontiguousarray(np.concatenate(rows, 0)[:height, :width])


def mirrored_photo(
    *,
    height: int = 480,
    width: int = 640,
    photo_dir: str | None = None,
    jpeg_quality: int = 85,
    noise: float = 0.01,
    warp_px: float = 1.0,
    illumination: float = 0.2,
    generator: torch.Generator | None = None,
) -> dict[str, torch.Tensor]:
    """A photograph with one mirror-symmetric object and its exact mirror field (thesis Ch. 3 ground truth).

    A random crop of a photo (from ``photo_dir``; a synthetic texture when None, empty or
    missing) has its left half mirrored onto its right half inside a mirror-symmetric
    mask; the object is rotated by a random angle, scaled and pasted on a mosaic of 4 x 4
    crops of other photos (no large symmetric object in the background). Then what photos have: a brightness gain of up to ``illumination`` on one side
    of the axis, a smooth random warp of up to ``warp_px`` pixels, Gaussian noise of
    ``noise``, JPEG at ``jpeg_quality``. The mirror field accounts for the warp (its inverse
    by fixed-point iteration), so it is exact at every object pixel up to rounding of
    ``1e-3`` px.

    Args:
        height: image height in pixels.
        width: image width in pixels.
        photo_dir: a folder of ``.jpg`` / ``.png`` photos.
        jpeg_quality: JPEG quality (1-100); 100 or more: no JPEG.
        noise: standard deviation of the added noise (image in [0, 1]).
        warp_px: largest displacement of the warp, pixels.
        illumination: largest relative brightness change on one side of the axis.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        ``image (3, H, W)`` float in [0, 1]; ``nmrf (H, W, 2)`` float ``(x, y)`` of each
        pixel's mirror; ``mask (H, W)`` bool, the object pixels whose mirror lies in the
        object; ``line (3,)`` the axis ``a x + b y + c = 0`` before the warp.
    """
    import glob
    import os

    import cv2

    rng = numpy_rng(generator)
    photos = []
    if photo_dir is not None and os.path.isdir(photo_dir):
        photos = sorted(glob.glob(os.path.join(photo_dir, "*.jpg")) + glob.glob(os.path.join(photo_dir, "*.png")))
    size = int(0.75 * min(height, width))
    obj = _photo_crop(rng, photos, size, size)
    mask = _mirror_with_polygon(rng, obj, (5, 9), (0.02, 0.98), (0.03, 0.4), cv2.LINE_8)
    c = (size - 1) / 2
    mask = np.minimum(mask, mask[:, ::-1])  # exactly symmetric
    ang = rng.uniform(-180, 180)
    scale = rng.uniform(0.85, 1.15)
    m = cv2.getRotationMatrix2D((c, c), ang, scale)
    m[:, 2] += [width / 2 - c + rng.uniform(-0.1, 0.1) * width, height / 2 - c + rng.uniform(-0.1, 0.1) * height]
    bg = _mosaic(rng, photos, height, width)
    fg = cv2.warpAffine(obj, m, (width, height), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    alpha = cv2.warpAffine(mask.astype(np.float32) / 255.0, m, (width, height), flags=cv2.INTER_LINEAR)
    img = alpha[..., None] * fg + (1 - alpha[..., None]) * bg
    # the mirror in image pixels: A Flip A^-1 with A = [m; 0 0 1], Flip x -> 2c - x
    a = np.vstack([m, [0, 0, 1]])
    flip = np.array([[-1, 0, 2 * c], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    mirror = a @ flip @ np.linalg.inv(a)  # (3, 3)
    ends = a @ np.array([[c, 0, 1], [c, size - 1, 1]], dtype=np.float64).T  # (3, 2)
    d = ends[:2, 1] - ends[:2, 0]
    nrm = np.array([d[1], -d[0]]) / np.hypot(*d)
    line = np.array([nrm[0], nrm[1], -nrm @ ends[:2, 0]])
    gx, gy = np.meshgrid(np.arange(width, dtype=np.float64), np.arange(height, dtype=np.float64))
    side = (line[0] * gx + line[1] * gy + line[2]) / 10.0
    gain = 1 + rng.uniform(-illumination, illumination) / (1 + np.exp(-side))
    img = np.clip(img * gain[..., None].astype(np.float32), 0, 1)
    # warp: J(x) = I(x + delta(x)), delta smooth with |delta| <= warp_px
    coarse = rng.uniform(-1, 1, (2, 5, 6)).astype(np.float32)
    delta = np.stack([cv2.resize(cc, (width, height), interpolation=cv2.INTER_CUBIC) for cc in coarse], -1).astype(np.float64)
    delta *= warp_px / max(np.abs(delta).max(), 1e-9)
    wx, wy = gx + delta[..., 0], gy + delta[..., 1]
    img = cv2.remap(img, wx.astype(np.float32), wy.astype(np.float32), cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    amask = cv2.remap(alpha, wx.astype(np.float32), wy.astype(np.float32), cv2.INTER_LINEAR)
    # mirror field: y with w(y) = M w(x), by y <- M w(x) - delta(y)
    tx = mirror[0, 0] * wx + mirror[0, 1] * wy + mirror[0, 2]
    ty = mirror[1, 0] * wx + mirror[1, 1] * wy + mirror[1, 2]
    fx, fy = tx.copy(), ty.copy()
    for _ in range(8):
        dx = cv2.remap(delta[..., 0].astype(np.float32), fx.astype(np.float32), fy.astype(np.float32), cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        dy = cv2.remap(delta[..., 1].astype(np.float32), fx.astype(np.float32), fy.astype(np.float32), cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        fx, fy = tx - dx, ty - dy
    img = np.clip(img + noise * rng.standard_normal(img.shape).astype(np.float32), 0, 1)
    if jpeg_quality < 100:
        ok, buf = cv2.imencode(".jpg", np.round(img[..., ::-1] * 255).astype(np.uint8), [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)])
        img = cv2.imdecode(buf, cv2.IMREAD_COLOR)[..., ::-1].astype(np.float32) / 255.0
    inside = (fx >= 0) & (fx <= width - 1) & (fy >= 0) & (fy <= height - 1)
    mirror_in = cv2.remap(amask, fx.astype(np.float32), fy.astype(np.float32), cv2.INTER_NEAREST) > 0.99
    valid = (amask > 0.99) & inside & mirror_in
    return {
        "image": torch.from_numpy(np.ascontiguousarray(img.transpose(2, 0, 1))).float(),
        "nmrf": torch.from_numpy(np.stack([fx, fy], -1)).float(),
        "mask": torch.from_numpy(valid),
        "line": torch.from_numpy(line).float(),
    }


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
