"""The CAD chair of the front-door tests (``torchsym.data.cad``), as a tuple, and its ``.obj`` file."""

from __future__ import annotations

from pathlib import Path

import torch

from torchsym.data.cad import cad_chair as _chair
from torchsym.geometry.mesh import Mesh
from torchsym.io import write_mesh


def cad_chair(fine_side: int = 6) -> tuple[Mesh, torch.Tensor, torch.Tensor]:
    """``(mesh, normal (3,), offset ())`` of :func:`torchsym.data.cad.cad_chair`."""
    model = _chair(fine_side)
    return model.mesh, model.normal, model.offset


def write_obj(path: Path, mesh: Mesh) -> Path:
    """``mesh`` as a Wavefront ``.obj``, as CAD exporters write it."""
    return write_mesh(path, mesh)
