"""Converters between the plane conventions of the learned symmetry methods.

torchsym writes a plane as a unit ``normal (..., D)`` and an ``offset (...)``, the set
``{x : normal . x + offset = 0}``. Two other conventions are common:

- PRS-Net's 4-vector ``(a, b, c, d)``: the plane ``a x + b y + c z + d = 0`` with a
  normal of any length; its reflection divides by ``|(a, b, c)|`` (``planesymTransform``
  in ``IGLICT/PRS-Net`` ``models/network.py``). Here any ``D``: ``(..., D + 1)``.
- NeRD's ``w (..., D)``: the plane ``w . x + 1 = 0`` (``w2S`` and ``sample_plane`` in
  ``zhou13/nerd`` ``sym/datasets.py``), so ``normal = w / |w|`` and ``offset = 1 / |w|``.
  A plane through the origin has no ``w`` (its ``|w|`` is infinite).

Also a shape check shared by the losses: ``normal (B, K, D)`` with ``offset (B, K)``.
Every converter keeps dtype and device, is batched and differentiable.
"""

from __future__ import annotations

import torch

from torchsym.errors import InputShapeError

__all__ = ["check_planes", "planes_from_nerd", "planes_from_prsnet", "planes_to_nerd", "planes_to_prsnet"]


def check_planes(normal: torch.Tensor, offset: torch.Tensor, dim: int | None = None) -> None:
    """Check ``normal (B, K, D)`` and ``offset (B, K)`` (and ``D == dim`` when given); raise
    :class:`InputShapeError` naming the argument otherwise."""
    if not isinstance(normal, torch.Tensor) or normal.dim() != 3 or normal.shape[-1] < 1:
        raise InputShapeError(f"normal: expected a (B, K, D) tensor, got {getattr(normal, 'shape', type(normal).__name__)}")
    if dim is not None and normal.shape[-1] != dim:
        raise InputShapeError(f"normal: expected (B, K, {dim}) to match the points, got {tuple(normal.shape)}")
    if not isinstance(offset, torch.Tensor) or offset.shape != normal.shape[:-1]:
        raise InputShapeError(
            f"offset: expected {tuple(normal.shape[:-1])} to match normal, got {getattr(offset, 'shape', type(offset).__name__)}"
        )


def _tiny(t: torch.Tensor) -> float:
    return torch.finfo(t.dtype).tiny if t.is_floating_point() else 1e-38


def planes_from_prsnet(plane: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """``(..., D + 1)`` PRS-Net plane ``[a; d]`` (``a . x + d = 0``) to unit ``normal (..., D)``
    and ``offset (...)``, both divided by ``|a|``.

    Example:
        >>> planes_from_prsnet(torch.tensor([0.0, 0.0, 2.0, -1.0]))
        (tensor([0., 0., 1.]), tensor(-0.5000))
    """
    if not isinstance(plane, torch.Tensor) or plane.dim() < 1 or plane.shape[-1] < 2:
        raise InputShapeError(f"plane: expected a (..., D + 1) tensor with D >= 1, got {getattr(plane, 'shape', type(plane).__name__)}")
    a, d = plane[..., :-1], plane[..., -1]
    norm = a.norm(dim=-1).clamp_min(_tiny(a))
    return a / norm.unsqueeze(-1), d / norm


def planes_to_prsnet(normal: torch.Tensor, offset: torch.Tensor) -> torch.Tensor:
    """Unit ``normal (..., D)`` and ``offset (...)`` to PRS-Net's ``(..., D + 1)`` vector
    ``[normal; offset]`` (the unit-normal representative)."""
    if not isinstance(normal, torch.Tensor) or normal.dim() < 1:
        raise InputShapeError(f"normal: expected a (..., D) tensor, got {getattr(normal, 'shape', type(normal).__name__)}")
    offset = torch.as_tensor(offset, dtype=normal.dtype, device=normal.device).expand(normal.shape[:-1])
    norm = normal.norm(dim=-1).clamp_min(_tiny(normal))
    return torch.cat([normal / norm.unsqueeze(-1), (offset / norm).unsqueeze(-1)], dim=-1)


def planes_from_nerd(w: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """NeRD's ``w (..., D)`` (plane ``w . x + 1 = 0``) to ``normal = w / |w|`` and
    ``offset = 1 / |w|`` (always positive: the origin lies on the normal's negative side).

    Example:
        >>> planes_from_nerd(torch.tensor([0.0, 0.0, -2.0]))
        (tensor([ 0.,  0., -1.]), tensor(0.5000))
    """
    if not isinstance(w, torch.Tensor) or w.dim() < 1:
        raise InputShapeError(f"w: expected a (..., D) tensor, got {getattr(w, 'shape', type(w).__name__)}")
    norm = w.norm(dim=-1).clamp_min(_tiny(w))
    return w / norm.unsqueeze(-1), 1.0 / norm


def planes_to_nerd(normal: torch.Tensor, offset: torch.Tensor) -> torch.Tensor:
    """``normal (..., D)`` and ``offset (...)`` to NeRD's ``w = normal / offset`` (``(..., D)``).

    A plane through the origin (``offset = 0``) has no such ``w``: its entries are
    infinite. NeRD further rescales the scene so that ``w[2] = 1`` (monocular depth has
    no scale); that is a change of the scene, not of the convention, and is left out.
    """
    if not isinstance(normal, torch.Tensor) or normal.dim() < 1:
        raise InputShapeError(f"normal: expected a (..., D) tensor, got {getattr(normal, 'shape', type(normal).__name__)}")
    offset = torch.as_tensor(offset, dtype=normal.dtype, device=normal.device).expand(normal.shape[:-1])
    return normal / offset.unsqueeze(-1)  # (n/|n|) / (b/|n|): the scale of the normal cancels
