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
    eye = np.eye(true_c.shape[0])
    for d, o in zip(d_ops, o_ops):
        assert np.linalg.norm(true_c @ d - d @ true_c) < 0.05 * np.linalg.norm(d)
        anti = np.linalg.norm(true_c @ o + o @ true_c)
        assert anti < 0.05 * np.linalg.norm(o)
        # the identity commutes with D too: only the orientation term tells it from the mirror
        assert np.linalg.norm(eye @ d - d @ eye) == 0.0
        assert np.linalg.norm(eye @ o + o @ eye) > 20.0 * anti


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


def test_orientation_reversing_map_is_invariant_to_column_order_and_scale(blob):
    """Columns are normalised, then the energy depends on them only through sum_p f_p f_p^T
    (on a twisted blob, where no C zeroes every term, so the minimiser depends on them)."""
    mesh, _ = blob
    bent = twist(mesh, angle=0.6)
    v, f = bent.vertices.double().numpy(), bent.faces.numpy()
    evals, evecs = laplacian_eigen(v, f, 13, generator=torch.Generator().manual_seed(0))
    area = mass_matrix(v, f).diagonal()
    hks = heat_kernel_signature(evals, evecs, hks_times(evals, 50))
    a = orientation_reversing_map(v, f, evals, evecs, area, hks)
    scales = np.geomspace(0.1, 10.0, hks.shape[1])
    b = orientation_reversing_map(v, f, evals, evecs, area, (hks * scales)[:, ::-1])
    np.testing.assert_allclose(a, b, atol=1e-8)
    # and the descriptors matter: half of them give another minimiser
    c = orientation_reversing_map(v, f, evals, evecs, area, hks[:, :25])
    assert np.abs(a - c).max() > 1e-6


def test_orientation_reversing_map_bad_input(spectral_blob):
    from torchsym.errors import InputShapeError, InputValueError

    v, f, evals, evecs, area, hks, _, _ = spectral_blob
    with pytest.raises(InputShapeError, match="descriptors: expected"):
        orientation_reversing_map(v, f, evals, evecs, area, hks[:-1])
    with pytest.raises(InputValueError, match="descriptors: expected at least one non-zero"):
        orientation_reversing_map(v, f, evals, evecs, area, np.zeros_like(hks))
    with pytest.raises(InputValueError, match="descriptors: expected finite"):
        orientation_reversing_map(v, f, evals, evecs, area, np.full_like(hks, np.nan))
    with pytest.raises(InputValueError, match="w_orientation: expected a non-negative number"):
        orientation_reversing_map(v, f, evals, evecs, area, hks, w_orientation=-1.0)
    with pytest.raises(InputValueError, match="expected a positive sum"):
        orientation_reversing_map(
            v, f, evals, evecs, area, hks, w_descriptor=0, w_laplacian=0, w_commutation=0, w_orientation=0
        )


def test_resolvent_mask():
    evals = np.array([0.0, 1.0, 1.0, 4.0, 9.0])
    mask = resolvent_mask(evals)
    np.testing.assert_allclose(mask, mask.T)
    assert np.all(np.diag(mask) == 0) and mask[1, 2] == 0  # equal eigenvalues are free
    assert mask[0, 4] > mask[0, 3] > mask[0, 1] > 0
    assert mask.max() <= 2.0  # bounded, unlike (lambda_i - lambda_j)^2


