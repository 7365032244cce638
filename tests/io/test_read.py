import hashlib

import numpy as np
import pytest
import torch

import torchsym
from torchsym.errors import InputFileError
from torchsym.errors import InputShapeError, InputValueError
from torchsym.io import infer_kind, load_input, read_image, read_mesh, read_pointcloud, write_image, write_mesh, write_ply
from torchsym.mesh import Mesh


def _gen(seed: int = 0) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


def _digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


class TestRead:
    def test_ply_round_trip(self, tmp_path):
        pts = torch.rand(50, 3, generator=_gen())
        write_ply(tmp_path / "a.ply", pts, colors=torch.rand(50, 3, generator=_gen()))
        assert torch.allclose(read_pointcloud(tmp_path / "a.ply"), pts, atol=1e-6)
        kind, data = load_input(tmp_path / "a.ply")
        assert kind == "pointcloud"

    def test_mesh_ply(self, tmp_path):
        write_ply(tmp_path / "m.ply", torch.rand(4, 3, generator=_gen()), faces=torch.tensor([[0, 1, 2], [0, 2, 3]]))
        kind, mesh = load_input(tmp_path / "m.ply")
        assert kind == "mesh" and mesh.faces.shape == (2, 3)
        kind, pts = load_input(tmp_path / "m.ply", kind="pointcloud")
        assert kind == "pointcloud" and pts.shape == (4, 3)

    def test_xyz_and_npy(self, tmp_path):
        pts = np.random.default_rng(0).random((20, 6))
        np.savetxt(tmp_path / "a.xyz", pts)
        assert read_pointcloud(tmp_path / "a.xyz").shape == (20, 3)
        np.save(tmp_path / "b.npy", pts[:, :4])
        kind, data = load_input(tmp_path / "b.npy")
        assert kind == "points" and data.shape == (20, 4)

    @pytest.mark.parametrize("text", [
        "//X,Y,Z,R,G,B\n{rows}",  # CloudCompare's ASCII export
        "x y z\n{rows}",
        "# scan 3\n{rows}",
    ])
    @pytest.mark.parametrize("sep", [" ", ",", ";", "\t"])
    def test_text_points(self, tmp_path, text, sep):
        pts = np.random.default_rng(1).random((7, 6))
        rows = "\n".join(sep.join(f"{v:.17g}" for v in row) for row in pts) + "\n"
        (tmp_path / "a.txt").write_text(text.format(rows=rows))
        got = read_pointcloud(tmp_path / "a.txt", dtype=torch.float64)
        assert torch.equal(got, torch.from_numpy(pts[:, :3]))

    @pytest.mark.parametrize("content, expected", [
        (b"1 2 3 # first point\n4 5 6\n", [[1, 2, 3], [4, 5, 6]]),  # a comment, not a header
        (b"\xef\xbb\xbf1 2 3\n4 5 6\n", [[1, 2, 3], [4, 5, 6]]),  # UTF-8 byte-order mark
        (b"X;Y;Z\n1,5;2,25;3,75\n4;5;6\n", [[1.5, 2.25, 3.75], [4, 5, 6]]),  # decimal commas
        (b"1,2,3,\n4,5,6,\n", [[1, 2, 3], [4, 5, 6]]),  # a separator ending every row
        (b"# 5000 comment lines\n" * 5000 + b"1 2 3\n", [[1, 2, 3]]),
        (b"2\n1 2 3 -120 10 20 30\n4 5 6 -80 10 20 30\n", [[1, 2, 3], [4, 5, 6]]),  # Leica .pts: the count first
    ])
    def test_text_points_conventions(self, tmp_path, content, expected):
        (tmp_path / "a.xyz").write_bytes(content)
        got = read_pointcloud(tmp_path / "a.xyz", dtype=torch.float64)
        assert got.tolist() == expected

    @pytest.mark.parametrize("content, message", [
        (b"x y z\n1 2 3\nfour 5 6\n", "cannot read .* as rows of numbers"),  # only the first row may be a header
        (b"1,,3,0.1\n4,5,6,7\n", "cannot read .* as rows of numbers"),  # an empty field shifts no column
        (b"1 2 3 a\n4 5 6 7\n", "cannot read .* as rows of numbers"),  # a number in it: not a header
        (b"x y z\n", "holds no points"),
        (b"\xff\xfe\x00binary", "cannot read .* as text"),
    ])
    def test_text_points_bad(self, tmp_path, content, message):
        (tmp_path / "a.xyz").write_bytes(content)
        with pytest.raises(InputFileError, match=message):
            read_pointcloud(tmp_path / "a.xyz")

    def test_files_not_modified(self, tmp_path):
        p = tmp_path / "c.ply"
        write_ply(p, torchsym.data.sample_pointcloud())
        before = _digest(p)
        torchsym.detect(p)
        assert _digest(p) == before

    def test_image(self, tmp_path):
        img = torch.rand(3, 10, 12, generator=_gen())
        write_image(tmp_path / "i.png", img)
        back = read_image(tmp_path / "i.png")
        assert back.shape == (3, 10, 12) and torch.allclose(back, img, atol=1 / 255 + 1e-6)

    def test_infer_kind(self):
        assert infer_kind(torch.zeros(5, 3)) == "pointcloud"
        assert infer_kind(torch.zeros(5, 4)) == "points"
        assert infer_kind(torch.zeros(3, 8, 8)) == "image"

    @pytest.mark.parametrize("name, content, message", [
        ("nope.ply", None, "does not exist"),
        ("junk.ply", b"this is not a ply file", "cannot read"),
        ("junk.npy", b"garbage", "cannot read"),
        ("junk.xyz", b"a b c\n", "holds no points"),  # a header row and nothing else
        ("junk.txt", b"1 2 3\na b c\n", "cannot read"),
        ("two.xyz", b"1 2\n3 4\n", "expected at least 3 columns"),
        ("junk.png", b"not an image", "cannot decode"),
        ("thing.abc", b"x", "cannot tell what"),
    ])
    def test_exception(self, tmp_path, name, content, message):
        p = tmp_path / name
        if content is not None:
            p.write_bytes(content)
        with pytest.raises(InputFileError, match=message):
            load_input(p)

    def test_mesh_without_faces(self, tmp_path):
        write_ply(tmp_path / "pc.ply", torch.rand(5, 3, generator=_gen()))
        with pytest.raises(InputFileError, match="holds no triangles"):
            read_mesh(tmp_path / "pc.ply")

    def test_real_mesh(self, shared_data):
        mesh = read_mesh(shared_data / "meshes" / "dino.off")
        assert mesh.vertices.shape == (3916, 3) and mesh.faces.shape == (7828, 3)

    def test_kind_mismatch(self, tmp_path):
        write_ply(tmp_path / "m.ply", torch.rand(4, 3, generator=_gen()), faces=torch.tensor([[0, 1, 2], [0, 2, 3]]))
        with pytest.raises(InputFileError, match="is a mesh, but kind 'image' was asked for"):
            load_input(tmp_path / "m.ply", kind="image")
        np.savetxt(tmp_path / "p.xyz", np.ones((5, 3)))
        with pytest.raises(InputFileError, match="holds a pointcloud, but kind 'mesh' was asked for"):
            load_input(tmp_path / "p.xyz", kind="mesh")


