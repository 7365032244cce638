"""Orientation-reversing functional self-maps (torchsym.mesh.orientation)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.mesh import (
    descriptor_operators,
    functional_to_pointwise,
    heat_kernel_signature,
    hks_times,
    intrinsic_symmetry,
    laplacian_eigen,
    mass_matrix,
    orientation_operators,
    orientation_reversing_map,
    pointwise_to_functional,
    resolvent_mask,
)
from torchsym.mesh.orientation import _commutator_gram
from torchsym.mesh.synthetic import twist


@pytest.fixture(scope="module")
def spectral_blob(blob):
    mesh, gt = blob
    v, f = mesh.vertices.double().numpy(), mesh.faces.numpy()
    evals, evecs = laplacian_eigen(v, f, 13, generator=torch.Generator().manual_seed(0))
    area = mass_matrix(v, f).diagonal()
    hks = heat_kernel_signature(evals, evecs, hks_times(evals, 50))
    true_c = pointwise_to_functional(evecs, area, gt)  # (k, k) the symmetry's functional map
    return v, f, evals, evecs, area, hks, gt, true_c


def test_commutator_gram_matches_the_direct_sum():
    rng = np.random.default_rng(0)
    ops = rng.standard_normal((4, 6, 6))
    c = rng.standard_normal((6, 6))
    for sign in (1.0, -1.0):
        gram, _ = _commutator_gram(ops, sign)
        direct = sum(np.sum((c @ x - sign * x @ c) ** 2) for x in ops)
        assert c.ravel() @ gram @ c.ravel() == pytest.approx(direct, rel=1e-12)


def test_symmetry_commutes_with_descriptors_and_anticommutes_with_orientation(spectral_blob):
    v, f, _, evecs, area, hks, _, true_c = spectral_blob
    desc = hks[:, ::10]
    d_ops = descriptor_operators(evecs, area, desc)  # (p, k, k)
    o_ops = orientation_operators(v, f, evecs, desc)
    for d, o in zip(d_ops, o_ops):
        assert np.linalg.norm(true_c @ d - d @ true_c) < 0.05 * np.linalg.norm(d)
        assert np.linalg.norm(true_c @ o + o @ true_c) < 0.05 * np.linalg.norm(o)
        # the identity commutes with both: only the sign of the orientation term tells them apart
        assert np.linalg.norm(o + o) > 0.5 * np.linalg.norm(o)


def test_orientation_operator_flips_sign_with_the_surface_orientation(spectral_blob):
    v, f, _, evecs, _, hks, _, _ = spectral_blob
    ops = orientation_operators(v, f, evecs, hks[:, :3])
    flipped = orientation_operators(v, f[:, ::-1].copy(), evecs, hks[:, :3])
    np.testing.assert_allclose(flipped, -ops, atol=1e-12 * np.abs(ops).max())


def test_orientation_reversing_map_recovers_the_mirror(spectral_blob):
    v, f, evals, evecs, area, hks, gt, _ = spectral_blob
    fmap = orientation_reversing_map(v, f, evals, evecs, area, hks)
    assert fmap.shape == (13, 13)
    np.testing.assert_allclose(fmap[:, 0], np.eye(13)[0])  # constants map to constants
    vmap = functional_to_pointwise(evecs, fmap)
    assert np.mean(vmap == gt) > 0.9
    assert np.mean(vmap == np.arange(len(gt))) < 0.05  # not the identity


def test_orientation_reversing_map_is_invariant_to_descriptor_basis(spectral_blob):
    """The energy depends on the descriptors only through sum_p f_p f_p^T."""
    v, f, evals, evecs, area, hks, _, _ = spectral_blob
    a = orientation_reversing_map(v, f, evals, evecs, area, hks)
    b = orientation_reversing_map(v, f, evals, evecs, area, hks[:, ::-1])
    np.testing.assert_allclose(a, b, atol=1e-8)


def test_resolvent_mask():
    evals = np.array([0.0, 1.0, 1.0, 4.0, 9.0])
    mask = resolvent_mask(evals)
    np.testing.assert_allclose(mask, mask.T)
    assert np.all(np.diag(mask) == 0) and mask[1, 2] == 0  # equal eigenvalues are free
    assert mask[0, 4] > mask[0, 3] > mask[0, 1] > 0
    assert mask.max() <= 2.0  # bounded, unlike (lambda_i - lambda_j)^2


def test_intrinsic_symmetry_keeps_the_thesis_map_on_a_nearly_ambiguous_shape(blob):
    """The twisted blob is nearly a sphere: the orientation-reversing fit finds another
    near-isometric involution with smaller functional defects than the true mirror. The
    geodesic test keeps the thesis's (correct) map; the choice is seeded (same bits)."""
    from torchsym.metrics import correspondence_rate

    mesh, gt = blob
    bent = twist(mesh, angle=0.3)
    on = intrinsic_symmetry(bent)
    off = intrinsic_symmetry(bent, orientation_hypothesis=False)
    assert on.hypothesis == "pairs" and off.hypothesis == "pairs"
    assert correspondence_rate(bent, on.map, ground_truth=torch.from_numpy(gt)).rate > 0.95
    assert torch.equal(on.map, intrinsic_symmetry(bent).map)


def test_rank_choice_rules():
    from torchsym.mesh.intrinsic import _rank_choice

    inf = np.inf
    # the challenger ranks first and distorts geodesics less: it wins
    assert _rank_choice(np.array([[2.0, 4.0, 0.05], [1.0, 2.0, 0.03]]), 0.08) == 1
    # ranks first on the functional defects but distorts geodesics more: the thesis's map stays
    assert _rank_choice(np.array([[2.0, 4.0, 0.03], [1.0, 2.0, 0.04]]), 0.08) == 0
    # too much distortion in absolute terms: stays
    assert _rank_choice(np.array([[2.0, 4.0, 0.30], [1.0, 2.0, 0.10]]), 0.08) == 0
    # an unusable thesis map: a usable challenger below the limit wins, else row 0
    assert _rank_choice(np.array([[inf, inf, inf], [1.0, 2.0, 0.05]]), 0.08) == 1
    assert _rank_choice(np.array([[inf, inf, inf], [1.0, 2.0, 0.30]]), 0.08) == 0
    assert _rank_choice(np.array([[inf, inf, inf], [inf, inf, inf]]), 0.08) == 0


def test_has_boundary(blob):
    from torchsym.mesh.intrinsic import _has_boundary

    mesh, _ = blob
    faces = mesh.faces.numpy()
    assert not _has_boundary(faces)  # a closed sphere
    assert _has_boundary(faces[1:])  # one triangle removed: a hole
