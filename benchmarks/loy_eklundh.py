"""Reference implementation of Loy & Eklundh (ECCV 2006), the standard baseline for
reflection axes in photographs.

Each SIFT keypoint is matched against the *mirrored* descriptors of the others (the
mirror permutation of :mod:`torchsym.features.sift`); every match ``(i, j)`` votes for the
perpendicular bisector ``r = x_c cos(theta) + y_c sin(theta)`` in a Hough space with
weight ``Phi_ij * S_ij``: ``Phi_ij = 1 - cos(phi_i + phi_j - 2 theta_ij)`` (orientations
must be mirror images about the axis) and ``S_ij = exp(-|s_i - s_j| / (s_i + s_j))^2``
(similar scales). Peaks of the Gaussian-smoothed accumulator are the axes; an axis's
extent is that of the pairs that voted for it, its score the peak's vote.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from torchsym.core.checks import check_image
from torchsym.features.mirror_pairs import mirror_sift_knn
from torchsym.image.results import ReflectionAxesResult, build_result, empty_result

__all__ = ["loy_eklundh_axes"]


def loy_eklundh_axes(
    image: torch.Tensor,
    *,
    num_features: int = 1000,
    matches_per_point: int = 3,
    theta_bins: int = 180,
    r_bin: float = 2.0,
    smooth: float = 1.5,
    max_axes: int = 5,
    min_peak: float = 0.2,
    min_pair_distance: float = 5.0,
) -> ReflectionAxesResult:
    """Reflection axes of ``image (C, H, W)`` by mirrored-SIFT Hough voting (Loy & Eklundh 2006).

    Args:
        image: ``(C, H, W)`` or ``(1, C, H, W)`` float image in [0, 1].
        num_features: the most SIFT keypoints.
        matches_per_point: mirrored-descriptor matches kept per keypoint.
        theta_bins: angle bins over [0, pi).
        r_bin: distance bin width in pixels.
        smooth: Gaussian smoothing of the accumulator, in bins.
        max_axes: the most peaks returned.
        min_peak: peaks below this fraction of the highest are dropped.
        min_pair_distance: keypoints closer than this (pixels) are not paired.
    """
    import cv2

    img = check_image(image, "image", min_size=16)
    h, w = int(img.shape[-2]), int(img.shape[-1])
    feats, ii, jj, _ = mirror_sift_knn(img, num_features=num_features, k=matches_per_point, min_pair_distance=min_pair_distance)
    if len(feats) < 2:
        return empty_result(h, w, "loy_eklundh")
    ii, jj = ii.numpy(), jj.numpy()
    keep = ii != jj
    ii, jj = ii[keep], jj[keep]
    if ii.size == 0:
        return empty_result(h, w, "loy_eklundh")
    p = feats.points.double().numpy()
    phi = feats.orientations.double().numpy()
    s = feats.scales.double().numpy()
    d = p[jj] - p[ii]
    theta = np.arctan2(d[:, 1], d[:, 0])  # direction of the chord = axis normal
    weight = (1 - np.cos(phi[ii] + phi[jj] - 2 * theta)) * np.exp(-np.abs(s[ii] - s[jj]) / (s[ii] + s[jj])) ** 2
    theta = np.mod(theta, np.pi)
    mid = 0.5 * (p[ii] + p[jj])
    r = mid[:, 0] * np.cos(theta) + mid[:, 1] * np.sin(theta)
    r_max = math.hypot(h, w)
    n_r = int(math.ceil(2 * r_max / r_bin)) + 1
    ti = np.minimum((theta / np.pi * theta_bins).astype(np.int64), theta_bins - 1)
    ri = np.clip(((r + r_max) / r_bin).astype(np.int64), 0, n_r - 1)
    acc = np.zeros((theta_bins, n_r))
    np.add.at(acc, (ti, ri), weight)
    # theta wraps to theta + pi with r -> -r; pad by mirroring before smoothing
    pad = int(3 * smooth) + 1
    big = np.concatenate([acc[-pad:, ::-1], acc, acc[:pad, ::-1]], 0)
    big = cv2.GaussianBlur(big, (0, 0), smooth)
    acc_s = big[pad:-pad]
    peaks = (acc_s == cv2.dilate(acc_s, np.ones((7, 7), np.uint8))) & (acc_s > 0)
    pt, pr = np.nonzero(peaks)
    order = np.argsort(-acc_s[pt, pr])[:max_axes]
    top = acc_s[pt[order[0]], pr[order[0]]] if order.size else 0.0
    pairs = torch.from_numpy(np.concatenate([p[ii], p[jj]], 1))
    lines, supports, scores = [], [], []
    for o in order:
        val = acc_s[pt[o], pr[o]]
        if val < min_peak * top:
            break
        th = (pt[o] + 0.5) / theta_bins * np.pi
        rr = (pr[o] + 0.5) * r_bin - r_max
        dth = np.abs(np.mod(theta - th + np.pi / 2, np.pi) - np.pi / 2)
        sup = np.nonzero((dth < 2 * np.pi / theta_bins) & (np.abs(r - rr) < 2 * r_bin) & (weight > 0.5))[0]
        if sup.size < 2:
            continue
        lines.append(torch.tensor([math.cos(th), math.sin(th), -rr], dtype=torch.float64))
        supports.append(torch.from_numpy(sup))
        scores.append(float(val))
    return build_result(lines, supports, scores, pairs, h, w, "loy_eklundh")
