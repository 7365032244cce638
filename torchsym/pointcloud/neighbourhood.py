"""Steps every point-cloud detector shares about a point's neighbourhood (the one plane
of :mod:`~torchsym.pointcloud.reflection_plane`, every plane of
:mod:`~torchsym.pointcloud.reflection_planes`, the group of :mod:`~torchsym.pointcloud.symmetry`)."""

from __future__ import annotations

import torch

from torchsym.matching.knn import KNNIndex

__all__ = ["SUPPORT_REACH", "neighbourhood_pca"]

#: residuals beyond this many kernel widths add less than exp(-18) to a support: not searched for
SUPPORT_REACH = 6.0


def neighbourhood_pca(
    points: torch.Tensor, index: KNNIndex, at: torch.Tensor, k: int = 10
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The ``k`` nearest points of ``points (N, 3)`` (``index`` over them) to each of
    ``at (M, 3)``: their centroid ``(M, 3)``, and the eigenvalues ``(M, 3)`` (ascending)
    and eigenvectors ``(M, 3, 3)`` (columns) of their scatter matrix."""
    _, j = index.query(at, k=min(k, points.shape[0]))
    nb = points[j]  # (M, k, 3)
    centroid = nb.mean(1)
    nb = nb - centroid[:, None, :]
    lam, vecs = torch.linalg.eigh(nb.transpose(1, 2) @ nb)
    return centroid, lam, vecs
