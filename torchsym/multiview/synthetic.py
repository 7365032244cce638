"""A small multi-view scene with a planted reflection plane, rendered in code.

A facade, two side wings and a protruding block, symmetric about the plane ``x = 0``:
each textured quad's mirror image carries the mirrored texture. Every view is rendered by
homographies of the textures into a pinhole camera (OpenCV), so the whole multi-view
pipeline runs on it in seconds.
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np
import torch

from torchsym.core.random import numpy_rng

__all__ = ["SyntheticScene", "symmetric_scene"]


@dataclasses.dataclass(frozen=True)
class SyntheticScene:
    """Rendered views and the scene's truth.

    Attributes:
        images: ``(V, 3, H, W)`` float32 views in [0, 1].
        normal: ``(3,)`` the planted plane's normal (``(1, 0, 0)``).
        offset: ``()`` its offset (0).
        intrinsics: ``(3, 3)`` the camera matrix.
        rotations: ``(V, 3, 3)`` camera-from-world rotations.
        translations: ``(V, 3)`` camera-from-world translations.
    """

    images: torch.Tensor
    normal: torch.Tensor
    offset: torch.Tensor
    intrinsics: torch.Tensor
    rotations: torch.Tensor
    translations: torch.Tensor


def _texture(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """A cluttered texture of shapes and grain, ``(h, w, 3)`` uint8."""
    t = rng.integers(90, 170, (h, w, 3)).astype(np.uint8)
    t = cv2.GaussianBlur(t, (0, 0), 3)
    for _ in range((h * w) // 900):
        color = tuple(int(c) for c in rng.integers(0, 256, 3))
        x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
        s = int(rng.integers(4, max(5, min(h, w) // 8)))
        kind = rng.integers(0, 3)
        if kind == 0:
            cv2.rectangle(t, (x, y), (x + s, y + int(rng.integers(3, 2 * s))), color, -1)
        elif kind == 1:
            cv2.circle(t, (x, y), s // 2, color, -1)
        else:
            cv2.line(t, (x, y), (x + int(rng.integers(-2 * s, 2 * s)), y + int(rng.integers(-2 * s, 2 * s))), color, 2)
    return t


def _symmetric(rng: np.random.Generator, h: int, w: int, symmetric: bool) -> np.ndarray:
    """A texture whose right half mirrors its left half (or an independent one)."""
    if not symmetric:
        return _texture(rng, h, w)
    left = _texture(rng, h, w // 2)
    return np.concatenate([left, left[:, ::-1]], axis=1)


def _look_at(centre: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Camera-from-world ``R, t`` of a camera at ``centre`` looking at ``target`` (y down)."""
    z = target - centre
    z /= np.linalg.norm(z)
    x = np.cross(np.array([0.0, -1.0, 0.0]), z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    r = np.stack([x, y, z])
    return r, -r @ centre


def symmetric_scene(
    n_views: int = 7,
    *,
    height: int = 480,
    width: int = 640,
    symmetric: bool = True,
    generator: torch.Generator | None = None,
) -> SyntheticScene:
    """Render ``n_views`` photos of a scene symmetric about ``x = 0`` (or, with
    ``symmetric=False``, of the same geometry with unrelated textures on each side).

    Args:
        n_views: photos, from viewpoints spread over 70 degrees in front of the facade.
        height, width: photo size in pixels.
        symmetric: plant the symmetry in the textures.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.
    """
    rng = numpy_rng(generator)
    f = 0.9 * width
    k = np.array([[f, 0, width / 2], [0, f, height / 2], [0, 0, 1.0]])
    front = _symmetric(rng, 600, 800, symmetric)
    block = _symmetric(rng, 300, 420, symmetric)
    wing = _texture(rng, 600, 400)
    other_wing = wing[:, ::-1] if symmetric else _texture(rng, 600, 400)
    # quads: corners (TL, TR, BR, BL) in world coordinates (y down, z towards the cameras)
    quads = [
        (front, np.array([[-2, -1.5, 0], [2, -1.5, 0], [2, 1.5, 0], [-2, 1.5, 0]], float)),
        (block, np.array([[-0.7, -0.5, 0.8], [0.7, -0.5, 0.8], [0.7, 0.5, 0.8], [-0.7, 0.5, 0.8]], float)),
        (wing, np.array([[-3.2, -1.5, 1.6], [-2, -1.5, 0], [-2, 1.5, 0], [-3.2, 1.5, 1.6]], float)),
        (other_wing, np.array([[2, -1.5, 0], [3.2, -1.5, 1.6], [3.2, 1.5, 1.6], [2, 1.5, 0]], float)),
    ]
    angles = np.linspace(-35, 35, n_views) + rng.uniform(-4, 4, n_views)
    images, rots, trans = [], [], []
    for a in np.radians(angles):
        centre = np.array([7.5 * math.sin(a), -0.8 + rng.uniform(-0.3, 0.3), 7.5 * math.cos(a)])
        r, t = _look_at(centre, np.array([0.0, 0.0, 0.4]) + rng.uniform(-0.2, 0.2, 3))
        canvas = np.full((height, width, 3), 200, np.uint8)
        order = sorted(quads, key=lambda q: -float((r @ q[1].mean(0) + t)[2]))
        for tex, corners in order:
            cam = corners @ r.T + t  # (4, 3)
            if (cam[:, 2] <= 0.1).any():
                continue
            img = cam @ k.T
            img = (img[:, :2] / img[:, 2:]).astype(np.float32)
            th, tw = tex.shape[:2]
            src = np.array([[0, 0], [tw - 1, 0], [tw - 1, th - 1], [0, th - 1]], np.float32)
            h = cv2.getPerspectiveTransform(src, img)
            warped = cv2.warpPerspective(tex, h, (width, height), flags=cv2.INTER_AREA)
            mask = cv2.warpPerspective(np.full((th, tw), 255, np.uint8), h, (width, height)) > 127
            canvas[mask] = warped[mask]
        images.append(torch.from_numpy(canvas).permute(2, 0, 1).float() / 255.0)
        rots.append(r)
        trans.append(t)
    return SyntheticScene(
        images=torch.stack(images),
        normal=torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64),
        offset=torch.zeros((), dtype=torch.float64),
        intrinsics=torch.from_numpy(k),
        rotations=torch.from_numpy(np.stack(rots)),
        translations=torch.from_numpy(np.stack(trans)),
    )
