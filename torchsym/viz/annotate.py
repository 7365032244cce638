"""Text on OpenCV pictures (BGR uint8 arrays), shared by the photo writers."""

from __future__ import annotations

import numpy as np

__all__ = ["banner"]


def banner(img: np.ndarray, text: str) -> np.ndarray:
    """Write ``text`` in black on a white band at the top of the BGR ``img (H, W, 3)``, in
    place (the font scaled to the width); returns ``img``."""
    import cv2

    scale = max(0.4, min(0.8, img.shape[1] / 500))
    (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
    cv2.rectangle(img, (0, 0), (min(img.shape[1], tw + 12), th + 12), (255, 255, 255), -1)
    cv2.putText(img, text, (6, th + 6), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 1, cv2.LINE_AA)
    return img
