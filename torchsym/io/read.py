"""Reading point clouds, meshes and images, and telling which kind an input is.

Meshes and mesh-format point clouds go through pymeshlab; ``.xyz`` and ``.npy`` through
NumPy; images through OpenCV. Files are only ever opened for reading.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.errors import InputFileError, InputShapeError
from torchsym.geometry.mesh import Mesh

__all__ = [
    "IMAGE_SUFFIXES",
    "MESH_SUFFIXES",
    "POINT_SUFFIXES",
    "infer_kind",
    "load_input",
    "read_image",
    "read_mesh",
    "read_pointcloud",
]

MESH_SUFFIXES = (".ply", ".obj", ".off", ".stl")
POINT_SUFFIXES = MESH_SUFFIXES + (".xyz", ".npy", ".txt", ".pts")
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm")


def _existing(path: str | Path, name: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise InputFileError(f"{name}: file {str(p)!r} does not exist")
    if not p.is_file():
        raise InputFileError(f"{name}: {str(p)!r} is not a file")
    return p


def _load_meshlab(p: Path, name: str) -> tuple[np.ndarray, np.ndarray]:
    import pymeshlab

    ms = pymeshlab.MeshSet()
    try:
        ms.load_new_mesh(str(p))
    except pymeshlab.PyMeshLabException as exc:
        raise InputFileError(f"{name}: cannot read {str(p)!r} as a {p.suffix} mesh or point cloud ({exc})") from None
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), dtype=np.float64), np.asarray(m.face_matrix(), dtype=np.int64)


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _strip_comment(line: str) -> str:
    return line.split("#", 1)[0].split("//", 1)[0].strip()


def _read_text_rows(p: Path) -> np.ndarray:
    """Rows of numbers from a text point file, as scanners and CloudCompare write them.

    Numbers are separated by whitespace, commas or semicolons (decided on the first data
    row; with semicolons a comma is a decimal mark, the spreadsheet convention; one
    separator ending every row is allowed), ``#`` and ``//`` start comments, a UTF-8
    byte-order mark is skipped, and a first row of column names (``X,Y,Z``; no field a
    number) or of the point count alone (Leica ``.pts``) is skipped as a header. Empty
    fields and later non-numeric rows are errors, never silently dropped.
    """
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
    except (ValueError, UnicodeDecodeError) as exc:
        raise InputFileError(f"path: cannot read {str(p)!r} as rows of numbers ({exc})") from None
    if arr.size == 0:
        raise InputFileError(f"path: {str(p)!r} holds no points (no rows of numbers)")
    return arr


def read_pointcloud(path: str | Path, *, dtype: torch.dtype = torch.float32) -> torch.Tensor:
    """Read the points of a ``.ply .obj .off .stl .xyz .txt .pts .npy`` file as ``(N, D)``.

    Mesh formats give their vertices. ``.xyz``/``.txt``/``.pts`` are text with one point
    per row, numbers separated by whitespace, commas or semicolons, ``#`` or ``//``
    comments and an optional header row of column names (extra columns such as normals
    or colours after the first three are dropped; see :func:`_read_text_rows`); ``.npy``
    must hold a 2-D float array.

    Raises:
        InputFileError: missing, unreadable, or not a point cloud.
    """
    p = _existing(path, "path")
    suffix = p.suffix.lower()
    if suffix == ".npy":
        try:
            arr = np.load(p, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise InputFileError(f"path: cannot read {str(p)!r} as a NumPy array ({exc})") from None
        if arr.ndim != 2 or not np.issubdtype(arr.dtype, np.number):
            raise InputFileError(f"path: expected {str(p)!r} to hold a numeric (N, D) array, got {arr.dtype} {arr.shape}")
    elif suffix in (".xyz", ".txt", ".pts"):
        arr = _read_text_rows(p)
        if arr.shape[1] < 3:
            raise InputFileError(f"path: expected at least 3 columns (x y z) in {str(p)!r}, got {arr.shape[1]}")
        arr = arr[:, :3]
    elif suffix in MESH_SUFFIXES:
        arr, _ = _load_meshlab(p, "path")
    else:
        raise InputFileError(f"path: expected one of {', '.join(POINT_SUFFIXES)} for a point cloud, got {str(p)!r}")
    if arr.shape[0] == 0:
        raise InputFileError(f"path: {str(p)!r} holds no points")
    return torch.from_numpy(np.ascontiguousarray(arr)).to(dtype)


def read_mesh(path: str | Path, *, dtype: torch.dtype = torch.float32) -> Mesh:
    """Read a triangle mesh (``.off .obj .ply .stl``) through pymeshlab.

    Raises:
        InputFileError: missing, unreadable, or holding no triangles.
    """
    p = _existing(path, "path")
    if p.suffix.lower() not in MESH_SUFFIXES:
        raise InputFileError(f"path: expected one of {', '.join(MESH_SUFFIXES)} for a mesh, got {str(p)!r}")
    v, f = _load_meshlab(p, "path")
    if f.shape[0] == 0:
        raise InputFileError(f"path: {str(p)!r} holds no triangles (a point cloud, not a mesh)")
    return Mesh(torch.from_numpy(v).to(dtype), torch.from_numpy(f))


def read_image(path: str | Path) -> torch.Tensor:
    """Read an image as an RGB ``(3, H, W)`` float tensor in [0, 1] (grayscale kept as ``(1, H, W)``).

    Raises:
        InputFileError: missing or not a decodable image.
    """
    import cv2

    p = _existing(path, "path")
    data = np.fromfile(str(p), dtype=np.uint8)
    img = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    if img is None:
        raise InputFileError(f"path: cannot decode {str(p)!r} as an image")
    if img.dtype == np.uint16:
        scale = 65535.0
    elif img.dtype == np.uint8:
        scale = 255.0
    else:
        scale = 1.0
    img = img.astype(np.float32) / scale
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
        data = torch.from_numpy(data)
    if isinstance(data, torch.Tensor):
        if data.dim() == 2:
            return "pointcloud" if data.shape[1] == 3 else "points"
        if data.dim() in (3, 4) and data.shape[-3] in (1, 3):
            return "image"
        raise InputShapeError(
            f"input: expected (N, D) points, (C, H, W) or (B, C, H, W) image, or a Mesh, got {tuple(data.shape)}"
        )
    raise InputShapeError(f"input: expected a path, tensor, array or Mesh, got {type(data).__name__}")


def load_input(path: str | Path, kind: str | None = None) -> tuple[str, Any]:
    """Read a file and return ``(kind, data)``; the kind comes from the suffix and contents.

    Mesh formats holding triangles are ``mesh`` unless ``kind="pointcloud"`` asks for the
    vertices alone; mesh formats without triangles, ``.xyz`` and 3-column ``.npy`` are
    ``pointcloud``; other ``.npy`` widths are ``points``; image suffixes are ``image``.
    """
    p = _existing(path, "input")
    suffix = p.suffix.lower()
    if suffix in IMAGE_SUFFIXES:
        if kind not in (None, "image"):
            raise InputFileError(f"input: {str(p)!r} is an image, but kind {kind!r} was asked for")
        return "image", read_image(p)
    if suffix in MESH_SUFFIXES:
        v, f = _load_meshlab(p, "input")
        if v.shape[0] == 0:
            raise InputFileError(f"input: {str(p)!r} holds no points")
        verts = torch.from_numpy(np.ascontiguousarray(v)).to(torch.float32)
        if kind in ("pointcloud", "points") or (kind is None and f.shape[0] == 0):
            return "pointcloud", verts
        if kind not in (None, "mesh"):
            raise InputFileError(f"input: {str(p)!r} is a mesh, but kind {kind!r} was asked for")
        if f.shape[0] == 0:
            raise InputFileError(f"input: {str(p)!r} holds no triangles (a point cloud, not a mesh)")
        return "mesh", Mesh(verts, torch.from_numpy(f))
    if suffix in POINT_SUFFIXES:
        pts = read_pointcloud(p)
        found = "pointcloud" if pts.shape[1] == 3 else "points"
        if kind not in (None, found) and not (kind == "points" and found == "pointcloud"):
            raise InputFileError(f"input: {str(p)!r} holds a {found}, but kind {kind!r} was asked for")
        return (kind or found), pts
    known = ", ".join(IMAGE_SUFFIXES + POINT_SUFFIXES)
    raise InputFileError(f"input: cannot tell what {str(p)!r} holds from its suffix; expected one of {known}")
