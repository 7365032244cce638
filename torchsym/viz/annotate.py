"""Text on OpenCV pictures (BGR uint8 arrays), shared by the photo writers."""

from __future__ import annotations

import numpy as np

__all__ = ["banner", "titled"]


def banner(img: np.ndarray, text: str) -> np.ndarray:
    """Write ``text`` in black on a white band at the top of the BGR ``img (H, W, 3)``, in
    place (the font scaled to the width); returns ``img``."""
    import cv2

    scale = max(0.4, min(0.8, img.shape[1] / 500))
    (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
    cv2.rectangle(img, (0, 0), (min(img.shape[1], tw + 12), th + 12), (255, 255, 255), -1)
    cv2.putText(img, text, (6, th + 6), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 1, cv2.LINE_AA)
    return img


def titled(img: np.ndarray, title: str, legend: str = "") -> np.ndarray:
    """``img (H, W, 3)`` BGR (or ``(H, W)`` grey) under a white band holding ``title`` in
    black and ``legend`` (what the colours mean) in grey, each wrapped to the width; a new
    BGR array ``(H + band, W, 3)``, the picture itself untouched."""
    import cv2

    img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR) if img.ndim == 2 else img
    w = img.shape[1]
    scale = max(0.4, min(0.6, w / 900))
    rows: list[tuple[str, tuple[int, int, int]]] = []
    for text, colour in ((title, (0, 0, 0)), (legend, (90, 90, 90))):
        line = ""
        for word in text.split():
            trial = f"{line} {word}".strip()
            if line and cv2.getTextSize(trial, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)[0][0] > w - 12:
                rows.append((line, colour))
                line = word
            else:
                line = trial
        if line:
            rows.append((line, colour))
    step = cv2.getTextSize("Ag", cv2.FONT_HERSHEY_SIMPLEX, scale, 1)[0][1] + 8
    band = np.full((step * len(rows) + 8, w, 3), 255, np.uint8)
    for i, (text, colour) in enumerate(rows):
        cv2.putText(band, text, (6, step * (i + 1)), cv2.FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv2.LINE_AA)
    return np.concatenate([band, img], axis=0)
