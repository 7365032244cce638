"""The part of a photograph the axis stage scores: the image less its constant frame and a
border band.

A constant frame (zero padding, a white mat) and the image's own border are symmetric
structures of their own: the frame's inner edges pair up about the image's middle lines, and
smoothing or ``avg_pool`` with zero padding fades every side alike. Neither says anything
about the subject, so every score of the stage (the candidates' mirrored-gradient evidence,
the photometric test and its chance level) is taken on the content box: the rows and
columns of a constant frame stripped from each side, then a band of ``margin`` more.
"""

from __future__ import annotations

import torch

__all__ = ["content_box"]


def _frame_depth(lines: torch.Tensor, tolerance: float) -> int:
    """How many of ``lines (N, C, L)`` (from the border inwards) belong to a frame: the run
    constant at the first one's colour, and, when there is one, its smoothed edge (the
    ramp from the frame's colour to the content's: as many lines again past the edge, where
    the lines' mean crosses half-way, as before it)."""
    ref = lines[0].mean(-1, keepdim=True)  # (C, 1): the frame's colour
    flat = ((lines - ref[None]).abs().amax((1, 2)) <= tolerance)  # (N,)
    bad = (~flat).nonzero()
    run = int(bad[0]) if bad.numel() else int(lines.shape[0])
    if run == 0 or run >= lines.shape[0] - 1:
        return run
    means = lines.mean((1, 2))  # (N,)
    frame, content = float(means[0]), float(means[run:].median())
    if abs(content - frame) <= tolerance:
        return run
    past = ((means[run:] - (frame + content) / 2) * (content - frame) >= 0).nonzero()  # lines past half-way
    edge = run + (int(past[0]) if past.numel() else 0)
    return min(edge + (edge - run), int(lines.shape[0]))


def content_box(image: torch.Tensor, *, tolerance: float, margin: float, min_margin: int) -> tuple[int, int, int, int]:
    """``(y0, y1, x0, x1)``: the rows ``y0:y1`` and columns ``x0:x1`` of ``image (C, H, W)``
    the axis stage scores.

    Args:
        image: ``(C, H, W)`` float image in [0, 1].
        tolerance: a border row or column within this of the first one's colour at every
            pixel belongs to the frame.
        margin: the band left out inside the frame (or the image's border), times the
            shorter side.
        min_margin: the least band, px.

    Returns:
        The box; the whole image less the band when there is no frame, and the whole image
        when what is left would be under 16 px a side (a frame around next to nothing).
    """
    c, h, w = image.shape
    img = image.float()
    top = _frame_depth(img.permute(1, 0, 2), tolerance)  # rows from the top: (H, C, W)
    bottom = _frame_depth(img.flip(1).permute(1, 0, 2), tolerance)
    left = _frame_depth(img.permute(2, 0, 1), tolerance)  # columns from the left: (W, C, H)
    right = _frame_depth(img.flip(2).permute(2, 0, 1), tolerance)
    band = max(int(min_margin), round(margin * min(h, w)))
    y0, y1, x0, x1 = top + band, h - bottom - band, left + band, w - right - band
    if y1 - y0 < 16 or x1 - x0 < 16:
        return 0, h, 0, w
    return y0, y1, x0, x1
