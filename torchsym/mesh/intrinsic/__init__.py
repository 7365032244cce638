"""Intrinsic reflection symmetry of a triangle mesh by functional maps (thesis Ch. 6).

One module per stage: :mod:`~.workspace` (step 1 and the plan), :mod:`~.spectrum` (steps
2-3), :mod:`~.hypotheses` (steps 4-8), :mod:`~.select` (steps 9-10), :mod:`~.refine` (step
11), :mod:`~.reorient` (12), :mod:`~.polish` (13), :mod:`~.realign` (14);
:mod:`~.solver` reads them as the thesis's list of steps.
"""

from torchsym.mesh.intrinsic.probe import GeodesicProbe
from torchsym.mesh.intrinsic.result import IntrinsicSymmetryResult
from torchsym.mesh.intrinsic.settings import IntrinsicSymmetrySettings
from torchsym.mesh.intrinsic.solver import IntrinsicSymmetry, intrinsic_symmetry

__all__ = ["GeodesicProbe", "IntrinsicSymmetry", "IntrinsicSymmetryResult", "IntrinsicSymmetrySettings", "intrinsic_symmetry"]
