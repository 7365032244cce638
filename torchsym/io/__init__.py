"""Reading inputs and writing results.

``read``: point clouds, meshes and images from files, and the kind of an input;
``meshfiles``: mesh file parsing; ``write``: JSON, PLY, meshes and images. The public
names of ``read`` and ``write`` are importable from here.
"""

from torchsym.io import read, write
from torchsym.io.read import *  # noqa: F403
from torchsym.io.write import *  # noqa: F403

__all__ = [*read.__all__, *write.__all__]
