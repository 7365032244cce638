"""Fixtures of the intrinsic-symmetry tests: the solved blob, its spectra, and a spy on the settings the Module passes on."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.mesh import heat_kernel_signature, hks_times, intrinsic_symmetry, laplacian_eigen


@pytest.fixture(scope="module")
def solved(blob):
    mesh, gt = blob
    return intrinsic_symmetry(mesh), mesh, gt


@pytest.fixture(scope="module")
def spectral25(blob):
    """The blob's first 25 eigenfunctions, areas, orientation operators, a 300-vertex sample and its ground truth."""
    from torchsym.mesh.operators import mass_matrix
    from torchsym.mesh.orientation import orientation_operators, reduce_descriptors

    mesh, gt = blob
    v, f = mesh.vertices.double().numpy(), mesh.faces.numpy()
    evals, big = laplacian_eigen(v, f, 25, generator=torch.Generator().manual_seed(0))
    area = mass_matrix(v, f).diagonal()
    hks = heat_kernel_signature(evals[:13], big[:, :13], hks_times(evals[:13], 50))
    ops = orientation_operators(v, f, big, reduce_descriptors(hks, area))  # (r, 25, 25)
    rows = np.sort(np.random.default_rng(0).choice(v.shape[0], 300, replace=False))
    return big, area, ops, rows, gt


@pytest.fixture
def settings_spy(monkeypatch) -> dict:
    """Record the settings the module passes on to ``intrinsic_symmetry`` (the dict fills on each call)."""
    from torchsym.mesh.intrinsic import solver

    seen: dict = {}
    original = solver.intrinsic_symmetry

    def spy(mesh, settings=None, **kw):
        seen["settings"] = settings
        return original(mesh, settings, **kw)

    monkeypatch.setattr(solver, "intrinsic_symmetry", spy)
    return seen
