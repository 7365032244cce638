"""Writing results: JSON, coloured PLY point clouds and meshes, PNG images."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.core.results import to_jsonable
from torchsym.errors import InputFileError

__all__ = ["write_image", "write_json", "write_mesh", "write_ply"]

MESH_WRITE_SUFFIXES = (".ply", ".obj", ".off", ".stl")


def write_json(obj: Any, path: str | Path) -> Path:
    """Write a result (or anything :func:`to_jsonable` handles) as indented JSON."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(json.dumps(to_jsonable(obj), indent=2))
    return p


def _np(x: Any) -> np.ndarray:
    if isinstance(x, torch.Tensor):
        return x.detach().cpu().numpy()
    return np.asarray(x)


def write_ply(
    path: str | Path,
    vertices: Any,
    *,
    colors: Any | None = None,
    faces: Any | None = None,
    edges: Any | None = None,
) -> Path:
    """Write a binary little-endian PLY that MeshLab, CloudCompare or Blender open.

    Args:
        path: output file.
        vertices: ``(V, 3)`` positions.
        colors: ``(V, 3)`` RGB in [0, 1] or uint8, optional.
        faces: ``(F, 3)`` triangle indices, optional.
        edges: ``(E, 2)`` line segments between vertices (e.g. mirror pairs), optional.
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    v = _np(vertices).astype("<f4").reshape(-1, 3)
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(v)}",
              "property float x", "property float y", "property float z"]
    vdtype = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    if colors is not None:
        c = _np(colors)
        c = (np.clip(c, 0, 1) * 255).round().astype(np.uint8) if c.dtype != np.uint8 else c
        header += ["property uchar red", "property uchar green", "property uchar blue"]
        vdtype += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    rec = np.empty(len(v), dtype=vdtype)
    rec["x"], rec["y"], rec["z"] = v[:, 0], v[:, 1], v[:, 2]
    if colors is not None:
        rec["red"], rec["green"], rec["blue"] = c[:, 0], c[:, 1], c[:, 2]
    blobs = [rec.tobytes()]
    if faces is not None:
        f = _np(faces).astype("<i4").reshape(-1, 3)
        header += [f"element face {len(f)}", "property list uchar int vertex_indices"]
        frec = np.empty(len(f), dtype=[("n", "u1"), ("i", "<i4", (3,))])
        frec["n"], frec["i"] = 3, f
        blobs.append(frec.tobytes())
    if edges is not None:
        e = _np(edges).astype("<i4").reshape(-1, 2)
        header += [f"element edge {len(e)}", "property int vertex1", "property int vertex2"]
        blobs.append(e.tobytes())
    header.append("end_header")
    with p.open("wb") as fh:
        fh.write(("\n".join(header) + "\n").encode("ascii"))
        for b in blobs:
            fh.write(b)
    return p


def write_mesh(path: str | Path, mesh: Any, *, colors: Any | None = None) -> Path:
    """Write a triangle mesh through pymeshlab (``.ply`` binary, ``.obj``, ``.off``, ``.stl``).

    Args:
        path: output file; its suffix picks the format. Its folder is created.
        mesh: a :class:`torchsym.mesh.Mesh`.
        colors: ``(V, 3)`` per-vertex RGB in [0, 1] or uint8, optional (kept by PLY, OFF
            and OBJ; STL has no vertex colours).

    Raises:
        InputFileError: an unsupported suffix, or pymeshlab cannot write the file.
        InputShapeError: ``mesh`` is not a Mesh, or ``colors`` is not ``(V, 3)``.
    """
    import pymeshlab

    from torchsym.errors import InputShapeError
    from torchsym.geometry.mesh import Mesh

    if not isinstance(mesh, Mesh):
        raise InputShapeError(f"mesh: expected a torchsym.mesh.Mesh, got {type(mesh).__name__}")
    p = Path(path)
    if p.suffix.lower() not in MESH_WRITE_SUFFIXES:
        raise InputFileError(f"path: expected one of {', '.join(MESH_WRITE_SUFFIXES)} to write a mesh, got {str(p)!r}")
    v = _np(mesh.vertices).astype(np.float64)
    f = _np(mesh.faces).astype(np.int32)
    kwargs: dict[str, Any] = {"vertex_matrix": v, "face_matrix": f}
    if colors is not None:
        c = _np(colors)
        if c.shape != (v.shape[0], 3):
            raise InputShapeError(f"colors: expected ({v.shape[0]}, 3) per-vertex RGB, got {tuple(c.shape)}")
        c = c.astype(np.float64) / 255.0 if c.dtype == np.uint8 else np.clip(c.astype(np.float64), 0.0, 1.0)
        kwargs["v_color_matrix"] = np.concatenate([c, np.ones((c.shape[0], 1))], axis=1)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(**kwargs))
    p.parent.mkdir(parents=True, exist_ok=True)
    save: dict[str, Any] = {}
    if p.suffix.lower() == ".ply":
        save = {"binary": True, "save_vertex_color": colors is not None}
    elif p.suffix.lower() in (".off", ".obj"):
        save = {"save_vertex_color": colors is not None}
    try:
        ms.save_current_mesh(str(p), **save)
    except pymeshlab.PyMeshLabException as exc:
        raise InputFileError(f"path: cannot write a mesh to {str(p)!r} ({exc})") from None
    return p


def write_image(path: str | Path, image: Any) -> Path:
    """Write an RGB image given as ``(3, H, W)`` / ``(H, W, 3)`` float in [0, 1] or uint8."""
    import cv2

    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    img = _np(image)
    if img.ndim == 3 and img.shape[0] in (1, 3) and img.shape[-1] not in (1, 3):
        img = np.transpose(img, (1, 2, 0))
    if img.dtype != np.uint8:
        img = (np.clip(img, 0, 1) * 255).round().astype(np.uint8)
    if img.ndim == 3 and img.shape[2] == 3:
        img = img[:, :, ::-1]
    if not cv2.imwrite(str(p), np.ascontiguousarray(img)):
        raise InputFileError(f"path: cannot write an image to {str(p)!r}")
    return p
