"""Reading point clouds, meshes and images, and telling which kind an input is.

Mesh formats are parsed in NumPy (:mod:`torchsym.io.meshfiles`), text points and ``.npy``
through NumPy, images through OpenCV after Pillow has read their size from the header.
Files are only ever opened for reading. Every reader checks its limits before it
allocates (``max_points``, ``max_pixels``) and refuses NaN, infinite or stray coordinates,
naming the file.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.core.checks import check_dense, scale_problem
from torchsym.core.registry import IMAGE_SUFFIXES, MESH_SUFFIXES, POINT_SUFFIXES
from torchsym.errors import InputFileError, InputShapeError, InputValueError
from torchsym.io.meshfiles import parse_mesh_file
from torchsym.geometry.mesh import Mesh

__all__ = [
    "IMAGE_SUFFIXES",
    "MAX_PIXELS",
    "MAX_POINTS",
    "MESH_SUFFIXES",
    "POINT_SUFFIXES",
    "infer_kind",
    "load_input",
    "read_image",
    "read_mesh",
    "read_pointcloud",
]


#: default ``max_points`` of the readers: most points (rows, or mesh vertices) read from a file
MAX_POINTS = 20_000_000
#: default ``max_pixels`` of :func:`read_image`: most pixels (width x height) decoded, 50 megapixels
MAX_PIXELS = 50_000_000


def _existing(path: str | Path, name: str) -> Path:
    p = Path(path)
    if p.is_symlink() and not p.exists():
        raise InputFileError(f"{name}: {str(p)!r} is a symbolic link to nothing (a loop or a missing target)")
    if not p.exists():
        raise InputFileError(f"{name}: file {str(p)!r} does not exist")
    if not p.is_file():
        raise InputFileError(f"{name}: {str(p)!r} is not a file")
    return p


def _check_coords(arr: np.ndarray, p: Path, dtype: torch.dtype) -> torch.Tensor:
    """``arr (N, D)`` as a tensor of ``dtype``, refusing non-finite and stray coordinates."""
    t = torch.from_numpy(np.ascontiguousarray(arr)).to(dtype)
    bad = ~torch.isfinite(t)
    if bad.any():
        row, col = (int(i) for i in bad.nonzero()[0])
        raise InputValueError(
            f"path: {str(p)!r} holds {int(bad.sum())} NaN or infinite coordinates (first in row {row}, column {col}"
            f"{', a number too large for ' + str(dtype) if np.isfinite(arr[row, col]) else ''})"
        )
    problem = scale_problem(t)
    if problem is not None:
        raise InputValueError(f"path: {str(p)!r}: {problem}")
    return t


def _check_count(n: int, p: Path, max_points: int) -> None:
    if n > max_points:
        raise InputFileError(f"path: {str(p)!r} holds {n} points, more than max_points={max_points}")


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _strip_comment(line: str) -> str:
    return line.split("#", 1)[0].split("//", 1)[0].strip()


def _read_text_rows(p: Path, max_points: int) -> np.ndarray:
    """Rows of numbers from a text point file, as scanners and CloudCompare write them.

    Numbers are separated by whitespace, commas or semicolons (decided on the first data
    row; with semicolons a comma is a decimal mark, the spreadsheet convention; one
    separator ending every row is allowed), ``#`` and ``//`` start comments, a UTF-8
    byte-order mark is skipped, and a first row of column names (``X,Y,Z``; no field a
    number) or of the point count alone (Leica ``.pts``) is skipped as a header. Empty
    fields and later non-numeric rows are errors, never silently dropped. More than
    ``max_points`` lines are refused before any is parsed.
    """
    try:
        with open(p, "rb") as fh:
            n_lines = sum(chunk.count(b"\n") for chunk in iter(lambda: fh.read(1 << 24), b""))
    except OSError as exc:
        raise InputFileError(f"path: cannot read {str(p)!r} ({exc.strerror or exc})") from None
    if n_lines > max_points + 1:
        raise InputFileError(f"path: {str(p)!r} holds {n_lines} lines, more than max_points={max_points} points")
    try:
        with open(p, encoding="utf-8-sig") as fh:
            head: list[str] = []
            data_rows: list[int] = []
            for line in fh:  # up to the second data row
                if _strip_comment(line):
                    data_rows.append(len(head))
                head.append(line)
                if len(data_rows) >= 2:
                    break
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(f"path: cannot read {str(p)!r} as text ({exc})") from None
    if not data_rows:
        raise InputFileError(f"path: {str(p)!r} holds no points (no rows of numbers)")
    first = _strip_comment(head[data_rows[0]])
    tokens = [t for t in re.split(r"[\s,;]+", first) if t]
    # a header names every column: no token of it is a number; Leica's .pts starts with
    # the number of points alone on its line
    header = not any(_is_number(t) for t in tokens) or (
        len(tokens) == 1 and tokens[0].isdigit() and len(data_rows) > 1
        and len(_strip_comment(head[data_rows[1]]).split()) >= 3
    )
    skip = data_rows[0] + 1 if header else 0
    if header and len(data_rows) < 2:
        raise InputFileError(f"path: {str(p)!r} holds no points (a header row and no rows of numbers)")
    sample = _strip_comment(head[data_rows[1] if header else data_rows[0]])
    delimiter = ";" if ";" in sample else "," if "," in sample else None
    options: dict[str, Any] = {}
    if delimiter == ";":
        options["converters"] = lambda field: float(field.replace(",", "."))
    if delimiter is not None and sample.endswith(delimiter):  # rows ending in a separator
        options["usecols"] = range(sample.count(delimiter))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # numpy's "input contained no data"
            arr = np.loadtxt(p, delimiter=delimiter, comments=("#", "//"), skiprows=skip, ndmin=2,
                             encoding="utf-8-sig", **options)
    except (ValueError, UnicodeDecodeError, OverflowError) as exc:
        raise InputFileError(f"path: cannot read {str(p)!r} as rows of numbers ({exc})") from None
    if arr.size == 0:
        raise InputFileError(f"path: {str(p)!r} holds no points (no rows of numbers)")
    return arr


def _read_npy(p: Path, max_points: int) -> np.ndarray:
    """A 2-D real array from ``p``; shape and dtype are read (memory-mapped) before loading."""
    try:
        mapped = np.load(p, mmap_mode="r", allow_pickle=False)
    except Exception as exc:  # noqa: BLE001 -- a corrupt header raises anything from tokenize to TypeError
        raise InputFileError(f"path: cannot read {str(p)!r} as a NumPy array ({exc or type(exc).__name__})") from None
    shape, dtype = mapped.shape, mapped.dtype
    if len(shape) != 2 or not (np.issubdtype(dtype, np.integer) or np.issubdtype(dtype, np.floating)):
        raise InputFileError(f"path: expected {str(p)!r} to hold a real (N, D) array, got {dtype} {shape}")
    _check_count(shape[0], p, max_points)
    if shape[0] * shape[1] > 3 * max_points:
        raise InputFileError(f"path: {str(p)!r} holds {shape[0]} x {shape[1]} numbers, more than 3 x max_points={3 * max_points}")
    return np.array(mapped, dtype=dtype.newbyteorder("="))  # native byte order for torch


def _read_points_array(p: Path, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    """``(points (N, D), faces (F, 3))`` of any point or mesh file, limits checked."""
    suffix = p.suffix.lower()
    faces = np.zeros((0, 3), dtype=np.int64)
    if suffix == ".npy":
        arr = _read_npy(p, max_points)
    elif suffix in (".xyz", ".txt", ".pts"):
        arr = _read_text_rows(p, max_points)
        if arr.shape[1] < 3:
            raise InputFileError(f"path: expected at least 3 columns (x y z) in {str(p)!r}, got {arr.shape[1]}")
        arr = arr[:, :3]
    elif suffix in MESH_SUFFIXES:
        arr, faces = parse_mesh_file(p, max_points)
    else:
        raise InputFileError(f"path: expected one of {', '.join(POINT_SUFFIXES)} for a point cloud, got {str(p)!r}")
    if arr.shape[0] == 0:
        raise InputFileError(f"path: {str(p)!r} holds no points")
    _check_count(arr.shape[0], p, max_points)
    return arr, faces


def read_pointcloud(path: str | Path, *, dtype: torch.dtype = torch.float32, max_points: int = MAX_POINTS) -> torch.Tensor:
    """Read the points of a ``.ply .obj .off .stl .xyz .txt .pts .npy`` file as ``(N, D)``.

    Mesh formats give their vertices. ``.xyz``/``.txt``/``.pts`` are text with one point
    per row, numbers separated by whitespace, commas or semicolons, ``#`` or ``//``
    comments and an optional header row of column names (extra columns such as normals
    or colours after the first three are dropped; see :func:`_read_text_rows`); ``.npy``
    must hold a 2-D real array.

    Args:
        path: the file.
        dtype: floating dtype of the result.
        max_points: most points read (default :data:`MAX_POINTS`, 20 million); checked
            from the header or line count before the points are parsed.

    Raises:
        InputFileError: missing, unreadable, not a point cloud, or past ``max_points``.
        InputValueError: NaN, infinite or stray coordinates (see
            :func:`torchsym.core.checks.scale_problem`).
    """
    p = _existing(path, "path")
    arr, _ = _read_points_array(p, max_points)
    return _check_coords(arr, p, dtype)


def read_mesh(path: str | Path, *, dtype: torch.dtype = torch.float32, max_points: int = MAX_POINTS) -> Mesh:
    """Read a triangle mesh (``.off .obj .ply .stl``; polygons split into triangle fans).

    ``max_points`` bounds the vertices (default :data:`MAX_POINTS`) and four times it the
    faces; both are checked before the file is parsed past its header.

    Raises:
        InputFileError: missing, unreadable, malformed (e.g. a face index outside the
            vertices), past the limits, or holding no triangles.
        InputValueError: NaN, infinite or stray vertex coordinates.
    """
    p = _existing(path, "path")
    if p.suffix.lower() not in MESH_SUFFIXES:
        raise InputFileError(f"path: expected one of {', '.join(MESH_SUFFIXES)} for a mesh, got {str(p)!r}")
    v, f = _read_points_array(p, max_points)
    if f.shape[0] == 0:
        raise InputFileError(f"path: {str(p)!r} holds no triangles (a point cloud, not a mesh)")
    return Mesh(_check_coords(v, p, dtype), torch.from_numpy(f))


def _image_size(p: Path, max_pixels: int) -> None:
    """Refuse ``p`` unless Pillow reads a width and height from its header (no pixels are
    decoded) and width x height <= ``max_pixels``."""
    import warnings

    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(p) as im:
                width, height = im.size
    except Image.DecompressionBombError as exc:
        raise InputFileError(f"path: {str(p)!r} is larger than max_pixels={max_pixels} ({exc})") from None
    except Exception as exc:  # noqa: BLE001 -- Pillow's header parsers raise many types on corrupt files
        raise InputFileError(f"path: cannot decode {str(p)!r} as an image ({exc or type(exc).__name__})") from None
    if width * height > max_pixels:
        raise InputFileError(
            f"path: {str(p)!r} is {width} x {height} = {width * height} pixels, more than max_pixels={max_pixels}"
        )


def read_image(path: str | Path, *, max_pixels: int = MAX_PIXELS) -> torch.Tensor:
    """Read an image as an RGB ``(3, H, W)`` float tensor in [0, 1] (grayscale kept as ``(1, H, W)``).

    Args:
        path: the file (``.png .jpg .bmp .tif .webp .pgm .ppm``...).
        max_pixels: most pixels (width x height) decoded; default :data:`MAX_PIXELS`
            (50 megapixels, about 600 MB as a float RGB tensor). The size is read from the
            file's header before anything is decoded.

    Raises:
        InputFileError: missing, not a decodable image, or more than ``max_pixels``.
    """
    import cv2

    p = _existing(path, "path")
    _image_size(p, max_pixels)
    data = np.fromfile(str(p), dtype=np.uint8)
    try:
        img = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    except cv2.error:
        img = None
    if img is None:
        raise InputFileError(f"path: cannot decode {str(p)!r} as an image")
    if img.dtype == np.uint16:
        scale = 65535.0
    elif img.dtype == np.uint8:
        scale = 255.0
    else:
        scale = 1.0
    img = img.astype(np.float32) / scale
    if not np.isfinite(img).all():
        raise InputValueError(f"path: {str(p)!r} holds NaN or infinite pixel values")
    if img.ndim == 2:
        return torch.from_numpy(img)[None]
    if img.shape[2] == 4:
        img = img[:, :, :3]
    img = img[:, :, ::-1]  # BGR -> RGB
    return torch.from_numpy(np.ascontiguousarray(img)).permute(2, 0, 1).contiguous()


def infer_kind(data: Any) -> str:
    """The input kind of an in-memory input: ``pointcloud``, ``points``, ``image`` or ``mesh``.

    ``(N, 3)`` tensors are point clouds, other ``(N, D)`` tensors are d-dimensional point
    sets, ``(C, H, W)`` and ``(B, C, H, W)`` tensors with ``C`` in {1, 3} are images.
    """
    if isinstance(data, Mesh):
        return "mesh"
    if isinstance(data, np.ndarray):
        data = torch.from_numpy(data) if data.dtype.isnative and data.dtype != object else torch.zeros(data.shape)
    if isinstance(data, torch.Tensor):
        check_dense(data, "input")
        if data.dim() == 2:
            return "pointcloud" if data.shape[1] == 3 else "points"
        if data.dim() in (3, 4) and data.shape[-3] in (1, 3):
            return "image"
        hint = " (an (H, W, C) photo array must be uint8 or uint16 to be read as channels-last)" if data.dim() == 3 else ""
        raise InputShapeError(
            f"input: expected (N, D) points, (C, H, W) or (B, C, H, W) image, or a Mesh, got {tuple(data.shape)}{hint}"
        )
    raise InputShapeError(
        f"input: expected a path, tensor, array, Mesh, trimesh or Open3D geometry or PIL image, got {type(data).__name__}"
    )


def load_input(path: str | Path, kind: str | None = None, *, max_points: int = MAX_POINTS,
               max_pixels: int = MAX_PIXELS) -> tuple[str, Any]:
    """Read a file and return ``(kind, data)``; the kind comes from the suffix and contents.

    Mesh formats holding triangles are ``mesh`` unless ``kind="pointcloud"`` asks for the
    vertices alone; mesh formats without triangles, ``.xyz`` and 3-column ``.npy`` are
    ``pointcloud``; other ``.npy`` widths are ``points``; image suffixes are ``image``.
    ``max_points`` and ``max_pixels`` are the readers' limits.
    """
    p = _existing(path, "input")
    suffix = p.suffix.lower()
    if suffix in IMAGE_SUFFIXES:
        if kind not in (None, "image"):
            raise InputFileError(f"input: {str(p)!r} is an image, but kind {kind!r} was asked for")
        return "image", read_image(p, max_pixels=max_pixels)
    if suffix not in POINT_SUFFIXES:
        known = ", ".join(IMAGE_SUFFIXES + POINT_SUFFIXES)
        raise InputFileError(f"input: cannot tell what {str(p)!r} holds from its suffix; expected one of {known}")
    arr, f = _read_points_array(p, max_points)
    pts = _check_coords(arr, p, torch.float32)
    if suffix in MESH_SUFFIXES:
        if kind in ("pointcloud", "points") or (kind is None and f.shape[0] == 0):
            return "pointcloud", pts
        if kind not in (None, "mesh"):
            raise InputFileError(f"input: {str(p)!r} is a mesh, but kind {kind!r} was asked for")
        if f.shape[0] == 0:
            raise InputFileError(f"input: {str(p)!r} holds no triangles (a point cloud, not a mesh)")
        return "mesh", Mesh(pts, torch.from_numpy(f))
    found = "pointcloud" if pts.shape[1] == 3 else "points"
    if kind not in (None, found) and not (kind == "points" and found == "pointcloud"):
        raise InputFileError(f"input: {str(p)!r} holds a {found}, but kind {kind!r} was asked for")
    return (kind or found), pts
