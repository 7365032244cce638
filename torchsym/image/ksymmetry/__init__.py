"""Reflection symmetry axes by k-symmetry clustering of mirror pairs (thesis Sec. 2.2).

Steps: :mod:`~torchsym.image.sift_pairs` (mirror pairs, Sec. 2.2.1) ->
:mod:`.clustering` (Algorithm 1 and the choice of ``k``) -> the shared verification tail
(:mod:`~torchsym.image.verification`); the top function is in :mod:`.detect`.
"""

from torchsym.image.ksymmetry.clustering import ksymmetry_clustering
from torchsym.image.ksymmetry.detect import KSymmetryDetector, ksymmetry_axes
from torchsym.image.ksymmetry.settings import Clustering, KSymmetrySettings, MirrorPairs

__all__ = ["Clustering", "KSymmetryDetector", "KSymmetrySettings", "MirrorPairs", "ksymmetry_axes", "ksymmetry_clustering"]
