"""Differentiable losses for learned reflection symmetry.

Conventions: points ``(B, N, D)`` with a ``(B, N)`` mask of real points; planes as
``normal (B, K, D)`` and ``offset (B, K)`` (``n . x + b = 0``); losses return ``(B, K)``
or ``(B,)`` with ``reduction="none"``. Nothing on the loss path reads a device tensor
back to the host (the kd-tree is used for CPU tensors only); formulas and their sources
in ``docs/design/losses.md``. Focal loss is kornia's
(:func:`binary_focal_loss_with_logits`, re-exported), which is EquiSym's
``sigmoid_focal_loss`` (``ahyunSeo/EquiSym`` ``utils.py``) with the same alpha and gamma.
"""

from kornia.losses import BinaryFocalLossWithLogits, binary_focal_loss_with_logits

from torchsym.losses.field import field_symmetry_loss
from torchsym.losses.flip import flip_consistency_loss, orientation_flip_permutation
from torchsym.losses.modules import OrthogonalityLoss, PRSNetSymmetryLoss, SymmetryDistanceLoss
from torchsym.losses.prsnet import closest_point_grid, grid_cell_index, occupancy_grid, prsnet_symmetry_loss
from torchsym.losses.regularizers import orthogonality_loss
from torchsym.losses.symmetry_distance import nearest_neighbours, reflect_batch, robust_kernel, symmetry_distance

__all__ = [
    "BinaryFocalLossWithLogits",
    "OrthogonalityLoss",
    "PRSNetSymmetryLoss",
    "SymmetryDistanceLoss",
    "binary_focal_loss_with_logits",
    "closest_point_grid",
    "field_symmetry_loss",
    "flip_consistency_loss",
    "grid_cell_index",
    "nearest_neighbours",
    "occupancy_grid",
    "orientation_flip_permutation",
    "orthogonality_loss",
    "prsnet_symmetry_loss",
    "reflect_batch",
    "robust_kernel",
    "symmetry_distance",
]
