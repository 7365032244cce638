"""Harris corners of an image as a point set (the corner points of thesis Sec. 7.4.4)."""

from __future__ import annotations

from typing import Any

import kornia
import torch
import torch.nn.functional as F

from torchsym.core.checks import check_image
from torchsym.errors import InputShapeError

__all__ = ["harris_corners"]


def harris_corners(image: Any, n_corners: int = 200, harris_k: float = 0.04, nms_size: int = 5) -> torch.Tensor:
    """The ``n_corners`` strongest Harris corners of an image, ``(K, 2)`` as ``(x, y)`` pixels.

    Local maxima of :func:`kornia.feature.harris_response` on the grey image in
    ``nms_size x nms_size`` windows, positive and at least 1% of the largest response,
    strongest first.

    Args:
        image: ``(H, W)``, ``(C, H, W)`` or ``(1, C, H, W)`` image.
        n_corners: largest number of corners returned.
        harris_k: the Harris detector's ``k``.
        nms_size: odd window size of the non-maximum suppression, in pixels.

    Raises:
        InputShapeError: not a single image, or a side under 4 pixels.
    """
    img = check_image(image, "image", min_size=4)  # kornia pads the 7 x 7 window by 3
    if img.shape[0] != 1:
        raise InputShapeError(f"image: expected a single image (B = 1), got {tuple(img.shape)}")
    gray = img.mean(1, keepdim=True)  # (1, 1, H, W)
    resp = kornia.feature.harris_response(gray, k=harris_k)[0, 0]  # (H, W)
    peak = F.max_pool2d(resp[None, None], nms_size, stride=1, padding=nms_size // 2)[0, 0]
    keep = (resp == peak) & (resp > 0) & (resp >= 0.01 * resp.max())
    rows, cols = keep.nonzero(as_tuple=True)
    order = resp[rows, cols].argsort(descending=True)[:n_corners]
    return torch.stack([cols[order], rows[order]], 1).to(img.dtype)  # (K, 2)
