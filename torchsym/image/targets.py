"""Training targets for learned axis detectors: axis heat maps and orientation labels.

Segments are ``(B, S, 4)`` rows ``(x1, y1, x2, y2)`` in pixels, ``x`` to the right and ``y``
down, with pixel ``(row r, column c)`` centred at ``(x, y) = (c, r)`` (as PIL's
``ImageDraw.line`` places them); a ``(B, S)`` mask marks real segments.

Heat-map modes (:func:`axis_heatmap`):

- ``"gaussian"``: ``exp(-d^2 / (2 sigma^2))`` of the distance ``d`` to the nearest segment.
- ``"pmcnet"``: PMCNet's target (``ahyunSeo/PMCNet`` ``dataset.py``): the axes drawn one
  pixel wide, blurred by ``cv2.GaussianBlur(axis, (5, 5), cv2.BORDER_DEFAULT)`` (that third
  argument is ``sigmaX``, and ``BORDER_DEFAULT == 4``: a 5 x 5 Gaussian of sigma 4 with
  reflect-101 borders), divided by ``max + 1e-5``.
- ``"equisym"``: EquiSym's (``ahyunSeo/EquiSym`` ``dendi_loader.py``): the same blur,
  clipped at ``0.21260943`` (the blurred value on an isolated straight line: the centre
  tap of the 5-tap sigma-4 kernel) so crossings do not stand out, then divided by
  ``max + 1e-5``.

The one-pixel line is drawn softly, ``max(0, 1 - d)``, which equals the rasterised line for
axis-aligned segments with integer ends and makes every mode differentiable in the end
points. Orientation labels (:func:`orientation_labels`) follow EquiSym's
``process_theta_ref``.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F

from torchsym.errors import InputShapeError, InputValueError

__all__ = ["HEATMAP_MODES", "axis_heatmap", "orientation_bins", "orientation_labels", "segment_distance"]

HEATMAP_MODES = ("gaussian", "pmcnet", "equisym")
EQUISYM_CLIP = 0.21260943  # ahyunSeo/EquiSym dendi_loader.py: the blurred value on a straight line


def _check(segments: torch.Tensor, mask: torch.Tensor | None, size: tuple[int, int]) -> torch.Tensor:
    if not isinstance(segments, torch.Tensor) or segments.dim() != 3 or segments.shape[-1] != 4 or not segments.is_floating_point():
        raise InputShapeError(f"segments: expected a floating (B, S, 4) tensor, got {getattr(segments, 'shape', type(segments).__name__)}")
    if len(size) != 2 or min(size) < 1:
        raise InputValueError(f"size: expected (H, W) with H, W >= 1, got {size}")
    if mask is None:
        return torch.ones(segments.shape[:2], dtype=torch.bool, device=segments.device)
    if mask.shape != segments.shape[:2]:
        raise InputShapeError(f"mask: expected {tuple(segments.shape[:2])}, got {tuple(mask.shape)}")
    return mask.bool()


def segment_distance(segments: torch.Tensor, size: tuple[int, int]) -> torch.Tensor:
    """``(B, S, H, W)`` distance in pixels from every pixel centre to every segment (differentiable)."""
    h, w = size
    ys = torch.arange(h, dtype=segments.dtype, device=segments.device).view(1, 1, h, 1)
    xs = torch.arange(w, dtype=segments.dtype, device=segments.device).view(1, 1, 1, w)
    x1, y1, x2, y2 = (segments[..., i, None, None] for i in range(4))  # (B, S, 1, 1)
    dx, dy = x2 - x1, y2 - y1
    length2 = (dx * dx + dy * dy).clamp_min(torch.finfo(segments.dtype).eps)
    t = (((xs - x1) * dx + (ys - y1) * dy) / length2).clamp(0.0, 1.0)
    ex, ey = xs - (x1 + t * dx), ys - (y1 + t * dy)
    return (ex * ex + ey * ey + torch.finfo(segments.dtype).tiny).sqrt()


def _cv2_gaussian(ksize: int, sigma: float, dtype, device) -> torch.Tensor:
    x = torch.arange(ksize, dtype=torch.float64) - (ksize - 1) / 2
    k = torch.exp(-(x * x) / (2 * sigma * sigma))
    return (k / k.sum()).to(dtype=dtype, device=device)


def _blur(img: torch.Tensor, ksize: int = 5, sigma: float = 4.0) -> torch.Tensor:
    """cv2.GaussianBlur with BORDER_REFLECT_101 (torch's ``"reflect"`` padding), separable."""
    k = _cv2_gaussian(ksize, sigma, img.dtype, img.device)
    r = ksize // 2
    h, w = img.shape[-2:]
    mode = "reflect" if min(h, w) > r else "replicate"
    out = F.pad(img, (r, r, r, r), mode=mode)
    out = F.conv2d(out, k.view(1, 1, 1, ksize))
    return F.conv2d(out, k.view(1, 1, ksize, 1))


def axis_heatmap(
    segments: torch.Tensor,
    size: tuple[int, int],
    mask: torch.Tensor | None = None,
    *,
    mode: str = "gaussian",
    sigma: float = 2.0,
) -> torch.Tensor:
    """``(B, 1, H, W)`` heat map of the axes ``segments (B, S, 4)`` in ``[0, 1]``, differentiable in the end points.

    Args:
        segments: ``(B, S, 4)`` axis segments ``(x1, y1, x2, y2)`` in pixels.
        size: ``(H, W)`` of the map.
        mask: ``(B, S)`` True for real segments; an image with none gives zeros.
        mode: ``"gaussian"``, ``"pmcnet"`` or ``"equisym"`` (module docstring).
        sigma: width in pixels of the ``"gaussian"`` mode.
    """
    valid = _check(segments, mask, size)
    if mode not in HEATMAP_MODES:
        raise InputValueError(f"mode: expected one of {HEATMAP_MODES}, got {mode!r}")
    if not sigma > 0:
        raise InputValueError(f"sigma: expected > 0, got {sigma}")
    dist = segment_distance(segments, size)  # (B, S, H, W)
    if mode == "gaussian":
        profile = torch.exp(-(dist * dist) / (2 * sigma * sigma))
    else:
        profile = (1.0 - dist).clamp_min(0.0)  # the one-pixel line, drawn softly
    profile = profile * valid[..., None, None].to(profile.dtype)
    if segments.shape[1] == 0:
        return torch.zeros(segments.shape[0], 1, *size, dtype=segments.dtype, device=segments.device)
    line = profile.amax(dim=1, keepdim=True)  # (B, 1, H, W): union of the axes
    if mode == "gaussian":
        return line
    blurred = _blur(line)
    if mode == "equisym":
        blurred = blurred.clamp_max(EQUISYM_CLIP)
    return blurred / (blurred.amax(dim=(-1, -2), keepdim=True) + 1e-5)


def orientation_bins(segments: torch.Tensor, n_theta: int = 8) -> torch.Tensor:
    """``(B, S, n_theta)`` EquiSym orientation label of each segment (two neighbouring bins, weights summing to 1).

    ``theta = atan(-(y2 - y1) / (x2 - x1))`` in degrees (90 for a vertical segment; the
    minus sign turns image ``y`` up), bins ``180 / n_theta`` degrees apart; with
    ``k = floor(theta / d)`` and ``a = k + 1 - theta / d``, bin ``k mod n`` gets ``a`` and
    bin ``k + 1 mod n`` gets ``1 - a`` (``process_theta_ref`` in ``ahyunSeo/EquiSym``
    ``dendi_loader.py``).
    """
    if n_theta < 1:
        raise InputValueError(f"n_theta: expected >= 1, got {n_theta}")
    dx = segments[..., 2] - segments[..., 0]
    dy = segments[..., 3] - segments[..., 1]
    theta = torch.where(dx == 0, torch.full_like(dx, 90.0), torch.rad2deg(torch.atan(-dy / torch.where(dx == 0, torch.ones_like(dx), dx))))
    d = 180.0 / n_theta
    k = torch.floor(theta / d)
    a = k + 1 - theta / d
    out = torch.zeros(*segments.shape[:-1], n_theta, dtype=segments.dtype, device=segments.device)
    i1 = (k.long() % n_theta).unsqueeze(-1)
    i2 = ((k.long() + 1) % n_theta).unsqueeze(-1)
    out = out.scatter_add(-1, i1, a.unsqueeze(-1))
    return out.scatter_add(-1, i2, (1 - a).unsqueeze(-1))


def orientation_labels(
    segments: torch.Tensor,
    size: tuple[int, int],
    mask: torch.Tensor | None = None,
    *,
    n_theta: int = 8,
    width: float = 1.0,
) -> torch.Tensor:
    """``(B, n_theta, H, W)`` EquiSym orientation labels: at pixels within ``width / 2`` of an
    axis, the :func:`orientation_bins` of the nearest one; zeros elsewhere.

    EquiSym draws the axes one pixel wide and labels the drawn pixels (later segments
    over earlier ones); here the nearest segment decides, which agrees except at crossings.
    Not differentiable (a classification target).
    """
    valid = _check(segments, mask, size)
    if not width > 0 or not math.isfinite(width):
        raise InputValueError(f"width: expected a finite value > 0, got {width}")
    b = segments.shape[0]
    if segments.shape[1] == 0:
        return torch.zeros(b, n_theta, *size, dtype=segments.dtype, device=segments.device)
    with torch.no_grad():
        dist = segment_distance(segments.detach(), size).masked_fill(~valid[..., None, None], float("inf"))
        best, which = dist.min(dim=1)  # (B, H, W)
        bins = orientation_bins(segments.detach(), n_theta)  # (B, S, n)
        lab = torch.gather(bins, 1, which.reshape(b, -1, 1).expand(-1, -1, n_theta))  # (B, H W, n)
        lab = lab * (best.reshape(b, -1, 1) <= width / 2).to(lab.dtype)
        return lab.reshape(b, *size, n_theta).permute(0, 3, 1, 2).contiguous()
