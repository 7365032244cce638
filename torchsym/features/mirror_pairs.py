"""Mirror symmetric pixel pairs (MSPPs) by mutual k1 nearest neighbours (thesis Def. 2.2.1).

Keypoints ``p_i`` and ``p_j`` form an MSPP when ``p_j`` is among the ``k1`` nearest
neighbours of ``p_i`` and ``p_i`` among the ``k1`` nearest neighbours of ``p_j`` (the
"best buddy" rule), where the distance from ``p_w`` to ``p_i`` is
``|m_w - d_i|_2``, mirrored descriptor of one against descriptor of the other, and a
keypoint is never its own neighbour (Eq. 2.1). Because the mirror map is a permutation and
an involution, ``|m_w - d_i| = |d_w - m_i|``: the distance matrix is symmetric.

The thesis says ``k1`` is "determined automatically" and points to Sec. 2.2.3, whose only
automatic rule is the elbow of a curve; :func:`choose_k1` applies that rule to the number
of MSPPs found as ``k1`` grows.
"""

from __future__ import annotations

import torch

from torchsym.core.checks import check_int
from torchsym.errors import InputShapeError
from torchsym.features.sift import SiftFeatures, detect_sift, mirror_descriptors

__all__ = [
    "choose_k1",
    "elbow_index",
    "mirror_distance_matrix",
    "mirror_sift_distances",
    "mirror_sift_knn",
    "mutual_knn_pairs",
    "nearest_mirrors",
]


def elbow_index(values: torch.Tensor) -> int:
    """Index of the elbow of a monotone curve ``values (K,)``: the point farthest from the chord.

    Both axes are normalised to [0, 1] first (the "kneedle" construction). A curve with
    fewer than 3 points, or a straight one, gives index 0.
    """
    v = values.detach().double().flatten()
    k = v.numel()
    if k < 3:
        return 0
    span = (v.max() - v.min()).item()
    if span <= 0:
        return 0
    x = torch.linspace(0, 1, k, dtype=torch.float64)
    y = (v - v.min()) / span
    # distance of (x, y) to the chord from the first to the last point
    dx, dy = x[-1] - x[0], y[-1] - y[0]
    dist = (dy * (x - x[0]) - dx * (y - y[0])).abs() / torch.sqrt(dx * dx + dy * dy)
    if dist.max().item() < 1e-9:
        return 0
    return int(dist.argmax())


def mirror_distance_matrix(
    descriptors: torch.Tensor, points: torch.Tensor, *, min_distance: float = 0.0, layout: str = "kornia"
) -> torch.Tensor:
    """``(N, N)`` distances ``|m_j - d_i|``; the diagonal and pairs closer than ``min_distance``
    pixels are ``inf``. ``layout``: the descriptors' (:func:`~torchsym.features.sift.mirror_permutation`)."""
    if descriptors.dim() != 2 or points.dim() != 2 or descriptors.shape[0] != points.shape[0]:
        raise InputShapeError(
            f"descriptors: expected (N, 128) matching points (N, 2), got {tuple(descriptors.shape)} and {tuple(points.shape)}"
        )
    mir = mirror_descriptors(descriptors, layout=layout)  # (N, 128)
    dist = torch.cdist(descriptors.float(), mir.float())  # (N, N)
    dist = 0.5 * (dist + dist.T)  # exact up to rounding, see module docstring
    near = torch.cdist(points.float(), points.float()) < max(min_distance, 1e-6)  # (N, N), includes the diagonal
    return dist.masked_fill(near, float("inf"))


def nearest_mirrors(dist: torch.Tensor, k: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Each keypoint's ``k`` nearest mirror matches under ``dist (N, N)`` (``inf`` entries
    left out), row by row, nearest first.

    Returns:
        ``i (M,)`` and ``j (M,)`` int64 keypoint indices and ``distance (M,)``.
    """
    k = min(k, dist.shape[0] - 1)
    vals, idx = dist.topk(k, dim=1, largest=False)  # (N, k)
    rows = torch.arange(dist.shape[0], device=dist.device)[:, None].expand(-1, k)
    ok = torch.isfinite(vals)
    return rows[ok], idx[ok], vals[ok]


def mirror_sift_distances(
    image: torch.Tensor, *, num_features: int = 1000, min_pair_distance: float = 5.0, backend: str = "kornia"
) -> tuple[SiftFeatures, torch.Tensor | None]:
    """SIFT keypoints of ``image`` (:func:`~torchsym.features.sift.detect_sift`, ``backend``)
    and the ``(N, N)`` mirrored-descriptor distances :func:`mirror_distance_matrix` gives in
    the descriptors' own layout (keypoints closer than ``min_pair_distance`` pixels not
    matched); None with fewer than two keypoints."""
    feats = detect_sift(image, num_features=num_features, backend=backend)
    if len(feats) < 2:
        return feats, None
    return feats, mirror_distance_matrix(feats.descriptors, feats.points, min_distance=min_pair_distance, layout=feats.layout)


def mirror_sift_knn(
    image: torch.Tensor, *, num_features: int = 1000, k: int = 3, min_pair_distance: float = 5.0, backend: str = "kornia"
) -> tuple[SiftFeatures, torch.Tensor, torch.Tensor, torch.Tensor]:
    """SIFT keypoints of ``image`` and each one's ``k`` nearest mirrored-SIFT matches
    (:func:`mirror_sift_distances`, then :func:`nearest_mirrors`).

    Args:
        image: ``(C, H, W)`` or ``(1, C, H, W)`` float image in [0, 1].
        num_features: the most SIFT keypoints.
        k: matches per keypoint.
        min_pair_distance: pixels.
        backend: SIFT's, ``"kornia"`` or ``"opencv"``.

    Returns:
        The features, and ``i (M,)``, ``j (M,)``, ``distance (M,)`` as
        :func:`nearest_mirrors` gives them (empty with fewer than two keypoints).
    """
    feats, dist = mirror_sift_distances(image, num_features=num_features, min_pair_distance=min_pair_distance, backend=backend)
    if dist is None:
        none = torch.zeros(0, dtype=torch.int64, device=feats.points.device)
        return feats, none, none, torch.zeros(0, device=feats.points.device)
    return (feats, *nearest_mirrors(dist, k))


def mutual_knn_pairs(dist: torch.Tensor, k1: int) -> torch.Tensor:
    """Pairs ``(i, j)``, ``i < j``, that are mutual ``k1`` nearest neighbours under ``dist (N, N)`` (Eq. 2.1).

    Returns:
        ``(P, 2)`` int64 indices.
    """
    k1 = check_int(k1, "k1", minimum=1)
    n = dist.shape[0]
    if n < 2:
        return torch.zeros(0, 2, dtype=torch.int64, device=dist.device)
    i, j, _ = nearest_mirrors(dist, k1)
    knn = torch.zeros(n, n, dtype=torch.bool, device=dist.device)
    knn[i, j] = True
    mutual = knn & knn.T
    return torch.triu(mutual, diagonal=1).nonzero()


def choose_k1(dist: torch.Tensor, *, k_max: int = 10) -> int:
    """``k1`` at the elbow of the number of mutual ``k1``-NN pairs for ``k1 = 1..k_max`` (thesis Sec. 2.2.1)."""
    k_max = check_int(k_max, "k_max", minimum=1)
    counts = torch.tensor([float(mutual_knn_pairs(dist, k).shape[0]) for k in range(1, k_max + 1)])
    return elbow_index(counts) + 1
