import struct

import numpy as np
import pytest
import torch

from torchsym.errors import InputFileError, InputValueError
from torchsym.io import load_input, read_mesh, read_pointcloud, write_mesh
from torchsym.io.meshfiles import parse_mesh_file
from torchsym.geometry.mesh import Mesh

# an octahedron: 6 vertices, 8 triangles
_V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64)
_F = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
_PLY_HEAD = "ply\nformat {fmt} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"


def _pymeshlab_read(path):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    return ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()


class TestParseMeshFile:
    @pytest.mark.parametrize("suffix, options", [
        (".off", {}), (".obj", {}), (".ply", {"binary": True}), (".ply", {"binary": False}),
        (".stl", {"binary": True}), (".stl", {"binary": False}),
    ])
    def test_same_as_pymeshlab(self, tmp_path, suffix, options):
        import pymeshlab

        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(_V, _F))
        path = tmp_path / f"m{suffix}"
        ms.save_current_mesh(str(path), **options)
        v, f = parse_mesh_file(path, 1000)
        v_ref, f_ref = _pymeshlab_read(path)
        assert np.allclose(v, v_ref, atol=1e-6) and np.array_equal(f, f_ref)
        assert v.dtype == np.float64 and f.dtype == np.int64

    def test_polygons_become_fans(self, tmp_path):
        (tmp_path / "q.off").write_text("NCOFF\n# a square and a triangle\n5 2 0\n" + "0 0 0 0 0 1 255 0 0 255\n" * 5
                                        + "4 0 1 2 3 255 0 0\n3 0 3 4\n")
        _, f = parse_mesh_file(tmp_path / "q.off", 100)
        assert f.tolist() == [[0, 1, 2], [0, 2, 3], [0, 3, 4]]

    def test_obj_conventions(self, tmp_path):
        (tmp_path / "m.obj").write_text("mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0 0.5 0.5 0.5\nvt 0 0\nvn 0 0 1\n"
                                        "f 1/1/1 2/1/1 3/1/1\nf -3//1 -2//1 -1//1\ng part\nl 1 2\n")
        v, f = parse_mesh_file(tmp_path / "m.obj", 100)
        assert v.shape == (3, 3) and f.tolist() == [[0, 1, 2], [0, 1, 2]]

    def test_ply_ascii_extra_properties(self, tmp_path):
        text = (_PLY_HEAD.format(fmt="ascii", nv=4) + "property uchar red\nelement face 1\n"
                "property list uchar float texcoord\nproperty list uchar int vertex_indices\nend_header\n"
                "0 0 0 1\n1 0 0 2\n0 1 0 3\n0 0 1 4\n2 0.5 0.5 4 0 1 2 3\n")
        (tmp_path / "a.ply").write_text(text)
        v, f = parse_mesh_file(tmp_path / "a.ply", 100)
        assert v.shape == (4, 3) and f.tolist() == [[0, 1, 2], [0, 2, 3]]

    @pytest.mark.parametrize("order", ["<", ">"])
    def test_ply_binary_mixed_polygons(self, tmp_path, order):
        fmt = "binary_little_endian" if order == "<" else "binary_big_endian"
        head = _PLY_HEAD.format(fmt=fmt, nv=4) + "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        body = np.arange(12, dtype=order + "f4").tobytes()
        body += bytes([3]) + np.array([0, 1, 2], order + "i4").tobytes() + bytes([4]) + np.array([0, 1, 2, 3], order + "i4").tobytes()
        (tmp_path / "b.ply").write_bytes(head.encode() + body)
        v, f = parse_mesh_file(tmp_path / "b.ply", 100)
        assert v[3].tolist() == [9, 10, 11] and f.tolist() == [[0, 1, 2], [0, 1, 2], [0, 2, 3]]


_BINARY_PLY = (_PLY_HEAD.format(fmt="binary_little_endian", nv=3)
               + "element face 1\nproperty list uchar int vertex_indices\nend_header\n").encode()


class TestBadFiles:
    """Each of these crashed the process in pymeshlab or raised an untyped error."""

    @pytest.mark.parametrize("name, content, message", [
        ("a.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1000000000000\n", r"face 0: vertex index \d+ outside \[0, 3\)"),
        ("b.off", b"OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 99\n", r"face 0: vertex indices \[0, 1, 99\] outside"),
        ("c.ply", (_PLY_HEAD.format(fmt="ascii", nv=10**12) + "end_header\n0 0 0\n").encode(), r"element vertex: expected a count in \[0, 1000\]"),
        ("d.off", b"OFF\n1000000000000 0 0\n0 0 0\n", r"vertex count: expected a count in \[0, 1000\], got 1000000000000"),
        ("e.ply", _BINARY_PLY + np.zeros(9, "<f4").tobytes() + bytes([3]) + np.array([0, 1, 7], "<i4").tobytes(), "vertex index 7 outside"),
        ("f.ply", _BINARY_PLY + np.zeros(5, "<f4").tobytes(), "3 rows need 36 bytes"),
        ("g.ply", _BINARY_PLY + np.zeros(9, "<f4").tobytes() + bytes([200]), "a list of 200 entries runs past the end"),
        ("h.stl", b"\0" * 80 + struct.pack("<I", 10**9) + b"\0" * 50, "neither binary STL"),
        ("i.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n", "declares 3 vertices and 1 faces, but the file holds 2 lines"),
        ("j.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 x\n", "expected integer vertex indices"),
        ("k.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "face 0: expected at least 3 corners"),
        ("l.obj", b"v 0 0 0\nf 1 2\n", "a face needs at least 3 corners"),
        ("m.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float q\nend_header\n1\n", "expected vertex properties x, y and z"),
        ("n.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "expected a PLY header"),
        ("o.off", b"OFF BINARY\n", "binary OFF is not supported"),
        ("p.off", b"", "expected the keyword OFF"),
    ])
    def test_typed_error_naming_the_file(self, tmp_path, name, content, message):
        path = tmp_path / name
        path.write_bytes(content)
        with pytest.raises(InputFileError, match=message) as info:
            read_pointcloud(path, max_points=1000)
        assert str(path) in str(info.value)
        with pytest.raises(InputFileError):
            load_input(path)

    def test_nan_vertex(self, tmp_path):
        (tmp_path / "n.off").write_text("OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n")
        with pytest.raises(InputValueError, match=r"n.off' holds 1 NaN or infinite coordinates \(first in row 1, column 0\)"):
            read_mesh(tmp_path / "n.off")

    def test_max_points(self, tmp_path):
        write_mesh(tmp_path / "m.ply", Mesh(torch.from_numpy(_V), torch.from_numpy(_F)))
        assert read_mesh(tmp_path / "m.ply", max_points=6).num_vertices == 6
        with pytest.raises(InputFileError, match=r"expected a count in \[0, 5\], got 6"):
            read_mesh(tmp_path / "m.ply", max_points=5)
