"""Triangle meshes: the mesh type and (later) its operators and intrinsic symmetry."""

from torchsym.mesh.mesh import Mesh

__all__ = ["Mesh"]
