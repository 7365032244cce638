"""The in-memory objects users already hold, as torchsym inputs.

``torchsym.detect`` takes tensors, arrays and :class:`~torchsym.geometry.mesh.Mesh`; this
module turns the objects of the libraries people load data with into those, by duck
typing, so none of these libraries is a dependency:

| object | becomes |
|---|---|
| ``trimesh.Trimesh`` (``vertices``, ``faces``) | :class:`Mesh` |
| ``trimesh.PointCloud`` (``vertices``, no faces) | ``(N, 3)`` points |
| Open3D ``TriangleMesh`` (``vertices``, ``triangles``) | :class:`Mesh` |
| Open3D ``PointCloud`` (``points``) | ``(N, 3)`` points |
| ``PIL.Image.Image`` (``mode``, ``size``, ``convert``) | ``(3, H, W)`` uint8 image |
| an ``(H, W, 3)`` / ``(H, W, 4)`` uint8 or uint16 array (OpenCV, PIL, imageio) | ``(3, H, W)`` image, alpha dropped |

OpenCV arrays are BGR; torchsym's photo methods use colour only through contrasts that do
not depend on the channel order, so no swap is made.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from torchsym.errors import InputShapeError
from torchsym.geometry.mesh import Mesh

__all__ = ["from_user_object", "is_channels_last_image"]


def is_channels_last_image(x: Any) -> bool:
    """Whether ``x`` is an ``(H, W, 3)`` or ``(H, W, 4)`` integer array or tensor, the way
    OpenCV and PIL give photos (an ``(N, 3)`` point cloud is 2-D, a ``(C, H, W)`` image has
    ``C`` first)."""
    shape = tuple(getattr(x, "shape", ()))
    dtype = getattr(x, "dtype", None)
    integer = dtype in (np.uint8, np.uint16, torch.uint8, torch.uint16)
    return integer and len(shape) == 3 and shape[2] in (3, 4) and shape[0] not in (1, 3) and min(shape[:2]) > 4


def _array(x: Any, what: str) -> np.ndarray:
    try:
        arr = np.asarray(x)
    except Exception as exc:  # noqa: BLE001 -- any failure of a foreign object's conversion
        raise InputShapeError(f"input: cannot read the {what} of the {type(x).__name__} as an array ({exc})") from None
    return arr


def _points(arr: np.ndarray, owner: Any) -> torch.Tensor:
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.dtype.kind not in "fiu":
        raise InputShapeError(f"input: expected the {type(owner).__name__}'s points as (N, 3) numbers, got {arr.shape} {arr.dtype}")
    return torch.from_numpy(np.ascontiguousarray(arr, dtype=np.float64)).float()


def _mesh(vertices: Any, faces: Any, owner: Any) -> Mesh:
    v, f = _array(vertices, "vertices"), _array(faces, "faces")
    if f.ndim != 2 or f.shape[1] != 3 or f.dtype.kind not in "iu":
        raise InputShapeError(f"input: expected the {type(owner).__name__}'s faces as (F, 3) integers, got {f.shape} {f.dtype}")
    return Mesh.create(_points(v, owner), torch.from_numpy(f.astype(np.int64)))


def _image(arr: np.ndarray) -> torch.Tensor:
    """``(3, H, W)`` of an ``(H, W, C)`` integer array, alpha dropped, dtype kept."""
    return torch.from_numpy(np.ascontiguousarray(arr[..., :3].transpose(2, 0, 1)))


def from_user_object(x: Any) -> Any:
    """``x`` as a torchsym input: a :class:`Mesh`, ``(N, 3)`` float points or a
    ``(3, H, W)`` integer image for the objects in the table above; anything else is
    returned unchanged (tensors, arrays, meshes).

    Raises:
        InputShapeError: one of these objects with contents of the wrong shape or type
            (an empty mesh's faces, points that are not ``(N, 3)`` numbers).
    """
    if isinstance(x, (torch.Tensor, Mesh)):
        return x
    if isinstance(x, np.ndarray):
        return _image(x) if is_channels_last_image(x) else x
    if hasattr(x, "mode") and hasattr(x, "size") and callable(getattr(x, "convert", None)):  # PIL.Image.Image
        return _image(_array(x.convert("RGB"), "pixels"))
    if hasattr(x, "vertices") and hasattr(x, "faces"):  # trimesh.Trimesh
        return _mesh(x.vertices, x.faces, x)
    if hasattr(x, "vertices") and hasattr(x, "triangles"):  # open3d.geometry.TriangleMesh
        return _mesh(x.vertices, x.triangles, x)
    if hasattr(x, "points") and not isinstance(x, (list, tuple, dict)):  # open3d.geometry.PointCloud
        return _points(_array(x.points, "points"), x)
    if hasattr(x, "vertices") and not isinstance(x, (list, tuple, dict)):  # trimesh.PointCloud
        return _points(_array(x.vertices, "vertices"), x)
    return x
