"""The symmetry score map of one cluster (thesis Eqs. 3.7-3.8)."""

from __future__ import annotations

import torch

__all__ = ["distance_to_points", "symmetry_scores"]


def distance_to_points(height: int, width: int, points: torch.Tensor, chunk: int = 65536) -> torch.Tensor:
    """``(H * W,)`` distance of every pixel to the nearest of ``points (M, 2)`` (``inf`` if none)."""
    ys, xs = torch.meshgrid(
        torch.arange(height, device=points.device, dtype=torch.float32),
        torch.arange(width, device=points.device, dtype=torch.float32),
        indexing="ij",
    )
    grid = torch.stack([xs.reshape(-1), ys.reshape(-1)], 1)  # (N, 2)
    if points.shape[0] == 0:
        return torch.full((grid.shape[0],), float("inf"), device=points.device)
    out = torch.empty(grid.shape[0], device=points.device)
    pts = points.float()
    for s in range(0, grid.shape[0], chunk):
        out[s : s + chunk] = torch.cdist(grid[s : s + chunk], pts).min(1).values
    return out


def symmetry_scores(
    cost: torch.Tensor, distance: torch.Tensor, height: int, width: int, *, sigma_feature: float, sigma_d: float
) -> torch.Tensor:
    """``S(p) = exp(-cost_p / sigma_feature^2) exp(-dist(p, I)^2 / ((w^2 + h^2) sigma_d^2))``, ``(H * W,)`` in [0, 1].

    ``cost (H * W,)`` is ``|d_p - m_f(p)|^2`` (Eq. 3.7; the thesis's ``sigma_feature`` is 1)
    and ``distance (H * W,)`` the pixel's distance to the cluster's pixels ``I``.
    """
    diag2 = float(height * height + width * width)
    s = torch.exp(-cost / sigma_feature**2) * torch.exp(-(distance**2) / (diag2 * sigma_d**2))
    return s.clamp(0.0, 1.0)
