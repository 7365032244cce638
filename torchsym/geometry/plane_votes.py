"""Dense plane votes: one plane from each mirror pair, and sign-invariant clustering of them.

E3Sym (``renwuli/e3sym`` ``lib/model.py``, ``dense_predict``) turns every predicted pair
``(p, q)`` into the plane bisecting it, ``n = (q - p) / |q - p|``, ``d = -n . (p + q) / 2``,
then groups the votes by a radius graph on the 4-vectors ``[n, d]`` and keeps one
representative per connected component (``lib/ops/function.py``). A 4-vector and its
negative are the same plane, which a plain distance on ``[n, d]`` splits in two;
:func:`cluster_planes` compares ``(n, d)`` with both ``(n', d')`` and ``(-n', -d')``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import torch
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError

__all__ = ["PlaneClusters", "cluster_planes", "pair_planes", "plane_vote_distance"]


def pair_planes(points: torch.Tensor, mirrors: torch.Tensor, eps: float = 1e-12) -> tuple[torch.Tensor, torch.Tensor]:
    """The bisecting plane of each pair ``(points[i], mirrors[i])``.

    Args:
        points: ``(..., N, D)`` first points.
        mirrors: ``(..., N, D)`` their partners.
        eps: floor of ``|q - p|`` (a pair of equal points gets a zero normal, not NaN).

    Returns:
        ``normal (..., N, D)`` unit, pointing from ``p`` to ``q``, and ``offset (..., N)``:
        ``n . x + offset = 0`` holds at the midpoint and reflects ``p`` onto ``q``.
    """
    if not isinstance(points, torch.Tensor) or not isinstance(mirrors, torch.Tensor) or points.dim() < 2:
        raise InputShapeError(f"points: expected a (..., N, D) tensor, got {getattr(points, 'shape', type(points).__name__)}")
    if mirrors.shape != points.shape:
        raise InputShapeError(f"mirrors: expected {tuple(points.shape)} like points, got {tuple(mirrors.shape)}")
    chord = mirrors - points  # (..., N, D)
    normal = chord / chord.norm(dim=-1, keepdim=True).clamp_min(eps)
    offset = -(normal * 0.5 * (points + mirrors)).sum(-1)
    return normal, offset


def plane_vote_distance(normal: torch.Tensor, offset: torch.Tensor, scale: float = 1.0) -> torch.Tensor:
    """Sign-invariant distance between every two planes, ``(..., M, M)``.

    ``min_s sqrt(|n_i - s n_j|^2 + ((b_i - s b_j) / scale)^2)`` over ``s = +-1``, so
    ``(n, b)`` and ``(-n, -b)`` are at distance 0. ``scale`` is the length at which an
    offset difference weighs like a unit normal difference (e.g. the shape's radius).
    """
    if normal.dim() < 2 or offset.shape != normal.shape[:-1]:
        raise InputShapeError(f"offset: expected {tuple(normal.shape[:-1])} to match normal, got {tuple(offset.shape)}")
    dot = normal @ normal.transpose(-1, -2)  # (..., M, M)
    sq = (normal * normal).sum(-1)
    nn_sq = sq.unsqueeze(-1) + sq.unsqueeze(-2)
    b = offset / scale
    same = nn_sq - 2 * dot + (b.unsqueeze(-1) - b.unsqueeze(-2)) ** 2
    flip = nn_sq + 2 * dot + (b.unsqueeze(-1) + b.unsqueeze(-2)) ** 2
    return torch.minimum(same, flip).clamp_min(0).sqrt()


@dataclasses.dataclass(frozen=True)
class PlaneClusters(Result):
    """Clusters of plane votes, heaviest first.

    Attributes:
        normal: ``(C, D)`` unit normal of each cluster (weighted mean of its sign-aligned votes).
        offset: ``(C,)`` offset of each cluster.
        weight: ``(C,)`` summed weight of its votes.
        size: ``(C,)`` number of votes in it.
        labels: ``(M,)`` cluster of each vote, -1 for votes in clusters under ``min_size``.
    """

    normal: torch.Tensor
    offset: torch.Tensor
    weight: torch.Tensor
    size: torch.Tensor
    labels: torch.Tensor


def cluster_planes(
    normal: torch.Tensor,
    offset: torch.Tensor,
    weight: torch.Tensor | None = None,
    *,
    radius: float = 0.1,
    scale: float = 1.0,
    min_size: int = 1,
) -> PlaneClusters:
    """Group ``M`` plane votes whose sign-invariant distance is under ``radius``.

    The votes are the nodes of a graph with an edge wherever :func:`plane_vote_distance`
    is below ``radius``; each connected component with at least ``min_size`` votes is a
    cluster (E3Sym's grouping, with the sign made irrelevant). A cluster's plane is the
    weighted mean of its votes after flipping each to agree with the heaviest one.
    Not differentiable (the grouping is discrete); ``O(M^2)`` memory.

    Args:
        normal: ``(M, D)`` unit normals.
        offset: ``(M,)`` offsets.
        weight: ``(M,)`` non-negative vote weights; None weighs all 1.
        radius: linking distance (unitless; ``0.1`` is about 6 degrees of normal).
        scale: offset length matching a unit normal difference.
        min_size: smallest cluster kept.
    """
    if normal.dim() != 2 or offset.shape != normal.shape[:1]:
        raise InputShapeError(f"normal, offset: expected (M, D) and (M,), got {tuple(normal.shape)} and {tuple(offset.shape)}")
    if not (radius > 0 and math.isfinite(radius)):
        raise InputValueError(f"radius: expected a finite value > 0, got {radius}")
    m = normal.shape[0]
    w = torch.ones(m, dtype=normal.dtype, device=normal.device) if weight is None else weight.to(normal.dtype)
    if w.shape != (m,):
        raise InputShapeError(f"weight: expected ({m},), got {tuple(w.shape)}")
    n64, b64, w64 = (t.detach().to("cpu", torch.float64) for t in (normal, offset, w))
    close = (plane_vote_distance(n64, b64, scale) < radius).numpy()
    rows, cols = np.nonzero(close)
    graph = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(m, m))
    _, comp = connected_components(graph, directed=False)
    comp_t = torch.from_numpy(comp)
    labels = torch.full((m,), -1, dtype=torch.long)
    clusters = []
    for c in np.unique(comp):
        idx = torch.nonzero(comp_t == int(c)).squeeze(1)
        if idx.numel() < min_size:
            continue
        lead = idx[w64[idx].argmax()]
        sign = torch.where((n64[idx] @ n64[lead]) < 0, -1.0, 1.0).double()  # (m_c,)
        ww = w64[idx] * sign
        nc = (n64[idx] * ww.unsqueeze(1)).sum(0)
        bc = (b64[idx] * ww).sum()
        norm = nc.norm().clamp_min(1e-300)
        clusters.append((float(w64[idx].sum()), nc / norm, bc / norm, idx))
    clusters.sort(key=lambda t: -t[0])
    for k, (_, _, _, idx) in enumerate(clusters):
        labels[idx] = k
    dev, dt = normal.device, normal.dtype
    if not clusters:
        d = normal.shape[1]
        e = torch.zeros(0, dtype=dt, device=dev)
        return PlaneClusters(torch.zeros(0, d, dtype=dt, device=dev), e, e, torch.zeros(0, dtype=torch.long), labels.to(dev))
    return PlaneClusters(
        normal=torch.stack([c[1] for c in clusters]).to(dev, dt),
        offset=torch.stack([c[2] for c in clusters]).to(dev, dt),
        weight=torch.tensor([c[0] for c in clusters], dtype=dt, device=dev),
        size=torch.tensor([c[3].numel() for c in clusters], dtype=torch.long, device=dev),
        labels=labels.to(dev),
    )
