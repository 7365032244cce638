"""Input checks with messages that name the argument, what was expected and what came.

These helpers are the only place user input is validated; solvers call them first and
then trust their tensors. None of them uses ``assert``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

from torchsym.errors import InputShapeError, InputValueError

__all__ = [
    "as_tensor",
    "check_dense",
    "check_finite",
    "check_image",
    "check_in_range",
    "check_int",
    "check_points",
    "check_positive",
    "check_scale",
    "check_unit_range",
    "scale_problem",
]


def _shape(x: Any) -> str:
    shape = getattr(x, "shape", None)
    if shape is None:
        return type(x).__name__
    return "(" + ", ".join(str(int(s)) for s in shape) + ")"


def as_tensor(
    x: Any,
    name: str,
    *,
    dtype: torch.dtype | None = None,
    device: torch.device | str | None = None,
) -> torch.Tensor:
    """Turn ``x`` (tensor, NumPy array or nested list) into a floating-point tensor.

    Integer and boolean tensors and arrays become ``torch.get_default_dtype()``; nested
    lists become float64; floating input keeps its dtype unless ``dtype`` is given. Raises :class:`InputShapeError` for
    anything that is not numeric.
    """
    if isinstance(x, torch.Tensor):
        t = check_dense(x, name)
    elif isinstance(x, np.ndarray):
        if not (np.issubdtype(x.dtype, np.number) or x.dtype == np.bool_):
            raise InputShapeError(f"{name}: expected a numeric array, got dtype {x.dtype}")
        if not x.dtype.isnative:
            x = x.astype(x.dtype.newbyteorder("="))
        try:
            t = torch.from_numpy(np.ascontiguousarray(x))
        except TypeError:
            raise InputShapeError(f"{name}: expected a float, integer or boolean array, got dtype {x.dtype}") from None
    elif isinstance(x, (list, tuple)):
        try:
            t = torch.as_tensor(np.asarray(x, dtype=np.float64))
        except (TypeError, ValueError, OverflowError) as exc:
            raise InputShapeError(f"{name}: expected a numeric array, got {type(x).__name__} ({exc})") from None
    else:
        raise InputShapeError(f"{name}: expected a tensor or array, got {type(x).__name__}")
    if t.is_complex():
        raise InputShapeError(f"{name}: expected real numbers, got dtype {t.dtype}")
    if dtype is not None:
        t = t.to(dtype)
    elif not t.is_floating_point():
        t = t.to(torch.get_default_dtype())
    if device is not None:
        t = t.to(device)
    return t


def check_dense(t: torch.Tensor, name: str) -> torch.Tensor:
    """Raise :class:`InputShapeError` unless ``t`` is a dense (strided) tensor holding data
    (not sparse, not on the ``meta`` device); return ``t``."""
    if t.layout != torch.strided:
        raise InputShapeError(f"{name}: expected a dense tensor, got layout {t.layout}; call .to_dense() first")
    if t.is_meta:
        raise InputShapeError(f"{name}: expected a tensor holding data, got one on the meta device")
    return t


def scale_problem(points: torch.Tensor) -> str | None:
    """What makes the coordinates of ``points (..., N, D)`` unusable in their dtype, or None.

    Two cases: a point whose distance from the median point (largest coordinate
    difference) exceeds the median such distance by more than ``1 / eps`` of the dtype,
    so the rest of the cloud is below its rounding error (a stray value such as 1e20);
    or coordinates whose squares summed over the points overflow the dtype.
    """
    if not points.is_floating_point() or points.numel() == 0 or points.dim() < 2:
        return None
    t = points.detach().reshape(-1, points.shape[-1]).to(torch.float64)  # (M, D)
    finfo = torch.finfo(torch.promote_types(points.dtype, torch.float32))  # solvers compute in >= float32
    if t.shape[0] >= 3:
        dist = (t - t.median(dim=0).values).abs().amax(dim=1)  # (M,)
        typical, far = float(dist.median()), float(dist.max())
        if typical > 0 and far * finfo.eps > typical:
            i = int(dist.argmax())
            return (f"point {i} lies {far:.3g} from the median point, {far / typical:.2g} times the median "
                    f"distance {typical:.3g} of the points: a coordinate far outside the rest (a stray value?)")
    biggest = float(t.abs().max())
    if biggest > math.sqrt(finfo.max / t.numel()):
        return (f"coordinates up to {biggest:.3g} overflow {torch.promote_types(points.dtype, torch.float32)} in sums of squares over "
                f"{t.numel()} entries; rescale the input")
    return None


def check_scale(points: torch.Tensor, name: str) -> torch.Tensor:
    """Raise :class:`InputValueError` where :func:`scale_problem` finds one; return ``points``."""
    problem = scale_problem(points)
    if problem is not None:
        raise InputValueError(f"{name}: {problem}")
    return points


def check_finite(t: torch.Tensor, name: str) -> torch.Tensor:
    """Raise :class:`InputValueError` if ``t`` holds NaN or infinite entries."""
    if t.numel() and not bool(torch.isfinite(t).all()):
        bad = (~torch.isfinite(t)).nonzero()
        n_bad = int(bad.shape[0])
        first = tuple(int(i) for i in bad[0])
        raise InputValueError(
            f"{name}: expected finite values, got {n_bad} NaN or infinite entries (first at index {first})"
        )
    return t


def check_points(
    points: Any,
    name: str = "points",
    *,
    dim: int | None = None,
    min_dim: int = 1,
    min_points: int = 1,
    batched: bool = False,
    dtype: torch.dtype | None = None,
) -> torch.Tensor:
    """Validate a point set and return it as a floating tensor.

    Args:
        points: ``(N, D)`` points, or ``(B, N, D)`` when ``batched``.
        name: the argument's name, used in messages.
        dim: required ``D`` (e.g. 3 for a point cloud), or None for any ``D >= min_dim``.
        min_dim: smallest ``D`` accepted when ``dim`` is None.
        min_points: smallest ``N`` accepted.
        batched: accept a leading batch dimension.
        dtype: convert to this dtype.

    Raises:
        InputShapeError: wrong number of dimensions, ``D`` or ``N``.
        InputValueError: NaN or infinite coordinates.
    """
    t = as_tensor(points, name, dtype=dtype)
    want_nd = 3 if batched else 2
    d_text = f"D = {dim}" if dim is not None else f"D >= {min_dim}"
    expected = f"{'(B, N, D)' if batched else '(N, D)'} with {d_text} and N >= {min_points}"
    if t.dim() != want_nd:
        raise InputShapeError(f"{name}: expected {expected}, got {_shape(t)}")
    n, d = int(t.shape[-2]), int(t.shape[-1])
    if (dim is not None and d != dim) or (dim is None and d < min_dim) or n < min_points:
        raise InputShapeError(f"{name}: expected {expected}, got {_shape(t)}")
    return check_finite(t, name)


def check_image(image: Any, name: str = "image", *, min_size: int = 1) -> torch.Tensor:
    """Validate an image and return it as a float ``(B, C, H, W)`` tensor.

    Accepts ``(H, W)``, ``(C, H, W)`` or ``(B, C, H, W)`` with ``C`` in {1, 3}. Integer
    images (e.g. ``uint8``) are scaled to [0, 1].

    Raises:
        InputShapeError: wrong rank, channel count or a side shorter than ``min_size``.
        InputValueError: NaN or infinite pixels.
    """
    if isinstance(image, torch.Tensor) and image.dtype == torch.bool:
        image = image.float()
    raw = as_tensor(image, name)
    src_dtype = image.dtype if isinstance(image, (torch.Tensor, np.ndarray)) else None
    t = raw
    if t.dim() == 2:
        t = t[None, None]
    elif t.dim() == 3:
        t = t[None]
    elif t.dim() != 4:
        raise InputShapeError(f"{name}: expected (H, W), (C, H, W) or (B, C, H, W), got {_shape(raw)}")
    if t.shape[1] not in (1, 3):
        raise InputShapeError(f"{name}: expected 1 or 3 channels in (B, C, H, W), got {_shape(raw)}")
    if t.shape[-1] < min_size or t.shape[-2] < min_size:
        raise InputShapeError(f"{name}: expected height and width >= {min_size}, got {_shape(raw)}")
    if src_dtype is not None and src_dtype in (torch.uint8, np.uint8, np.dtype("uint8")):
        t = t / 255.0
    elif src_dtype is not None and src_dtype in (torch.uint16, np.dtype("uint16")):
        t = t / 65535.0
    return check_finite(t, name)


def check_unit_range(t: torch.Tensor, name: str, *, tol: float = 1e-3) -> torch.Tensor:
    """Raise :class:`InputValueError` unless the values of ``t`` lie in [0, 1] (to ``tol``);
    return ``t`` clamped to [0, 1]. For float images, whose methods read [0, 1] intensities
    (a 0-255 float image would silently saturate)."""
    if t.numel():
        lo, hi = float(t.min()), float(t.max())
        if lo < -tol or hi > 1 + tol:
            raise InputValueError(
                f"{name}: expected intensities in [0, 1] (or a uint8 image), got values in [{lo:.4g}, {hi:.4g}]"
            )
    return t.clamp(0, 1)


def check_int(value: Any, name: str, *, minimum: int | None = None) -> int:
    """Return ``value`` as an int, raising :class:`InputValueError` if it is not one."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InputValueError(f"{name}: expected an integer, got {value!r}")
    if minimum is not None and value < minimum:
        raise InputValueError(f"{name}: expected an integer >= {minimum}, got {value}")
    return int(value)


def check_positive(value: Any, name: str, *, allow_zero: bool = False) -> float:
    """Return ``value`` as a float, raising :class:`InputValueError` unless it is > 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputValueError(f"{name}: expected a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise InputValueError(f"{name}: expected a {'non-negative' if allow_zero else 'positive'} number, got {value!r}")
    return v


def check_in_range(value: Any, name: str, low: float, high: float) -> float:
    """Return ``value`` as a float, raising :class:`InputValueError` unless low <= value <= high."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputValueError(f"{name}: expected a number in [{low}, {high}], got {value!r}")
    v = float(value)
    if not (low <= v <= high):
        raise InputValueError(f"{name}: expected a number in [{low}, {high}], got {value!r}")
    return v
