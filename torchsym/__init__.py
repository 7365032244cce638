"""torchsym: reflection symmetry detection in PyTorch.

Images, point clouds, triangle meshes and d-dimensional point sets, following the thesis
"Reflection Symmetry Detection" (R. Nagar). Start with :func:`torchsym.detect`.
"""

from __future__ import annotations

__version__ = "0.1.0"

from torchsym import data, geometry, image, io, mesh, metrics, multiview, pointcloud, pointset
from torchsym.api import detect
from torchsym.core.config import Pipeline, PipelineConfig, build_pipeline, load_config
from torchsym.core.registry import SOLVERS, register_solver
from torchsym.core.results import Result
from torchsym.runner import evaluate, read_results, run
from torchsym.errors import (
    ConfigError,
    InputFileError,
    InputShapeError,
    InputValueError,
    SolverError,
    TorchsymError,
)
from torchsym.image import *  # noqa: F401,F403  (every solver importable from the top level)
from torchsym.mesh import *  # noqa: F401,F403
from torchsym.pointcloud import *  # noqa: F401,F403
from torchsym.pointset import *  # noqa: F401,F403
from torchsym.multiview import MultiviewPlaneDetector, MultiviewPlaneResult, MultiviewPlaneSettings  # noqa: F401

__all__ = [
    "MultiviewPlaneDetector",
    "MultiviewPlaneResult",
    "MultiviewPlaneSettings",
    "SOLVERS",
    "ConfigError",
    "InputFileError",
    "InputShapeError",
    "InputValueError",
    "Pipeline",
    "PipelineConfig",
    "Result",
    "SolverError",
    "TorchsymError",
    "build_pipeline",
    "data",
    "detect",
    "evaluate",
    "geometry",
    "image",
    "io",
    "load_config",
    "mesh",
    "metrics",
    "pointcloud",
    "pointset",
    "read_results",
    "register_solver",
    "run",
]
from torchsym import image as _image, mesh as _mesh, pointcloud as _pointcloud, pointset as _pointset  # noqa: E402

for _m in (_image, _mesh, _pointcloud, _pointset):
    __all__ += [n for n in _m.__all__ if n not in __all__]
del _m