def test_edge_face_counts_find_a_boundary(blob):
    from torchsym.mesh.operators import edge_face_counts

    mesh, _ = blob
    faces = mesh.faces.numpy()
    edges, counts = edge_face_counts(faces)
    assert edges.shape == (faces.shape[0] * 3 // 2, 2) and (counts == 2).all()  # a closed sphere
    _, counts = edge_face_counts(faces[1:])  # one triangle removed: a hole of 3 edges
    assert (counts == 1).sum() == 3


@pytest.mark.parametrize("dtype", [np.int64, np.int32])
def test_edge_face_counts_match_numpy_unique(dtype):
    from torchsym.mesh.operators import edge_face_counts

    rng = np.random.default_rng(0)
    for n in (0, 1, 7, 500):
        faces = rng.integers(0, 40, size=(n, 3)).astype(dtype)
        edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
        want_edges, want_counts = np.unique(edges.reshape(-1, 2), axis=0, return_counts=True)
        got_edges, got_counts = edge_face_counts(faces)
        assert np.array_equal(got_edges, want_edges.reshape(-1, 2)) and np.array_equal(got_counts, want_counts)
    # indices a key would overflow or collide on: the slow exact path
    big = np.array([[0, 2**32, 5], [5, 0, 2**32]], dtype=np.int64)
    edges, counts = edge_face_counts(big)
    assert edges.shape == (3, 2) and counts.tolist() == [2, 2, 2]
    neg = np.array([[-3, 3, 0], [-2, -1, 0]], dtype=np.int64)
    assert edge_face_counts(neg)[1].tolist() == [1, 1, 1, 1, 1, 1]


class TestOrientationReversal:
    """The pointwise test of whether a self map reverses the surface's orientation."""

    @staticmethod
    def _map(v: np.ndarray, matrix: np.ndarray) -> np.ndarray:
        from scipy.spatial import cKDTree

        return cKDTree(v).query(v @ matrix.T)[1]

    def test_reflection_reverses_and_rotation_keeps(self):
        from torchsym.mesh.orientation import orientation_reversal
        from torchsym.mesh.synthetic import icosphere

        s = icosphere(3)
        v, f = s.vertices.numpy(), s.faces.numpy()
        # the icosahedron's vertex coordinates are symmetric under every sign flip of one axis
        mirror = self._map(v, np.diag([-1.0, 1.0, 1.0]))
        half_turn = self._map(v, np.diag([-1.0, -1.0, 1.0]))  # rotation by pi about z
        assert np.all(orientation_reversal(v, f, mirror) == -1)
        assert np.all(orientation_reversal(v, f, half_turn) == 1)
        assert np.all(orientation_reversal(v, f, np.arange(v.shape[0])) == 1)
        # the winding, not the coordinates, defines the orientation: flipping it flips nothing here
        assert np.all(orientation_reversal(v, f[:, ::-1], mirror) == -1)

    def test_rows_and_collapse(self, blob):
        from torchsym.mesh.orientation import orientation_reversal

        mesh, gt = blob
        v, f = mesh.vertices.numpy(), mesh.faces.numpy()
        full = orientation_reversal(v, f, gt)
        assert (full == -1).mean() > 0.95  # all but a few vertices on the symmetry curve
        rows = np.array([5, 0, 17, 5])
        assert np.array_equal(orientation_reversal(v, f, gt, rows=rows), full[rows])
        from torchsym.errors import InputShapeError
        from torchsym.mesh.operators import ring_neighbourhood

        given = ring_neighbourhood(f, v.shape[0], rings=2)
        assert np.array_equal(orientation_reversal(v, f, gt, rows=rows, neighbourhood=given), full[rows])
        one_ring = orientation_reversal(v, f, gt, rings=1)
        assert np.array_equal(orientation_reversal(v, f, gt, neighbourhood=ring_neighbourhood(f, v.shape[0], rings=1)), one_ring)
        with pytest.raises(InputShapeError, match="neighbourhood: expected"):
            orientation_reversal(v, f, gt, neighbourhood=given[:5])
        assert np.all(orientation_reversal(v, f, np.zeros(v.shape[0], dtype=np.int64)) == 0)  # all to one vertex

    def test_orientation_test_gives_the_same_bits(self, blob):
        # the precomputed frames (the solver tests many maps on one sample) change nothing
        from torchsym.mesh.operators import ring_neighbourhood
        from torchsym.mesh.orientation import OrientationTest, orientation_reversal

        mesh, gt = blob
        v, f = mesh.vertices.double().numpy(), mesh.faces.numpy()
        rng = np.random.default_rng(0)
        rows = np.sort(rng.choice(v.shape[0], size=v.shape[0] // 3, replace=False))
        near = ring_neighbourhood(f, v.shape[0], rings=2)
        test = OrientationTest(v, f, rows, near)
        holed = gt.copy()
        holed[rng.choice(v.shape[0], size=20, replace=False)] = -1
        for vmap in (gt, rng.integers(0, v.shape[0], v.shape[0]), holed):
            assert np.array_equal(test(vmap), orientation_reversal(v, f, vmap, rows=rows, neighbourhood=near))

    def test_anticommutation_penalty_separates_mirror_from_identity(self, spectral_blob):
        from torchsym.mesh.orientation import (
            anticommutation_penalty,
            reduce_descriptors,
        )

        v, f, _, evecs, area, hks, _, true_c = spectral_blob
        ops = orientation_operators(v, f, evecs, reduce_descriptors(hks, area))
        pen = anticommutation_penalty(ops)
        value = lambda c: float(c.ravel() @ pen @ c.ravel())
        assert value(true_c) < 0.01
        assert value(np.eye(true_c.shape[0])) > 1.0  # the identity keeps the orientation: twice the random mean
        from scipy.stats import ortho_group

        randoms = [value(ortho_group.rvs(true_c.shape[0], random_state=i)) for i in range(200)]
        assert np.mean(randoms) == pytest.approx(1.0, rel=0.1)  # normalised by the Haar mean

    def test_missing_images_and_bad_input(self, blob):
        from torchsym.errors import InputShapeError, InputValueError
        from torchsym.mesh.operators import ring_neighbourhood
        from torchsym.mesh.orientation import orientation_reversal

        mesh, gt = blob
        v, f = mesh.vertices.numpy(), mesh.faces.numpy()
        partial = gt.copy()
        partial[0] = -1  # no image
        out = orientation_reversal(v, f, partial)
        assert out.dtype == np.int64
        near = ring_neighbourhood(f, v.shape[0], rings=2)[0].indices
        assert out[0] == 0 and np.all(out[near] == 0)
        far = np.setdiff1d(np.arange(v.shape[0]), np.append(near, 0))
        assert np.array_equal(out[far], orientation_reversal(v, f, gt)[far])
        with pytest.raises(InputShapeError, match="vertex_map: expected"):
            orientation_reversal(v, f, gt[:-1])
        with pytest.raises(InputValueError, match="vertex_map: expected indices"):
            orientation_reversal(v, f, np.full(v.shape[0], v.shape[0]))
        with pytest.raises(InputValueError, match="rows: expected"):
            orientation_reversal(v, f, gt, rows=np.array([-1]))
        with pytest.raises(InputValueError, match="rings: expected an integer >= 1"):
            orientation_reversal(v, f, gt, rings=0)
        with pytest.raises(InputShapeError, match="vertices: expected"):
            orientation_reversal(v[:, :2], f, gt)
