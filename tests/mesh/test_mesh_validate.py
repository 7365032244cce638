from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.mesh import Mesh, validate_mesh

TETRA_V = [[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
TETRA_F = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


def tetra(offset=(0.0, 0.0, 0.0)):
    return np.asarray(TETRA_V) + np.asarray(offset), np.asarray(TETRA_F)


class TestValidateMesh:
    def test_smoke(self):
        out = validate_mesh(Mesh.create(*tetra()))
        assert out.mesh.num_vertices == 4 and out.num_components == 1 and out.dropped_vertices == 0
        assert out.vertex_index.tolist() == [0, 1, 2, 3]

    def test_point_cloud_as_mesh(self):
        mesh = Mesh.create(np.random.default_rng(0).random((10, 3)), np.zeros((0, 3), dtype=np.int64))
        with pytest.raises(InputValueError, match=r"mesh.faces: expected at least one triangle, got \(0, 3\).*point cloud"):
            validate_mesh(mesh)

    def test_out_of_range_faces(self):
        v, f = tetra()
        with pytest.raises(InputValueError, match=r"faces: expected indices in \[0, 3\], got values in \[0, 4\]"):
            Mesh.create(v, np.vstack([f, [[1, 2, 4]]]))
        with pytest.raises(InputValueError, match=r"faces: expected indices in \[0, 3\], got values in \[-1, 3\]"):
            Mesh.create(v, np.vstack([f, [[-1, 2, 3]]]))

    def test_empty_vertices(self):
        with pytest.raises(InputValueError, match=r"vertices: expected at least one vertex, got \(0, 3\)"):
            Mesh.create(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))

    def test_wrong_shapes(self):
        v, f = tetra()
        with pytest.raises(InputShapeError, match=r"vertices: expected \(V, 3\) float tensor, got \(4, 2\)"):
            Mesh.create(v[:, :2], f)
        with pytest.raises(InputShapeError, match=r"faces: expected integer vertex indices, got non-integer values"):
            Mesh.create(v, f + 0.5)

    def test_repeated_vertex(self):
        v, f = tetra()
        f = np.concatenate([f, [[1, 1, 2]]])
        with pytest.raises(InputValueError, match=r"mesh.faces: .*1 degenerate triangles with a repeated vertex \(first: face 4"):
            validate_mesh(Mesh.create(v, f))

    def test_zero_area(self):
        v = np.concatenate([np.asarray(TETRA_V), [[2.0, 0, 0]]])
        f = np.concatenate([np.asarray(TETRA_F), [[0, 1, 4]]])  # collinear points
        with pytest.raises(InputValueError, match=r"mesh.faces: expected triangles of positive area, got 1 degenerate zero-area"):
            validate_mesh(Mesh.create(v, f))

    def test_non_manifold_edge(self):
        v = np.concatenate([np.asarray(TETRA_V), [[1.0, 1, 1]]])
        f = np.concatenate([np.asarray(TETRA_F), [[1, 2, 4]]])  # edge (1, 2) in three triangles
        with pytest.raises(InputValueError, match=r"non-manifold edges \(first: vertices \[1, 2\] in 3 triangles\)"):
            validate_mesh(Mesh.create(v, f))

    def test_nan_coordinates(self):
        v, f = tetra()
        v[2, 1] = np.nan
        with pytest.raises(InputValueError, match=r"vertices: expected finite values"):
            Mesh.create(v, f)

    def test_components_refuse(self):
        (v1, f1), (v2, f2) = tetra(), tetra((5.0, 0, 0))
        mesh = Mesh.create(np.concatenate([v1, v2]), np.concatenate([f1, f2 + 4]))
        with pytest.raises(InputValueError, match=r"mesh: expected one connected component, got 2"):
            validate_mesh(mesh, components="refuse")

    def test_components_largest(self):
        from torchsym.mesh.synthetic import icosphere

        s = icosphere(1)
        v2, f2 = tetra((5.0, 0, 0))
        n = s.num_vertices
        mesh = Mesh.create(np.concatenate([s.vertices.numpy(), v2]), np.concatenate([s.faces.numpy(), f2 + n]))
        out = validate_mesh(mesh)
        assert out.num_components == 2 and out.dropped_vertices == 4
        assert out.vertex_index.tolist() == list(range(n))
        back = out.map_to_input(torch.arange(n))
        assert back[:n].tolist() == list(range(n)) and back[n:].tolist() == [-1] * 4

    def test_bad_option(self):
        with pytest.raises(InputValueError, match="components: expected 'largest' or 'refuse', got 'all'"):
            validate_mesh(Mesh.create(*tetra()), components="all")  # type: ignore[arg-type]

    def test_not_a_mesh(self):
        with pytest.raises(InputShapeError, match="mesh: expected a torchsym.mesh.Mesh, got Tensor"):
            validate_mesh(torch.zeros(4, 3))  # type: ignore[arg-type]

    def test_too_few_vertices(self):
        with pytest.raises(InputValueError, match="expected at least 14 vertices in the largest connected component, got 4"):
            validate_mesh(Mesh.create(*tetra()), min_vertices=14)

    def test_real_meshes(self, shared_data):
        from torchsym.io import read_mesh

        holes = validate_mesh(read_mesh(shared_data / "meshes" / "elephant-with-holes.off"))
        assert holes.mesh.num_faces > 0
        dino = validate_mesh(read_mesh(shared_data / "meshes" / "dino.off"))  # COFF with colours
        assert dino.mesh.num_vertices > 1000
