"""Regularisers on sets of predicted planes."""

from __future__ import annotations

import torch

from torchsym.errors import InputShapeError
from torchsym.losses._common import check_reduction, reduce

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
    """
    if not isinstance(normal, torch.Tensor) or normal.dim() != 3:
        raise InputShapeError(f"normal: expected a (B, K, D) tensor, got {getattr(normal, 'shape', type(normal).__name__)}")
    check_reduction(reduction)
    n = normal / normal.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    gram = n @ n.transpose(-1, -2)  # (B, K, K)
    eye = torch.eye(n.shape[1], dtype=n.dtype, device=n.device)
    diff = gram - eye
    if plane_mask is not None:
        if plane_mask.shape != normal.shape[:2]:
            raise InputShapeError(f"plane_mask: expected {tuple(normal.shape[:2])}, got {tuple(plane_mask.shape)}")
        m = plane_mask.to(n.dtype)
        diff = diff * m.unsqueeze(-1) * m.unsqueeze(-2)
    return reduce((diff**2).sum((-1, -2)), reduction)
