"""The whole symmetry group of a 3D point cloud: reflections, rotations found directly
(chiral shapes too), rotoreflections and axes of revolution, closed into one group.

Stages, in the order :func:`detect_symmetry` runs them: the every-plane detector
(:mod:`~torchsym.pointcloud.reflection_planes`), :mod:`.rotations` (n-fold axes found
and tested directly), the group's closure (:mod:`~torchsym.pointcloud.reflection_planes.group`).
"""

from torchsym.pointcloud.symmetry.detect import SymmetryDetector, detect_symmetry
from torchsym.pointcloud.symmetry.result import SymmetryResult
from torchsym.pointcloud.symmetry.settings import GroupSettings, RotationSettings, SymmetrySettings

__all__ = ["GroupSettings", "RotationSettings", "SymmetryDetector", "SymmetryResult", "SymmetrySettings", "detect_symmetry"]