class TestWriteMesh:
    @pytest.mark.parametrize("suffix", [".ply", ".obj", ".off", ".stl"])
    def test_round_trip(self, tmp_path, suffix):
        v = torch.rand(4, 3, generator=_gen(), dtype=torch.float64)
        mesh = Mesh(v, torch.tensor([[0, 1, 2], [0, 2, 3]]))
        out = write_mesh(tmp_path / f"sub/m{suffix}", mesh, colors=torch.rand(4, 3, generator=_gen(1)))
        back = read_mesh(out, dtype=torch.float64)
        assert back.num_faces == 2 and back.num_vertices == 4
        if suffix != ".stl":  # STL stores triangles only: vertex order is not kept
            assert torch.allclose(back.vertices, v, atol=1e-5) and torch.equal(back.faces, mesh.faces)

    def test_colors_kept_in_ply(self, tmp_path):
        import pymeshlab

        mesh = Mesh(torch.rand(4, 3, generator=_gen()), torch.tensor([[0, 1, 2], [0, 2, 3]]))
        colors = torch.tensor([[255, 0, 0], [0, 255, 0], [0, 0, 255], [10, 20, 30]], dtype=torch.uint8)
        write_mesh(tmp_path / "c.ply", mesh, colors=colors)
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(tmp_path / "c.ply"))
        got = np.round(ms.current_mesh().vertex_color_matrix()[:, :3] * 255).astype(int)
        assert got.tolist() == colors.tolist()

    def test_exception(self, tmp_path):
        mesh = Mesh(torch.rand(4, 3, generator=_gen()), torch.tensor([[0, 1, 2], [0, 2, 3]]))
        with pytest.raises(InputFileError, match=r"path: expected one of .ply, .obj, .off, .stl to write a mesh"):
            write_mesh(tmp_path / "m.xyz", mesh)
        with pytest.raises(InputShapeError, match=r"mesh: expected a torchsym.mesh.Mesh, got Tensor"):
            write_mesh(tmp_path / "m.ply", mesh.vertices)
        with pytest.raises(InputShapeError, match=r"colors: expected \(4, 3\) per-vertex RGB, got \(3, 3\)"):
            write_mesh(tmp_path / "m.ply", mesh, colors=torch.rand(3, 3))


