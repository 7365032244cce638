"""torchsym: reflection symmetry detection in PyTorch.

Images, point clouds, triangle meshes and d-dimensional point sets, following the thesis
"Reflection Symmetry Detection" (R. Nagar). Start with :func:`torchsym.detect`.

The top level holds the solvers (functions and modules), their results and settings,
``detect``, the config and registry API, the error types, the dataset runner and the
subpackages; building blocks stay in their subpackages (``torchsym.geometry``...). Members
are imported on first use (``import torchsym`` loads no torch), every one at once by
:func:`load_all`.
"""

from __future__ import annotations

__version__ = "0.1.0"

from typing import TYPE_CHECKING

from torchsym._lazy import lazy_members

_SUBPACKAGES = ('core', 'data', 'features', 'geometry', 'image', 'io', 'losses', 'manifolds', 'matching', 'mesh', 'metrics', 'multiview', 'optim', 'pointcloud', 'pointset', 'runner', 'viz')
#: the module that defines each public name (a subpackage: itself)
_EXPORTS: dict[str, str] = {
    **{name: f"torchsym.{name}" for name in _SUBPACKAGES},
    **dict.fromkeys(('AxisStage', 'AxisStageSettings', 'BoundaryCliqueDetector', 'BoundaryCliquesSettings', 'ImageAxisResult', 'KSymmetryDetector', 'KSymmetrySettings', 'PointSymmImage', 'PointSymmImageSettings', 'ReflectionAxesBatch', 'ReflectionAxesResult', 'StylizeSolver', 'SymmetryMapResult', 'SymmetryMapSolver', 'SymmSlic', 'SymmSlicResult', 'boundary_clique_axes', 'image_axes', 'ksymmetry_axes', 'point_symm_image', 'stylize', 'symm_slic', 'symmetry_map'), 'torchsym.image'),
    **dict.fromkeys(('IntrinsicSymmetry', 'IntrinsicSymmetryResult', 'IntrinsicSymmetrySettings', 'intrinsic_symmetry'), 'torchsym.mesh'),
    **dict.fromkeys(('MultiviewPlaneDetector', 'MultiviewPlaneResult', 'MultiviewPlaneSettings', 'detect_multiview_plane'), 'torchsym.multiview'),
    **dict.fromkeys(('ReflectionPlaneDetector', 'ReflectionPlaneResult', 'ReflectionPlaneSettings', 'ReflectionPlanesDetector', 'ReflectionPlanesResult', 'ReflectionPlanesSettings', 'SymmetryDetector', 'SymmetryResult', 'SymmetrySettings', 'detect_symmetry', 'add_outliers', 'detect_reflection_plane', 'detect_reflection_planes', 'planted_symmetric_cloud'), 'torchsym.pointcloud'),
    **dict.fromkeys(('PointSymm', 'PointSymmResult', 'PointSymmSettings', 'make_symmetric_pointset', 'point_symm'), 'torchsym.pointset'),
    **dict.fromkeys(('evaluate',), 'torchsym.runner.scoring'),
    **dict.fromkeys(('read_results',), 'torchsym.runner.store'),
    **dict.fromkeys(('run', 'EngineOptions'), 'torchsym.runner.driver'),
    **dict.fromkeys(('detect',), 'torchsym.api'),
    **dict.fromkeys(('Pipeline', 'PipelineConfig', 'build_pipeline', 'load_config'), 'torchsym.core.config'),
    **dict.fromkeys(('SOLVERS', 'register_solver'), 'torchsym.core.registry'),
    **dict.fromkeys(('Result', 'load_result'), 'torchsym.core.results'),
    **dict.fromkeys(('Settings', 'Solver'), 'torchsym.core.settings'),
    **dict.fromkeys(('ConfigError', 'InputFileError', 'InputShapeError', 'InputValueError', 'SolverError', 'TorchsymError'), 'torchsym.errors'),
    **dict.fromkeys(('Mesh',), 'torchsym.geometry.mesh'),
    **dict.fromkeys(('StylizedResult', 'StylizeSettings', 'SymmetryMapSettings'), 'torchsym.image.symmetry_map'),
    **dict.fromkeys(('SymmSlicSettings',), 'torchsym.image.symmslic'),
}

