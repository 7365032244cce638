"""Tests of the one input expansion (``torchsym.io.inputs``) and of how ``prepare`` fits an input to its pipeline."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

import torchsym
from torchsym.api import prepare
from torchsym.errors import ConfigError, InputFileError, InputValueError
from torchsym.io.inputs import MANIFEST, expand_inputs, unique_stems


def _xyz(path: Path) -> Path:
    np.savetxt(path, np.random.default_rng(0).normal(size=(30, 3)))
    return path


class TestExpandInputs:
    def test_smoke(self, tmp_path):
        _xyz(tmp_path / "a.xyz")
        _xyz(tmp_path / ".hidden.xyz")
        (tmp_path / "photo.png").write_bytes(b"")
        got = expand_inputs([str(tmp_path / "a.xyz"), str(tmp_path / "photo.png")])
        assert [Path(s.name).name for s in got] == ["a.xyz", "photo.png"]  # no kind: every known file named
        got = expand_inputs(str(tmp_path), "pointcloud")
        assert [Path(s.name).name for s in got] == ["a.xyz"] and "photo.png" in got[0].notes[0]

    def test_a_folder_gives_the_kind_most_of_its_files_are(self, tmp_path):
        for name in ("b.png", "a.jpg"):
            (tmp_path / name).write_bytes(b"")
        np.savetxt(tmp_path / "axes.txt", [[0, 0, 1, 1]])  # a photo folder's ground truth
        got = expand_inputs(str(tmp_path))
        assert [Path(s.name).name for s in got] == ["a.jpg", "b.png"]
        assert "axes.txt" in got[0].notes[0] and "most of its files are photos" in got[0].notes[0]
        for name in ("c.xyz", "d.xyz", "e.xyz"):
            _xyz(tmp_path / name)
        got = expand_inputs(str(tmp_path))  # now 4 files of points (axes.txt reads as one) to 2 photos
        assert [Path(s.name).suffix for s in got] == [".txt", ".xyz", ".xyz", ".xyz"]
        assert "b.png" in got[0].notes[0]

    def test_skips_earlier_outputs(self, tmp_path):
        _xyz(tmp_path / "a.xyz")
        _xyz(tmp_path / "a_plane.ply")
        (tmp_path / MANIFEST).write_text('{"outputs": ["a_plane.ply"]}')
        assert [Path(s.name).name for s in expand_inputs(str(tmp_path))] == ["a.xyz"]

    def test_each_file_once(self, tmp_path):
        a = _xyz(tmp_path / "a.xyz")
        assert len(expand_inputs([str(a), str(tmp_path), str(tmp_path / "*.xyz")])) == 1

    def test_unique_stems(self):
        stems = unique_stems([Path("a/chair.png"), Path("a/chair.xyz"), Path("b/chair.xyz"), Path("scenes/fountain")])
        assert stems == ["chair_png", "chair_xyz", "chair_xyz_2", "fountain"]

    def test_exception(self, tmp_path):
        with pytest.raises(InputFileError, match="inputs: expected a file, folder or glob pattern, got ''"):
            expand_inputs([""])
        with pytest.raises(InputFileError, match="does not exist"):
            expand_inputs([str(tmp_path / "missing.xyz")])
        with pytest.raises(InputFileError, match="matches no file"):
            expand_inputs([str(tmp_path / "*.ply")])
        with pytest.raises(InputValueError, match="inputs: no input torchsym reads found"):
            expand_inputs([str(tmp_path)])


class TestPrepare:
    def test_manifold_mesh_keeps_the_intrinsic_pipeline(self):
        from torchsym.mesh.synthetic import icosphere

        p = prepare(icosphere(2))
        assert p.kind == "mesh" and p.config.steps[0].name == "intrinsic_symmetry" and not p.notes

    def test_cad_mesh_routed_with_a_note(self):
        from cad_models import cad_chair

        p = prepare(cad_chair()[0])
        assert p.kind == "pointcloud" and p.config.steps[0].name == "reflection_plane"
        assert p.data.shape == (20000, 3) and "non-manifold" in p.notes[0] and "sampled 20000 points" in p.notes[1]
        forced = prepare(cad_chair()[0], kind="mesh")
        assert forced.kind == "mesh" and not forced.notes

    def test_several_parts_routed(self):
        from torchsym.mesh.synthetic import icosphere

        s = icosphere(1)
        two = torchsym.mesh.Mesh(torch.cat([s.vertices, s.vertices + 3]), torch.cat([s.faces, s.faces + len(s.vertices)]))
        p = prepare(two)
        assert p.kind == "pointcloud" and "2 connected parts" in p.notes[0]

    def test_inputs_unchanged(self):
        from cad_models import cad_chair

        mesh = cad_chair()[0]
        before = mesh.vertices.clone()
        prepare(mesh)
        assert torch.equal(mesh.vertices, before)

    def test_exception(self, tmp_path):
        with pytest.raises(InputValueError, match="kind: expected one of pointcloud, points, image, mesh, multiview or None"):
            prepare(torch.zeros(5, 3), kind="scene")
        with pytest.raises(ConfigError, match="takes 'image' input, but the input is a pointcloud"):
            prepare(torch.rand(50, 3), {"input": "image", "steps": ["ksymmetry"]})
        a, b = _xyz(tmp_path / "a.xyz"), _xyz(tmp_path / "b.xyz")
        with pytest.raises(InputValueError, match="input: expected one input, got 2"):
            prepare([str(a), str(b)], kind="pointcloud")
