"""Riemannian manifolds in PyTorch: batch dimensions lead, the manifold's dimensions trail.

Every manifold has the same few operations (``proju``, ``egrad2rgrad``, ``ehess2rhess``,
``retr``, ``expmap``, ``inner``, ``norm``, ``projx``, ``random_point``, ``random_tangent``,
``zero_vector`` and the pure check ``check_point``), so the solvers in
:mod:`torchsym.optim` work on any of them.
"""

from torchsym.manifolds.base import Manifold
from torchsym.manifolds.euclidean import Euclidean
from torchsym.manifolds.plane_rotations import PlaneRotations, plane_rotation
from torchsym.manifolds.product import ProductManifold
from torchsym.manifolds.special_orthogonal import SpecialOrthogonal
from torchsym.manifolds.stiefel import Stiefel

__all__ = [
    "Euclidean",
    "Manifold",
    "PlaneRotations",
    "ProductManifold",
    "SpecialOrthogonal",
    "Stiefel",
    "plane_rotation",
]
