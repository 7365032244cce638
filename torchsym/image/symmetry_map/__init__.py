"""The dense reflection symmetry map of an image and symmetry-preserving stylization (thesis Ch. 3).

:func:`symmetry_map` returns, per symmetry axis, the nearest mirror reflection field
(NMRF, ``(H, W, 2)``) and the symmetry score map (SSM, ``(H, W)`` in [0, 1]) by
symmetric PatchMatch (Algorithm 3); :func:`stylize` merges SLIC superpixels by their
score (Sec. 3.4). Stage modules: ``candidates`` (mirrored-SIFT pairs), ``clustering``
(RansaCov, Eqs. 3.1-3.2), ``descriptors`` (dense, in the axis frame), ``patchmatch``
(IRS, MMP, BMP), ``scores`` (Eqs. 3.7-3.8), ``stylize``.

Where this departs from the thesis (each measured in ``docs/design/symmetry_map.md``):

- descriptors: dense SIFT-like descriptors in the frame of the cluster's axis, computed by
  convolutions for all pixels at once, mirrored by an exact permutation, reduced to
  ``descriptor.n_dims`` by a PCA that keeps the mirror exact (the thesis: SIFT per pixel);
- ``candidates.max_distance`` 0.3 (thesis 0.1, on its SIFT; with kornia's RootSIFT 0.1
  leaves half of the dev photographs without a pair);
- RansaCov: the two points of an agreeing pair lie on opposite sides of the axis, and
  ``|d1 - d2| <= clustering.tol_px`` also agrees; the greedy cover does not offer the set
  of a pair already covered (the same axis twice);
- PatchMatch runs on every ``patchmatch.stride``-th pixel (default 2), the field elsewhere
  following by symmetry coherency (Sec. 3.2.1), and moves all pixels at once; PatchMatch's
  own propagation from the 4 grid neighbours is an option (``patchmatch.neighbours``, off);
  a random-search sample must lower the cost by ``patchmatch.min_gain`` (0.2; thesis: any
  decrease), which stops the search drifting where the cost is flat;
- the score's ``sigma_feature`` 0.4 (thesis 1) and ``sigma_d`` 0.1 (thesis: unstated).
"""

from torchsym.image.symmetry_map.estimate import SymmetryMapSolver, symmetry_map
from torchsym.image.symmetry_map.result import StylizedResult, SymmetryMapResult
from torchsym.image.symmetry_map.settings import StylizeSettings, SymmetryMapSettings
from torchsym.image.symmetry_map.stylize import StylizeSolver, stylize

__all__ = [
    "StylizedResult",
    "StylizeSettings",
    "StylizeSolver",
    "SymmetryMapResult",
    "SymmetryMapSettings",
    "SymmetryMapSolver",
    "stylize",
    "symmetry_map",
]
