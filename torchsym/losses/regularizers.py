"""Regularisers on sets of predicted planes."""

from __future__ import annotations

import torch

from torchsym.errors import InputShapeError
from torchsym.losses._common import _shape, check_finite_here, check_reduction, reduce, unit_planes

__all__ = ["orthogonality_loss"]


def orthogonality_loss(normal: torch.Tensor, plane_mask: torch.Tensor | None = None, *, reduction: str = "none") -> torch.Tensor:
    """PRS-Net's regulariser ``|N N^T - I|_F^2`` on the unit normals of ``K`` planes, per batch entry.

    PRS-Net (``IGLICT/PRS-Net`` ``models/network.py``, ``RegularLoss``) stacks its three
    normalised normals as ``M`` and penalises ``|M M^T - I|_F^2``, pushing the planes apart
    (mutually orthogonal). Here the ``K x K`` Gram form, which is the same for ``K = D``
    and defined for any ``K`` (for ``K > D`` the planes cannot all be orthogonal and the
    minimum is positive). PRS-Net weighs it by 25 against the symmetry distance.

    Args:
        normal: ``(B, K, D)`` normals (any non-zero length).
        plane_mask: ``(B, K)`` 1 for planes taking part (rows and columns of absent ones dropped).
        reduction: ``"none"`` gives ``(B,)``; ``"mean"`` / ``"sum"`` a scalar.

    A zero normal counts as the zero vector (its row of ``N N^T - I`` is ``-e_k``: the
    loss is largest there, with finite gradients). Raises :class:`InputShapeError` for a
    bad shape and :class:`InputValueError` for NaN or infinite normals (CPU tensors
    outside ``torch.compile``).
    """
    if not isinstance(normal, torch.Tensor) or normal.dim() != 3 or not normal.is_floating_point() or normal.shape[-1] < 1:
        raise InputShapeError(f"normal: expected a (B, K, D) floating tensor with D >= 1, got {_shape(normal)}")
    check_reduction(reduction)
    check_finite_here(normal, "normal")
    n, _ = unit_planes(normal, normal.new_zeros(normal.shape[:-1]))
    gram = n @ n.transpose(-1, -2)  # (B, K, K)
    eye = torch.eye(n.shape[1], dtype=n.dtype, device=n.device)
    diff = gram - eye
    if plane_mask is not None:
        if not isinstance(plane_mask, torch.Tensor) or plane_mask.shape != normal.shape[:2] or plane_mask.is_complex():
            raise InputShapeError(f"plane_mask: expected a real {tuple(normal.shape[:2])} tensor, got {_shape(plane_mask)}")
        check_finite_here(plane_mask.to(n.dtype), "plane_mask")
        m = plane_mask.to(n.dtype)
        diff = diff * m.unsqueeze(-1) * m.unsqueeze(-2)
    return reduce((diff**2).sum((-1, -2)), reduction)
