"""The global reflection plane of a 3D point cloud (thesis Sec. 5.2, Algorithms 5 and 6).

Stages, in the order :func:`detect_reflection_plane` runs them: :mod:`torchsym.pointcloud.prepare`
(normalise, sample, subsample), :mod:`.candidates` (Algorithm 5), :mod:`.starts` with
:mod:`.prealign` (starts refined on the subsample), :mod:`.alternation` and :mod:`.polish`
(Algorithm 6), :mod:`.kernel` (kernel correlation for noisy clouds), :mod:`.result` with
:mod:`torchsym.pointcloud.score` (the mirror share against chance).
"""

from torchsym.pointcloud.reflection_plane.detect import ReflectionPlaneDetector, detect_reflection_plane
from torchsym.pointcloud.reflection_plane.result import ReflectionPlaneResult
from torchsym.pointcloud.reflection_plane.settings import ReflectionPlaneSettings

__all__ = ["ReflectionPlaneDetector", "ReflectionPlaneResult", "ReflectionPlaneSettings", "detect_reflection_plane"]
