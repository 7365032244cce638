from __future__ import annotations

import numpy as np
import pytest
import torch
from scipy.spatial import cKDTree

from torchsym.mesh import Mesh
from torchsym.mesh.synthetic import icosphere


def eared_blob(subdivisions: int = 3) -> tuple[Mesh, np.ndarray]:
    """A deformed sphere with two ears, mirror symmetric across x = 0 only, and its mirror map."""
    s = icosphere(subdivisions)
    v = s.vertices.numpy()
    x, y, z = v.T
    scale = 1 + 0.8 * x**2 + 0.3 * y + 0.25 * y * z + 0.2 * z**2 * y
    for cx in (-1.0, 1.0):
        c = np.array([0.6 * cx, 0.55, 0.58])
        c /= np.linalg.norm(c)
        scale = scale + 0.6 * np.exp(-((v - c) ** 2).sum(1) / 0.02)
    w = v * scale[:, None]
    gt = cKDTree(w).query(w * np.array([-1.0, 1.0, 1.0]))[1]
    return Mesh(torch.from_numpy(w), s.faces), gt


@pytest.fixture(scope="session")
def blob() -> tuple[Mesh, np.ndarray]:
    return eared_blob(3)


@pytest.fixture
def rigid_motion() -> tuple[np.ndarray, np.ndarray]:
    """A random rotation (det +1) and translation."""
    rng = np.random.default_rng(1)
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q, rng.standard_normal(3) * 5


@pytest.fixture(scope="module")
def spectral(blob):
    from torchsym.mesh.operators import laplacian_eigen, mass_matrix

    mesh, gt = blob
    v, f = mesh.vertices.numpy(), mesh.faces.numpy()
    _, evecs = laplacian_eigen(v, f, 13, generator=torch.Generator().manual_seed(0))
    area = mass_matrix(v, f).diagonal()
    signs = np.sign((area[:, None] * evecs * evecs[gt]).sum(0))  # even +1, odd -1
    return evecs, signs
