"""Small inputs shipped inside the package, so the demo runs from a wheel.

``chair.ply``: 4,000 points sampled from a procedurally built chair (seat, back, four
legs, two armrests) that is mirror symmetric, then turned and moved so that the plane is
not an axis plane. Made by ``scripts/make_sample_data.py`` (seeded); its true plane is
stored beside it in ``chair_plane.txt``.

``cad``: CAD-style meshes made in code (several parts, non-manifold edges, uneven
tessellation) with their true plane.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import torch

__all__ = ["sample_path", "sample_plane", "sample_pointcloud"]


def sample_path(name: str = "chair.ply") -> Path:
    """Path of a shipped sample file."""
    return Path(str(resources.files("torchsym.data").joinpath(name)))


def sample_pointcloud() -> torch.Tensor:
    """The shipped symmetric chair, ``(4000, 3)`` float32."""
    from torchsym.io.read import read_pointcloud

    return read_pointcloud(sample_path("chair.ply"))


def sample_plane() -> tuple[torch.Tensor, torch.Tensor]:
    """The chair's true reflection plane: ``normal (3,)`` and ``offset ()``."""
    vals = [float(v) for v in sample_path("chair_plane.txt").read_text().split()]
    return torch.tensor(vals[:3]), torch.tensor(vals[3])
