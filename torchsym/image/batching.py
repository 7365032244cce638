"""Batches and image sizes for the single-image axis detectors.

An image whose longer side exceeds ``max_side`` is detected on a copy scaled down to that
side (antialiased), one whose longer side is below ``min_side`` on a copy scaled up to it
(bilinear), and the result is mapped back to the input's pixels.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import torch

from torchsym.core.checks import check_image
from torchsym.errors import ConfigError
from torchsym.features.sift import SIFT_MIN_SIDE
from torchsym.image.results import ReflectionAxesBatch, ReflectionAxesResult

__all__ = ["check_sides", "run_batched", "to_input_pixels", "working_copy"]


def check_sides(min_side: int | None, max_side: int | None) -> None:
    """Raise :class:`~torchsym.errors.ConfigError` unless ``min_side <= max_side`` (None: no bound)."""
    if min_side is not None and max_side is not None and min_side > max_side:
        raise ConfigError(f"min_side: expected at most max_side ({max_side}), got {min_side}")


def working_copy(img: torch.Tensor, max_side: int | None, min_side: int | None = None) -> torch.Tensor:
    """``img (B, C, H, W)`` scaled so its longer side lies in ``[min_side, max_side]``
    (itself when it does, or a bound is None). Scaling down, the short side of a long strip
    stays at least ``SIFT_MIN_SIDE`` (32); the bilinear (antialiased when shrinking) filter
    keeps the input's range."""
    height, width = int(img.shape[-2]), int(img.shape[-1])
    long = max(height, width)
    if max_side is not None and long > max_side:
        scale = max_side / long
        size = tuple(min(side, max(SIFT_MIN_SIDE, round(side * scale))) for side in (height, width))
    elif min_side is not None and long < min_side:
        scale = min_side / long
        size = tuple(max(side, round(side * scale)) for side in (height, width))
    else:
        return img
    src = img if img.dtype in (torch.float32, torch.float64) else img.float()  # antialias: float32/64 only
    shrink = size[0] < height or size[1] < width
    out = torch.nn.functional.interpolate(src, size=size, mode="bilinear", align_corners=False, antialias=shrink)
    return out


def to_input_pixels(res: ReflectionAxesResult, height: int, width: int) -> ReflectionAxesResult:
    """``res``, found on a resized copy of an image, in the pixels of the ``height x width`` input.

    Pixel centres map to pixel centres (``x = (x' + 0.5) * width / w' - 0.5``, as
    ``interpolate(align_corners=False)`` samples); each line is mapped the same way and
    renormalised. ``info["working_size"]`` records the copy's size.
    """
    h, w = res.image_size
    sx, sy = width / w, height / h

    def points(t: torch.Tensor) -> torch.Tensor:
        t = t.double().clone()
        t[..., 0::2] = (t[..., 0::2] + 0.5) * sx - 0.5
        t[..., 1::2] = (t[..., 1::2] + 0.5) * sy - 0.5
        return t.float()

    ln = res.lines.double()
    a, b = ln[:, 0] / sx, ln[:, 1] / sy
    c = ln[:, 2] + ln[:, 0] * (0.5 / sx - 0.5) + ln[:, 1] * (0.5 / sy - 0.5)
    lines = torch.stack([a, b, c], 1) / torch.hypot(a, b)[:, None] if ln.shape[0] else ln
    return dataclasses.replace(
        res, axes=points(res.axes), lines=lines.float(), pairs=points(res.pairs), image_size=(height, width),
        info={**res.info, "working_size": (h, w)},
    )


def run_batched(
    detect_one: Callable[..., ReflectionAxesResult], image: Any, max_side: int | None, min_side: int | None = None,
    **kwargs: Any,
) -> ReflectionAxesResult | ReflectionAxesBatch:
    """``detect_one(image (1, C, H, W), **kwargs)`` on each image of ``image``.

    Args:
        detect_one: a single-image detector.
        image: ``(C, H, W)`` or ``(B, C, H, W)`` (or ``(H, W)``), checked by
            :func:`~torchsym.core.checks.check_image`.
        max_side: the longest side an image is detected at, px (None: no limit).
        min_side: the shortest longer side an image is detected at, px (None: no limit).

    Returns:
        A :class:`ReflectionAxesResult` for one image, else a :class:`ReflectionAxesBatch`.
    """
    img = check_image(image, "image", min_size=16)
    height, width = int(img.shape[-2]), int(img.shape[-1])
    work = working_copy(img, max_side, min_side)

    def one(b: int) -> ReflectionAxesResult:
        res = detect_one(work[b : b + 1], **kwargs)
        return res if work is img else to_input_pixels(res, height, width)

    if img.shape[0] == 1:
        return one(0)
    return ReflectionAxesBatch(tuple(one(b) for b in range(img.shape[0])))
