"""Sets that span only a proper affine subspace of R^D: solve in the hull, lift back.

Every reflection of a set maps its affine hull onto itself, so a flat set (``N <= D``
points, or data of lower rank) is solved in coordinates of its hull and the plane lifted
back with its normal in the hull (an extension: the thesis's sets fill their space).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import torch

from torchsym.pointset import transform as tf

__all__ = ["hull_basis", "lift_result"]


def hull_basis(raw: np.ndarray, centred: np.ndarray, dtype: torch.dtype) -> np.ndarray | None:
    """``(D, r)`` orthonormal basis of the directions a centred set spans, ``r >= 2``, or None
    when it spans ``R^D`` (or ``D = 2``).

    A direction ``v`` counts when its singular value exceeds what rounding the input's
    coordinates to ``dtype`` can put along it, ``4 eps |(|X| |v|)|``. ``raw`` is the
    ``(N, D)`` input; ``centred`` must be centred twice (the mean's own rounding adds a
    direction).
    """
    n, d = centred.shape
    if d <= 2:
        return None
    _, sv, vt = np.linalg.svd(centred, full_matrices=False)
    noise = 4.0 * torch.finfo(dtype).eps * np.linalg.norm(np.abs(raw) @ np.abs(vt.T), axis=0)
    r = max(int((sv > noise).sum()), 2)
    return None if r >= d else vt[:r].T.copy()


def lift_result(sub: Any, basis: np.ndarray, mu: np.ndarray, dtype: torch.dtype, device: Any) -> Any:
    """A :class:`~torchsym.pointset.PointSymmResult` found in the hull coordinates
    ``y = basis^T (x - mu)`` as a result in ``R^D``."""
    normal = basis @ sub.normal.numpy()
    normal = normal / np.linalg.norm(normal)
    k = int(np.argmax(np.abs(normal)))
    normal = normal * (1.0 if normal[k] >= 0 else -1.0)
    translation = mu + basis @ sub.translation.numpy()
    rots = tf.rotations_from_normal(torch.from_numpy(normal))
    return dataclasses.replace(
        sub,
        normal=torch.as_tensor(normal, dtype=dtype, device=device),
        offset=torch.as_tensor(-float(normal @ translation), dtype=dtype, device=device),
        rotations=torch.as_tensor(torch.stack(rots), dtype=dtype, device=device),
        translation=torch.as_tensor(translation, dtype=dtype, device=device),
        permutation=sub.permutation.to(device),
        residuals=torch.as_tensor(sub.residuals, dtype=dtype, device=device),
    )
