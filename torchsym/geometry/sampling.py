"""Deterministic samples of directions on the sphere, and seeded samples of mesh surfaces."""

from __future__ import annotations

import math

import torch

from torchsym.core.checks import check_int
from torchsym.core.random import make_generator
from torchsym.errors import InputValueError
from torchsym.geometry.mesh import Mesh

__all__ = ["sample_surface", "sphere_normals"]


def sphere_normals(count: int, *, dtype: torch.dtype = torch.float64) -> torch.Tensor:
    """``(count, 3)`` near-uniform unit normals on the upper half sphere (Fibonacci lattice).

    Every plane through the origin has exactly one normal with ``z >= 0``, so the half
    sphere covers all planes. ``count = 100`` leaves no plane much more than 10 degrees
    from a sample (the basin of thesis Sec. 5.2.3).
    """
    i = torch.arange(count, dtype=dtype) + 0.5
    z = 1.0 - i / count  # uniform in (0, 1]
    r = torch.sqrt((1.0 - z * z).clamp_min(0))
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    return torch.stack([r * torch.cos(phi), r * torch.sin(phi), z], dim=1)


def sample_surface(
    mesh: Mesh,
    count: int,
    *,
    generator: torch.Generator | int | None = None,
    dtype: torch.dtype | None = None,
) -> torch.Tensor:
    """``(count, 3)`` points drawn uniformly by area from the surface of ``mesh``.

    Each point picks a triangle with probability proportional to its area (inverse CDF
    of the cumulative areas, so any number of faces works) and a uniform position in it
    (two uniforms folded into the triangle). Vertices alone over-sample curved,
    finely tessellated parts and leave large flat faces empty; the thesis's point-cloud
    method (Sec. 5.2) assumes points spread over the surface.

    Args:
        mesh: a triangle mesh; degenerate (zero-area) triangles are never drawn.
        count: points drawn, >= 1.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.
        dtype: floating dtype of the result; None keeps the vertices' dtype. Areas and
            positions are computed in float64.

    Returns:
        ``(count, 3)`` points on the mesh's device.

    Raises:
        InputValueError: ``count`` < 1, or a mesh whose triangles have no area.
    """
    count = check_int(count, "count", minimum=1)
    gen = make_generator(generator)
    v = mesh.vertices.detach().cpu().to(torch.float64)  # (V, 3)
    tri = v[mesh.faces.cpu()]  # (F, 3, 3)
    area = torch.linalg.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0], dim=1).norm(dim=1)  # (F,) twice the areas
    cum = torch.cumsum(area, 0)  # (F,)
    if tri.shape[0] == 0 or not float(cum[-1]) > 0:
        raise InputValueError(f"mesh: expected triangles of positive total area, got {tri.shape[0]} triangles of area 0")
    pick = torch.rand(count, generator=gen, dtype=torch.float64) * cum[-1]  # (count,)
    face = torch.searchsorted(cum, pick, right=True).clamp_max(tri.shape[0] - 1)  # (count,)
    u = torch.rand(count, 2, generator=gen, dtype=torch.float64)  # (count, 2)
    fold = u.sum(1) > 1
    u[fold] = 1 - u[fold]
    t = tri[face]  # (count, 3, 3)
    pts = t[:, 0] + u[:, :1] * (t[:, 1] - t[:, 0]) + u[:, 1:] * (t[:, 2] - t[:, 0])  # (count, 3)
    return pts.to(device=mesh.vertices.device, dtype=dtype or mesh.vertices.dtype)
