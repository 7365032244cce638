"""The input of the multi-view detector: photos of one scene from several viewpoints."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import torch

from torchsym.core.checks import check_dense, check_finite, check_unit_range
from torchsym.errors import InputFileError, InputShapeError, InputValueError

__all__ = ["IMAGE_SUFFIXES", "Views", "as_views"]

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".tif", ".tiff", ".bmp")
MIN_SIDE = 32  # px: the smallest photo side accepted


@dataclasses.dataclass(frozen=True)
class Views:
    """Photos of one static scene: file paths, or ``(3, H, W)`` / ``(1, H, W)`` float
    tensors in [0, 1] (written to files for COLMAP)."""

    paths: tuple[Path, ...] = ()
    images: tuple[torch.Tensor, ...] = ()

    def __len__(self) -> int:
        return len(self.paths) or len(self.images)

    @property
    def names(self) -> list[str]:
        """One unique file name per photo."""
        if self.paths:
            return _unique_names(self.paths)
        return [f"view_{i:03d}.png" for i in range(len(self.images))]


def _unique_names(paths: Sequence[Path]) -> list[str]:
    names, seen = [], set()
    for i, p in enumerate(paths):
        name = p.name if p.name not in seen else f"{i:03d}_{p.name}"
        seen.add(name)
        names.append(name)
    return names


def _check_tensor(v: torch.Tensor, i: int) -> torch.Tensor:
    """``v`` if it is a ``(C, H, W)`` float photo in [0, 1], C in {1, 3}, H, W >= MIN_SIDE."""
    name = f"images[{i}]"
    if v.dim() != 3 or v.shape[0] not in (1, 3) or min(v.shape[1:]) < MIN_SIDE:
        raise InputShapeError(f"{name}: expected (C, H, W) with C in (1, 3) and H, W >= {MIN_SIDE}, got {tuple(v.shape)}")
    if not v.is_floating_point():
        raise InputShapeError(f"{name}: expected a float tensor in [0, 1], got {v.dtype}")
    check_dense(v, name)
    check_unit_range(check_finite(v, name), name)
    return v


def _check_photo(p: Path) -> Path:
    """``p`` if its header reads as an image of at least MIN_SIDE pixels a side (read before
    COLMAP and OpenCV see it: they fail deep inside on smaller or broken files)."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(p) as im:
            w, h = im.size
    except (OSError, UnidentifiedImageError, ValueError) as exc:
        raise InputFileError(f"images: '{p}' cannot be read as a photo ({exc})") from None
    if min(w, h) < MIN_SIDE:
        raise InputShapeError(f"images: '{p}' is {w} x {h} pixels, expected height and width >= {MIN_SIDE}")
    return p


def as_views(views: Any) -> Views:
    """``views`` as :class:`Views`: a folder of photos, a list of photo paths, a list of
    image tensors, or a ``(V, C, H, W)`` tensor.

    Raises:
        InputFileError: a path does not exist or is not an image file.
        InputShapeError: tensors of the wrong shape.
        InputValueError: fewer than 2 photos.
    """
    if isinstance(views, Views):
        out = views
    elif isinstance(views, (str, Path)):
        folder = Path(views)
        if not folder.is_dir():
            raise InputFileError(f"images: expected a folder of photos or a list of them, got '{folder}'")
        paths = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file())
        out = Views(paths=tuple(_check_photo(p) for p in paths))
    elif isinstance(views, torch.Tensor):
        if views.dim() != 4 or views.shape[1] not in (1, 3):
            raise InputShapeError(f"images: expected (V, C, H, W) with C in (1, 3), got {tuple(views.shape)}")
        out = Views(images=tuple(_check_tensor(v, i) for i, v in enumerate(views.unbind(0))))
    elif isinstance(views, Sequence) and all(isinstance(v, (str, Path)) for v in views):
        paths = tuple(Path(v) for v in views)
        for p in paths:
            if not p.is_file():
                raise InputFileError(f"images: '{p}' is not a file")
            if p.suffix.lower() not in IMAGE_SUFFIXES:
                raise InputFileError(f"images: '{p}' is not a photo (expected one of {', '.join(IMAGE_SUFFIXES)})")
        out = Views(paths=tuple(_check_photo(p) for p in paths))
    elif isinstance(views, Sequence) and all(isinstance(v, torch.Tensor) for v in views):
        out = Views(images=tuple(_check_tensor(v, i) for i, v in enumerate(views)))
    else:
        raise InputShapeError(
            f"images: expected a folder, a list of photo paths or of (C, H, W) tensors, got {type(views).__name__}"
        )
    if len(out) < 2:
        raise InputValueError(f"images: expected at least 2 photos of the scene, got {len(out)}")
    return out
