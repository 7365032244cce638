"""The intrinsic-symmetry method end to end and its Module (torchsym.mesh.intrinsic.solver)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.core.registry import SOLVERS
from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.mesh import (
    IntrinsicSymmetry,
    IntrinsicSymmetryResult,
    Mesh,
    intrinsic_symmetry,
    laplacian_eigen,
)
from torchsym.metrics.mesh import correspondence_rate


class TestIntrinsicSymmetry:
    def test_smoke(self, solved):
        result, mesh, _ = solved
        assert isinstance(result, IntrinsicSymmetryResult)
        assert result.map.shape == (mesh.num_vertices,) and result.map.dtype == torch.int64
        assert result.functional_map.shape == (13, 13) and result.rotation.shape == (13, 13)
        assert result.pairs.shape[1] == 2 and result.pairs.shape[0] >= 1
        assert {"eigen", "features", "pairs", "signs", "correction", "map", "total"} <= set(result.timings)
        assert result.dropped_vertices == 0 and result.notes == ()

    def test_exact_recovery(self, solved):
        result, mesh, gt = solved
        assert (result.map.numpy() == gt).mean() > 0.99
        assert correspondence_rate(mesh, result.map, ground_truth=gt).rate == 1.0
        r = result.rotation
        torch.testing.assert_close(r.T @ r, torch.eye(13, dtype=r.dtype), atol=1e-8, rtol=0)

    def test_map_from_refined_functional_map(self, solved):
        # the returned map is the nearest row of Phi to each row of Phi C_r (ZoomOut's last round)
        from scipy.spatial import cKDTree

        from torchsym.mesh import laplacian_eigen

        result, mesh, gt = solved
        c = result.refined_functional_map.numpy()
        assert c.shape == (40, 40)  # polished (step 13) in polish_k eigenfunctions
        v = mesh.vertices.double().numpy()
        _, phi = laplacian_eigen(v, mesh.faces.numpy(), 40)
        nearest, again = cKDTree(phi).query(phi @ c, k=1)
        assert (again == result.map.numpy()).mean() > 0.99
        # an approximate search: each image at most 1.5 times as far as the nearest row
        assert np.all(np.linalg.norm(phi @ c - phi[result.map.numpy()], axis=1) <= 1.5 * nearest + 1e-12)
        assert (result.map_before_refine.numpy() == gt).mean() > 0.95

    def test_no_refine(self, blob):
        mesh, _ = blob
        out = intrinsic_symmetry(mesh, refine={"enabled": False})
        assert torch.equal(out.map, out.map_before_refine) and out.refined_functional_map.shape == (0, 0)

    def test_rigid_motion(self, solved, rigid_motion):
        result, mesh, _ = solved
        rot, shift = rigid_motion
        moved = Mesh(mesh.vertices @ torch.from_numpy(rot).T + torch.from_numpy(shift), mesh.faces)
        again = intrinsic_symmetry(moved)
        assert (again.map == result.map).float().mean() > 0.99

    def test_vertex_permutation(self, solved):
        result, mesh, gt = solved
        perm = torch.from_numpy(np.random.default_rng(0).permutation(mesh.num_vertices))
        inv = torch.argsort(perm)
        permuted = Mesh(mesh.vertices[perm], inv[mesh.faces])
        out = intrinsic_symmetry(permuted)
        back = perm[out.map][inv]  # map in the original numbering
        assert (back.numpy() == gt).mean() > 0.99

    def test_seeded_determinism(self, blob):
        mesh, _ = blob
        a = intrinsic_symmetry(mesh, generator=torch.Generator().manual_seed(5))
        b = intrinsic_symmetry(mesh, generator=torch.Generator().manual_seed(5))
        assert torch.equal(a.map, b.map) and torch.equal(a.rotation, b.rotation)
        assert torch.equal(a.functional_map, b.functional_map) and torch.equal(a.pairs, b.pairs)

    def test_branches_on_threads_give_the_serial_result(self, blob, monkeypatch):
        # steps 2, 8, 9, 12 and 14 run independent branches on threads (run_branches): the
        # result must be bit for bit the one of the branches run one after another
        from torchsym.core import parallel
        from torchsym.core.parallel import run_branches
        from torchsym.mesh.intrinsic import realign

        mesh, _ = blob
        forced = {"realign": {"below": 2.0, "gain": -2.0}}  # step 14 runs and its map is kept
        sizes = []
        # (the searches' own two-way brute force, nearest.Nearest.brute, keeps the original)
        monkeypatch.setattr(parallel, "run_branches", lambda tasks: sizes.append(len(tasks)) or run_branches(tasks, 2))
        threaded = intrinsic_symmetry(mesh, generator=torch.Generator().manual_seed(3), **forced)
        assert sizes[:2] == [2, 2]  # the eigensolver beside the non-spectral work, the pairings beside step 8
        assert len(sizes) >= 4 and max(sizes[2:]) >= 2  # and at least steps 9 and 14
        monkeypatch.setattr(parallel, "run_branches", lambda tasks: run_branches(tasks, 1))
        serial = intrinsic_symmetry(mesh, generator=torch.Generator().manual_seed(3), **forced)
        assert any(n.startswith("realigned by ") for n in threaded.notes)
        assert torch.equal(threaded.map, serial.map) and torch.equal(threaded.map_before_refine, serial.map_before_refine)
        assert torch.equal(threaded.refined_functional_map, serial.refined_functional_map)
        assert threaded.notes == serial.notes

    def test_blas_on_one_thread_inside_and_restored_after(self, blob, monkeypatch):
        # the solver holds BLAS to one thread (its searches use every core) and gives the
        # caller's setting back
        from threadpoolctl import threadpool_info, threadpool_limits

        from torchsym.mesh import fmaps

        def blas_threads() -> dict:
            return {d["filepath"]: d["num_threads"] for d in threadpool_info() if d["user_api"] == "blas"}

        seen: list[dict] = []
        original = fmaps.zoomout

        def spy(*args, **kwargs):
            seen.append(blas_threads())
            return original(*args, **kwargs)

        monkeypatch.setattr(fmaps, "zoomout", spy)
        mesh, _ = blob
        with threadpool_limits(limits=2, user_api="blas"):
            before = blas_threads()
            intrinsic_symmetry(mesh)
            after = blas_threads()
        assert before and set(before.values()) == {2}
        assert seen and all(set(s.values()) == {1} for s in seen)
        assert after == before

    def test_correction_off(self, blob):
        mesh, gt = blob
        out = intrinsic_symmetry(mesh, correction={"enabled": False})
        assert torch.equal(out.rotation, torch.eye(13, dtype=out.rotation.dtype))
        assert (out.map.numpy() == gt).mean() > 0.95

    def test_refine(self, blob):
        mesh, gt = blob
        out = intrinsic_symmetry(mesh, refine={"max_iters": 3})
        assert "refine" in out.timings
        assert (out.map.numpy() == gt).mean() > 0.99
        with pytest.raises(ConfigError, match="refine.max_iters: expected an int >= 1, got -1"):
            intrinsic_symmetry(mesh, refine={"max_iters": -1})
        with pytest.raises(ConfigError, match="refine.n_eigen: expected an int >= 1, got 0"):
            intrinsic_symmetry(mesh, refine={"n_eigen": 0})
        assert IntrinsicSymmetry(n_eigen=30, refine={"enabled": False}).settings.refine.n_eigen == 25  # raised to n_eigen when used
        # the thesis's method: no extension
        thesis = intrinsic_symmetry(mesh, refine={"enabled": False}, signs={"n_uncertain": 0}, hypotheses={"hks_pairs": False})
        assert "refine" not in thesis.timings and (thesis.map.numpy() == gt).mean() > 0.99

    def test_refined_map_is_an_involution(self, solved):
        result, mesh, _ = solved
        c = result.refined_functional_map.numpy().astype(np.float64)
        eye = np.eye(c.shape[0])
        assert np.allclose(c, c.T, atol=1e-6) and np.allclose(c @ c, eye, atol=1e-6)
        # on a mesh that is only nearly symmetric, plain ZoomOut's map is no involution
        bumpy = Mesh(mesh.vertices * (1 + 0.05 * torch.sin(3 * mesh.vertices[:, :1] + 2 * mesh.vertices[:, 1:2])), mesh.faces)
        # (the intrinsic maps: on this mesh their defects are large, and the extrinsic plane
        # would replace them; see TestExtrinsicHypothesis)
        plain = intrinsic_symmetry(bumpy, refine={"involution": False}, extrinsic={"enabled": False})
        plain = plain.refined_functional_map.numpy().astype(np.float64)
        assert np.linalg.norm(plain @ plain - eye) > 0.1
        fixed = intrinsic_symmetry(bumpy, extrinsic={"enabled": False}).refined_functional_map.numpy().astype(np.float64)
        assert np.allclose(fixed @ fixed, eye, atol=1e-6)
        with pytest.raises(ConfigError, match="refine.involution"):
            intrinsic_symmetry(mesh, refine={"involution": 1})

    def test_dropped_component(self, blob):
        mesh, gt = blob
        n = mesh.num_vertices
        extra_v = torch.tensor([[9.0, 9, 9], [10, 9, 9], [9, 10, 9]], dtype=mesh.vertices.dtype)
        two = Mesh(torch.cat([mesh.vertices, extra_v]), torch.cat([mesh.faces, torch.tensor([[n, n + 1, n + 2]])]))
        out = intrinsic_symmetry(two)
        assert out.map.shape == (n + 3,) and out.map[n:].tolist() == [-1, -1, -1]
        assert (out.map[:n].numpy() == gt).mean() > 0.99
        assert out.dropped_vertices == 3 and "largest of 2 connected components" in out.notes[0]
        with pytest.raises(InputValueError, match="expected one connected component, got 2"):
            intrinsic_symmetry(two, components="refuse")

    def test_exception(self, blob):
        mesh, _ = blob
        cloud = Mesh(mesh.vertices, torch.zeros((0, 3), dtype=torch.int64))
        with pytest.raises(InputValueError, match=r"mesh.faces: expected at least one triangle.*point cloud"):
            intrinsic_symmetry(cloud)
        with pytest.raises(InputShapeError, match="mesh: expected a torchsym.mesh.Mesh, got Tensor"):
            intrinsic_symmetry(mesh.vertices)  # type: ignore[arg-type]
        tiny = Mesh.create([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
        with pytest.raises(InputValueError, match="expected at least 14 vertices in the largest connected component, got 4"):
            intrinsic_symmetry(tiny)
        with pytest.raises(ConfigError, match="n_eigen: expected an int >= 3, got 2"):
            intrinsic_symmetry(mesh, n_eigen=2)
        with pytest.raises(ConfigError, match="correction.mu: expected a finite number >= 0.0"):
            intrinsic_symmetry(mesh, correction={"mu": -1.0})


class TestIntrinsicSymmetryModule:
    def test_registered(self):
        entry = SOLVERS.get("intrinsic_symmetry")
        assert entry.cls is IntrinsicSymmetry and entry.kind == "mesh"
        assert SOLVERS.default_for("mesh").name == "intrinsic_symmetry"
        assert entry.defaults()["n_eigen"] == 13 and entry.defaults()["features"]["n_times"] == 50

    def test_forward_matches_function(self, solved):
        result, mesh, _ = solved
        module = IntrinsicSymmetry(seed=0)
        out = module(mesh)
        assert torch.equal(out.map, result.map)
        assert repr(module) == "IntrinsicSymmetry()"  # only changed settings are listed
        assert "n_eigen=14" in repr(IntrinsicSymmetry(n_eigen=14))

    def test_exception(self):
        with pytest.raises(ConfigError, match="correction.enabled: expected true or false, got 1"):
            IntrinsicSymmetry(correction={"enabled": 1})
        with pytest.raises(ConfigError, match="components: expected one of 'largest', 'refuse', got 'all'"):
            IntrinsicSymmetry(components="all")
        with pytest.raises(ConfigError, match="hypotheses.orientation: expected true or false, got 'yes'"):
            IntrinsicSymmetry(hypotheses={"orientation": "yes"})
        with pytest.raises(ConfigError, match="select.n_samples: expected an int >= 50, got 10"):
            IntrinsicSymmetry(select={"n_samples": 10})
        with pytest.raises(ConfigError, match="select.max_distortion: expected a finite number > 0.0"):
            IntrinsicSymmetry(select={"max_distortion": 0.0})
        with pytest.raises(ConfigError, match="refine_k: unknown setting of IntrinsicSymmetrySettings"):
            IntrinsicSymmetry(refine_k=25)

    def test_config(self):
        from pathlib import Path

        from torchsym.core.config import build_pipeline, load_config

        cfg = load_config(Path(__file__).resolve().parents[3] / "configs" / "mesh_intrinsic.yaml")
        pipe = build_pipeline(cfg)
        assert isinstance(pipe.steps[0], IntrinsicSymmetry)

    def test_to_json(self, solved):
        assert '"map"' in solved[0].to_json()


def test_real_mesh(shared_data):
    from torchsym.io import read_mesh
    from torchsym.mesh.synthetic import mirror_complete

    mesh, gt = mirror_complete(read_mesh(shared_data / "meshes" / "elk.off", dtype=torch.float64))
    out = intrinsic_symmetry(mesh)
    assert correspondence_rate(mesh, out.map, ground_truth=gt).rate > 0.95


def test_no_pairs_gives_identity(shared_data):
    from torchsym.io import read_mesh

    mesh = read_mesh(shared_data / "meshes" / "boeing.off")  # 122 components, largest without pairs
    out = intrinsic_symmetry(mesh, hypotheses={"orientation": False, "sign_basis": 0})
    kept = torch.nonzero(out.map >= 0).ravel()
    assert out.dropped_vertices > 0 and (out.map < 0).sum() == out.dropped_vertices
    assert out.pairs.shape[0] == 0
    assert torch.equal(out.map[kept], kept)
    assert any("no symmetry found" in n for n in out.notes)


def test_orientation_hypothesis_finds_what_pairs_miss(shared_data):
    """The largest part of boeing.off is a flat panel, mirror symmetric, on which no
    feature points pair up; the orientation-reversing functional map finds its mirror, and so
    do the sign hypotheses."""
    from torchsym.io import read_mesh

    mesh = read_mesh(shared_data / "meshes" / "boeing.off")
    for sign_basis, expected in ((0, ("orientation",)), (4, ("orientation", "signs"))):
        out = intrinsic_symmetry(mesh, hypotheses={"sign_basis": sign_basis})
        assert out.hypothesis in expected
        _assert_mirror(mesh, out)


def _assert_mirror(mesh, out):
    kept = torch.nonzero(out.map >= 0).ravel()
    x = mesh.vertices[kept].double().numpy()
    y = mesh.vertices[out.map[kept]].double().numpy()
    assert np.mean(np.all(x == y, axis=1)) < 0.1  # not the identity
    # the map is close to one mirror reflection: fit the plane from the displacements
    normal = np.linalg.svd(y - x - (y - x).mean(0))[2][0]
    centre = (0.5 * (x + y)).mean(0)
    mirrored = x - 2.0 * ((x - centre) @ normal)[:, None] * normal
    diag = np.linalg.norm(x.max(0) - x.min(0))
    assert np.median(np.linalg.norm(mirrored - y, axis=1)) < 0.03 * diag
