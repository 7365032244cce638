"""Evaluation protocols of every chapter, as library functions."""

from torchsym.metrics.plane import *  # noqa: F401,F403
from torchsym.metrics.pr import *  # noqa: F401,F403
from torchsym.metrics.pixel_f1 import *  # noqa: F401,F403
from torchsym.metrics.symmetry import *  # noqa: F401,F403
from torchsym.metrics.pointset import *  # noqa: F401,F403
from torchsym.metrics.mesh import *  # noqa: F401,F403
from torchsym.metrics.axes import *  # noqa: F401,F403
from torchsym.metrics.multiview import *  # noqa: F401,F403
from torchsym.metrics.superpixels import *  # noqa: F401,F403
from torchsym.metrics.masks import *  # noqa: F401,F403
from torchsym.metrics.symmetry_map import *  # noqa: F401,F403