def _png_header(width: int, height: int) -> bytes:
    """A PNG's signature, IHDR and an empty IDAT: the size, no pixel data."""
    import struct
    import zlib

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    out = b"\x89PNG\r\n\x1a\n"
    for kind, data in ((b"IHDR", ihdr), (b"IDAT", b""), (b"IEND", b"")):
        out += struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return out


class TestLimitsAndBadValues:
    """Inputs that raised untyped errors, allocated gigabytes or were read wrong."""

    def test_empty_npy(self, tmp_path):
        (tmp_path / "e.npy").write_bytes(b"")
        with pytest.raises(InputFileError, match=r"e.npy' as a NumPy array"):
            load_input(tmp_path / "e.npy")

    def test_complex_npy_refused(self, tmp_path):
        np.save(tmp_path / "c.npy", np.ones((5, 3)) * (1 + 2j))
        with pytest.raises(InputFileError, match=r"c.npy' to hold a real \(N, D\) array, got complex128 \(5, 3\)"):
            read_pointcloud(tmp_path / "c.npy")

    def test_npy_big_endian_and_limits(self, tmp_path):
        np.save(tmp_path / "b.npy", np.arange(30, dtype=">f8").reshape(10, 3))
        assert read_pointcloud(tmp_path / "b.npy", dtype=torch.float64)[-1].tolist() == [27, 28, 29]
        with pytest.raises(InputFileError, match=r"holds 10 points, more than max_points=5"):
            read_pointcloud(tmp_path / "b.npy", max_points=5)

    def test_text_limit_before_parsing(self, tmp_path):
        np.savetxt(tmp_path / "a.xyz", np.random.default_rng(0).random((10, 3)))
        with pytest.raises(InputFileError, match=r"holds 10 lines, more than max_points=5"):
            read_pointcloud(tmp_path / "a.xyz", max_points=5)

    @pytest.mark.parametrize("row", ["1 nan 0", "1 inf 0", "1 1e39 0"])
    def test_non_finite_from_the_reader(self, tmp_path, row):
        (tmp_path / "a.xyz").write_text(f"0 0 0\n{row}\n0 1 0\n")
        with pytest.raises(InputValueError, match=r"a.xyz' holds 1 NaN or infinite coordinates \(first in row 1"):
            load_input(tmp_path / "a.xyz")

    def test_stray_coordinate(self, tmp_path):
        pts = np.random.default_rng(0).random((1000, 3))
        pts[17] = 1e20
        np.savetxt(tmp_path / "s.xyz", pts)
        with pytest.raises(InputValueError, match=r"s.xyz': point 17 lies 1e\+20 from .* a coordinate far outside the rest"):
            torchsym.detect(tmp_path / "s.xyz")

    def test_image_size_read_from_the_header(self, tmp_path):
        (tmp_path / "huge.png").write_bytes(_png_header(25_000, 25_000))
        with pytest.raises(InputFileError, match=r"huge.png' is larger than max_pixels=50000000"):
            read_image(tmp_path / "huge.png")
        (tmp_path / "big.png").write_bytes(_png_header(8000, 8000))
        with pytest.raises(InputFileError, match=r"big.png' is 8000 x 8000 = 64000000 pixels, more than max_pixels=50000000"):
            load_input(tmp_path / "big.png")

    def test_max_pixels(self, tmp_path):
        write_image(tmp_path / "i.png", torch.rand(3, 10, 12, generator=_gen()))
        assert read_image(tmp_path / "i.png", max_pixels=120).shape == (3, 10, 12)
        with pytest.raises(InputFileError, match=r"is 12 x 10 = 120 pixels, more than max_pixels=119"):
            read_image(tmp_path / "i.png", max_pixels=119)

    def test_symlink_loop(self, tmp_path):
        (tmp_path / "loop.xyz").symlink_to(tmp_path / "loop.xyz")
        with pytest.raises(InputFileError, match=r"loop.xyz' is a symbolic link to nothing"):
            load_input(tmp_path / "loop.xyz")
