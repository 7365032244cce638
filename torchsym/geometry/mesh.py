"""The triangle mesh type shared by io, the point-cloud samplers and every mesh method."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import torch

from torchsym.core.checks import as_tensor, check_finite
from torchsym.errors import InputShapeError, InputValueError

__all__ = ["Mesh"]


@dataclasses.dataclass(frozen=True)
class Mesh:
    """A triangle mesh.

    Attributes:
        vertices: ``(V, 3)`` float vertex positions.
        faces: ``(F, 3)`` int64 vertex indices of each triangle (counter-clockwise).

    Construction checks shapes, dtypes, finiteness and that every face index is in
    range; use :meth:`Mesh.create` to convert arrays or lists.
    """

    vertices: torch.Tensor
    faces: torch.Tensor

    def __post_init__(self) -> None:
        v, f = self.vertices, self.faces
        if not isinstance(v, torch.Tensor) or v.dim() != 2 or v.shape[1] != 3 or not v.is_floating_point():
            raise InputShapeError(f"vertices: expected (V, 3) float tensor, got {_desc(v)}")
        if not isinstance(f, torch.Tensor) or f.dim() != 2 or f.shape[1] != 3 or f.dtype != torch.int64:
            raise InputShapeError(f"faces: expected (F, 3) int64 tensor, got {_desc(f)}")
        if v.shape[0] == 0:
            raise InputValueError("vertices: expected at least one vertex, got (0, 3)")
        check_finite(v, "vertices")
        if f.numel() and (int(f.min()) < 0 or int(f.max()) >= v.shape[0]):
            raise InputValueError(
                f"faces: expected indices in [0, {v.shape[0] - 1}], got values in [{int(f.min())}, {int(f.max())}]"
            )

    @classmethod
    def create(cls, vertices: Any, faces: Any) -> Mesh:
        """Build a mesh from tensors, arrays or lists (faces converted to int64)."""
        v = as_tensor(vertices, "vertices")
        if isinstance(faces, torch.Tensor):
            f = faces
        else:
            try:
                f = torch.as_tensor(np.asarray(faces))
            except (TypeError, ValueError) as exc:
                raise InputShapeError(f"faces: expected (F, 3) integer vertex indices, got {type(faces).__name__} ({exc})") from None
        if not (f.is_floating_point() or f.dtype in (torch.int8, torch.int16, torch.int32, torch.int64, torch.uint8)):
            raise InputShapeError(f"faces: expected (F, 3) integer vertex indices, got dtype {f.dtype}")
        if f.is_floating_point() and f.numel() and not bool((f == f.round()).all()):
            raise InputShapeError("faces: expected integer vertex indices, got non-integer values")
        return cls(v, f.to(torch.int64).reshape(-1, 3) if f.numel() == 0 else f.to(torch.int64))

    @property
    def num_vertices(self) -> int:
        return int(self.vertices.shape[0])

    @property
    def num_faces(self) -> int:
        return int(self.faces.shape[0])

    def to(self, device: torch.device | str) -> Mesh:
        return Mesh(self.vertices.to(device), self.faces.to(device))


def _desc(x: Any) -> str:
    if isinstance(x, torch.Tensor):
        return f"{tuple(x.shape)} {x.dtype}"
    return type(x).__name__