__all__ = [
    # solvers: module, function, result, settings
    "ReflectionPlaneDetector", "detect_reflection_plane", "ReflectionPlaneResult", "ReflectionPlaneSettings",
    "ReflectionPlanesDetector", "detect_reflection_planes", "ReflectionPlanesResult", "ReflectionPlanesSettings",
    "SymmetryDetector", "detect_symmetry", "SymmetryResult", "SymmetrySettings",
    "PointSymm", "point_symm", "PointSymmResult", "PointSymmSettings",
    "IntrinsicSymmetry", "intrinsic_symmetry", "IntrinsicSymmetryResult", "IntrinsicSymmetrySettings",
    "AxisStage", "image_axes", "AxisStageSettings",
    "BoundaryCliqueDetector", "boundary_clique_axes", "ReflectionAxesResult", "ReflectionAxesBatch",
    "BoundaryCliquesSettings",
    "KSymmetryDetector", "ksymmetry_axes", "KSymmetrySettings",
    "PointSymmImage", "point_symm_image", "ImageAxisResult", "PointSymmImageSettings",
    "SymmSlic", "symm_slic", "SymmSlicResult", "SymmSlicSettings",
    "SymmetryMapSolver", "symmetry_map", "SymmetryMapResult", "SymmetryMapSettings",
    "StylizeSolver", "stylize", "StylizedResult", "StylizeSettings",
    "MultiviewPlaneDetector", "detect_multiview_plane", "MultiviewPlaneResult", "MultiviewPlaneSettings",
    # inputs with a known symmetry, and the mesh type
    "Mesh", "add_outliers", "make_symmetric_pointset", "planted_symmetric_cloud",
    # one call, configs, registry, shapes
    "detect", "Pipeline", "PipelineConfig", "build_pipeline", "load_config",
    "SOLVERS", "register_solver", "Result", "load_result", "Settings", "Solver", "load_all",
    # errors
    "TorchsymError", "ConfigError", "InputFileError", "InputShapeError", "InputValueError", "SolverError",
    # dataset runner
    "run", "EngineOptions", "evaluate", "read_results",
    # subpackages
    "core", "data", "features", "geometry", "image", "io", "losses", "manifolds", "matching", "mesh",
    "metrics", "multiview", "optim", "pointcloud", "pointset", "runner", "viz",
]  # fmt: skip


__getattr__, __dir__ = lazy_members(__name__, _EXPORTS, globals())


def load_all() -> None:
    """Import every subpackage: registers every solver and result type (the registry and
    :func:`~torchsym.core.results.load_result` call it before a lookup)."""
    import importlib

    for name in _SUBPACKAGES:
        importlib.import_module(f"torchsym.{name}")


if TYPE_CHECKING:  # the same names, eagerly, for type checkers and editors
    from torchsym import (
        core,
        data,
        features,
        geometry,
        image,
        io,
        losses,
        manifolds,
        matching,
        mesh,
        metrics,
        multiview,
        optim,
        pointcloud,
        pointset,
        runner,
        viz,
    )
    from torchsym.api import detect
    from torchsym.core.config import Pipeline, PipelineConfig, build_pipeline, load_config
    from torchsym.core.registry import SOLVERS, register_solver
    from torchsym.core.results import Result, load_result
    from torchsym.core.settings import Settings, Solver
    from torchsym.errors import (
        ConfigError,
        InputFileError,
        InputShapeError,
        InputValueError,
        SolverError,
        TorchsymError,
    )
    from torchsym.geometry.mesh import Mesh
    from torchsym.image import (
        AxisStage,
        AxisStageSettings,
        BoundaryCliqueDetector,
        BoundaryCliquesSettings,
        ImageAxisResult,
        KSymmetryDetector,
        KSymmetrySettings,
        PointSymmImage,
        PointSymmImageSettings,
        ReflectionAxesBatch,
        ReflectionAxesResult,
        StylizeSolver,
        SymmetryMapResult,
        SymmetryMapSolver,
        SymmSlic,
        SymmSlicResult,
        boundary_clique_axes,
        image_axes,
        ksymmetry_axes,
        point_symm_image,
        stylize,
        symm_slic,
        symmetry_map,
    )
    from torchsym.image.symmetry_map import StylizedResult, StylizeSettings, SymmetryMapSettings
    from torchsym.image.symmslic import SymmSlicSettings
    from torchsym.mesh import IntrinsicSymmetry, IntrinsicSymmetryResult, IntrinsicSymmetrySettings, intrinsic_symmetry
    from torchsym.multiview import (
        MultiviewPlaneDetector,
        MultiviewPlaneResult,
        MultiviewPlaneSettings,
        detect_multiview_plane,
    )
    from torchsym.pointcloud import (
        ReflectionPlaneDetector,
        ReflectionPlaneResult,
        ReflectionPlaneSettings,
        ReflectionPlanesDetector,
        ReflectionPlanesResult,
        ReflectionPlanesSettings,
        SymmetryDetector,
        SymmetryResult,
        SymmetrySettings,
        add_outliers,
        detect_reflection_plane,
        detect_reflection_planes,
        detect_symmetry,
        planted_symmetric_cloud,
    )
    from torchsym.pointset import PointSymm, PointSymmResult, PointSymmSettings, make_symmetric_pointset, point_symm
    from torchsym.runner import EngineOptions, evaluate, read_results, run
