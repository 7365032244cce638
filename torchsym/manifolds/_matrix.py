"""Small matrix helpers shared by the matrix manifolds."""

from __future__ import annotations

import torch


def sym(a: torch.Tensor) -> torch.Tensor:
    """Symmetric part ``(A + A^T) / 2`` of ``(..., n, n)`` matrices."""
    return 0.5 * (a + a.transpose(-1, -2))


def skew(a: torch.Tensor) -> torch.Tensor:
    """Skew-symmetric part ``(A - A^T) / 2`` of ``(..., n, n)`` matrices."""
    return 0.5 * (a - a.transpose(-1, -2))


def qr_unique(a: torch.Tensor) -> torch.Tensor:
    """The Q factor of ``A = QR`` with ``diag(R) >= 0`` (the sign fix that makes Q unique)."""
    q, r = torch.linalg.qr(a)
    s = torch.sign(torch.diagonal(r, dim1=-2, dim2=-1))
    s = torch.where(s == 0, torch.ones_like(s), s)
    return q * s.unsqueeze(-2)


def polar(a: torch.Tensor, special: bool = False) -> torch.Tensor:
    """The orthogonal polar factor ``U V^T`` of ``A = U S V^T``; with ``special`` its determinant is +1."""
    u, _, vh = torch.linalg.svd(a, full_matrices=False)
    if special:
        det = torch.linalg.det(u @ vh)
        flip = torch.ones(u.shape[:-1], dtype=a.dtype, device=a.device)
        flip[..., -1] = torch.where(det < 0, -torch.ones_like(det), torch.ones_like(det))
        u = u * flip.unsqueeze(-2)
    return u @ vh
