"""Reflection geometry in d dimensions, batched and differentiable, and the triangle mesh type.

Modules: ``reflection`` (planes, reflections, their parametrisations), ``mesh`` (the
``Mesh`` type), ``sampling`` (normals spread over the sphere), ``cone`` (directions in a
cone), ``conventions`` (PRS-Net and NeRD plane conventions), ``plane_votes`` (per-pair
planes and their clustering), ``volume`` (reflection of voxel grids). Each module's public
names are importable from here.
"""

from torchsym.geometry import cone, conventions, mesh, plane_votes, reflection, sampling, volume
from torchsym.geometry.cone import *  # noqa: F403
from torchsym.geometry.conventions import *  # noqa: F403
from torchsym.geometry.mesh import *  # noqa: F403
from torchsym.geometry.plane_votes import *  # noqa: F403
from torchsym.geometry.reflection import *  # noqa: F403
from torchsym.geometry.sampling import *  # noqa: F403
from torchsym.geometry.volume import *  # noqa: F403

__all__ = [
    name for module in (mesh, reflection, sampling, cone, conventions, plane_votes, volume) for name in module.__all__
]
