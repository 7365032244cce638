"""Property-based fuzzing of the entry points: readers, ``torchsym.detect`` and the CLI.

Any input either raises a :class:`TorchsymError` whose message names the argument (for
files: the path), or gives a result whose numbers are finite and whose ``score`` is in
[0, 1]; input files are byte-identical afterwards; the CLI exits with code 2 and one
line of error. Mesh reading runs in this process, so a crash in a reader fails the run.
Seeded (``derandomize=True``) and bounded in examples to keep the file quick.
"""

import dataclasses
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import torchsym
from torchsym.errors import TorchsymError
from torchsym.io import IMAGE_SUFFIXES, MESH_SUFFIXES, POINT_SUFFIXES, load_input, read_image, read_mesh, read_pointcloud
from torchsym.geometry.mesh import Mesh


def _fuzz(n: int) -> settings:
    return settings(max_examples=n, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


# ------------------------------------------------------------------ strategies

_SPECIAL = [math.nan, math.inf, -math.inf, 1e300, -1e200, 1e20, 3.5e38, 0.0, -0.0, 5e-324]
_BAD_COUNTS = [-1, 2**31, 2**32 + 3, 10**12, 2**63 - 1]
_BAD_INDICES = [-1, -13, 2**31 - 1, 10**12, 10**30]
finite = st.floats(-10, 10, allow_nan=False, width=32)


def _num(x: float) -> str:
    return repr(float(x)) if not float(x).is_integer() or abs(x) > 1e15 else str(int(x))


def _rarely(draw) -> bool:
    """True in about one draw of five: where a near-valid file gets one thing wrong."""
    return draw(st.integers(0, 4)) == 0


@st.composite
def mutated(draw, data: bytes) -> bytes:
    """``data`` as is (mostly), truncated, or with one byte replaced."""
    how = draw(st.sampled_from(["keep"] * 6 + ["cut", "flip"]))
    if how == "cut" and data:
        return data[: draw(st.integers(0, len(data) - 1))]
    if how == "flip" and data:
        i = draw(st.integers(0, len(data) - 1))
        return data[:i] + bytes([draw(st.integers(0, 255))]) + data[i + 1:]
    return data


@st.composite
def point_rows(draw, n_min: int = 0, width: int = 3) -> list[list[float]]:
    """Rows of ``width`` finite numbers, rarely with a NaN, infinite or huge one."""
    n = draw(st.integers(n_min, 12))
    rows = draw(st.lists(st.lists(finite, min_size=width, max_size=width), min_size=n, max_size=n))
    if rows and _rarely(draw):
        rows[draw(st.integers(0, n - 1))][draw(st.integers(0, width - 1))] = draw(st.sampled_from(_SPECIAL))
    return rows


@st.composite
def mesh_parts(draw):
    """Vertices and polygons indexing them, rarely with a bad index or a short polygon."""
    verts = draw(point_rows(n_min=3))
    nv = len(verts)
    sizes = st.sampled_from([3, 3, 3, 3, 4, 5])
    faces = draw(st.lists(sizes.flatmap(lambda k: st.lists(st.integers(0, nv - 1), min_size=k, max_size=k)), max_size=8))
    if faces and _rarely(draw):
        f = faces[draw(st.integers(0, len(faces) - 1))]
        f[draw(st.integers(0, len(f) - 1))] = draw(st.sampled_from(_BAD_INDICES))
    if faces and _rarely(draw):
        faces[0] = faces[0][:2]
    return verts, faces


def _counts(draw, n: int) -> int:
    return draw(st.sampled_from(_BAD_COUNTS + [n + 1, max(n - 1, 0)])) if _rarely(draw) else n


@st.composite
def off_files(draw):
    verts, faces = draw(mesh_parts())
    nv, nf = _counts(draw, len(verts)), _counts(draw, len(faces))
    keyword = draw(st.sampled_from(["OFF BINARY", "off", "4OFF"])) if _rarely(draw) else "OFF"
    lines = [keyword, f"{nv} {nf} 0"]
    lines += [" ".join(_num(c) for c in v) for v in verts]
    lines += [" ".join(str(i) for i in [len(f), *f]) for f in faces]
    return draw(mutated("\n".join(lines).encode()))


@st.composite
def obj_files(draw):
    verts, faces = draw(mesh_parts())
    lines = ["# fuzz"] + ["v " + " ".join(_num(c) for c in v) for v in verts]
    style = draw(st.sampled_from(["{}", "{}/1", "{}//1", "{}/1/1", "-{}"]))
    lines += ["f " + " ".join(style.format(i + 1) for i in f) for f in faces]
    return draw(mutated("\n".join(lines).encode()))


@st.composite
def ply_files(draw):
    verts, faces = draw(mesh_parts())
    fmt = draw(st.sampled_from(["ascii", "binary_little_endian", "binary_big_endian"]))
    nv, nf = _counts(draw, len(verts)), _counts(draw, len(faces))
    head = (f"ply\nformat {fmt} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
            f"element face {nf}\nproperty list uchar int vertex_indices\nend_header\n").encode()
    if fmt == "ascii":
        body = "".join(" ".join(_num(c) for c in v) + "\n" for v in verts)
        body += "".join(" ".join(str(i) for i in [len(f), *f]) + "\n" for f in faces)
        return draw(mutated(head + body.encode()))
    order = "<" if fmt == "binary_little_endian" else ">"
    with np.errstate(all="ignore"):
        body = np.array(verts, dtype=np.float64).astype(order + "f4").tobytes()
    for f in faces:
        body += bytes([len(f)]) + np.array([i % 2**31 for i in f], dtype=order + "i4").tobytes()
    return draw(mutated(head + body))


@st.composite
def xyz_files(draw):
    rows = draw(point_rows(width=draw(st.sampled_from([3, 3, 3, 2, 6]))))
    sep = draw(st.sampled_from([" ", ",", ";", "\t"]))
    header = draw(st.sampled_from(["", "x y z\n", "# c\n", "5\n"]))
    return draw(mutated((header + "\n".join(sep.join(_num(c) for c in r) for r in rows)).encode()))


@st.composite
def npy_files(draw):
    import io

    rows = draw(point_rows(width=draw(st.sampled_from([3, 3, 3, 2, 4]))))
    dtype = draw(st.sampled_from(["<f4", ">f8", "<i8"] if not _rarely(draw) else ["|u1", "|b1", "<c16", "<f2", "O"]))
    arr = np.array(rows, dtype=np.float64).reshape(len(rows), -1) if rows else np.zeros((0, 3))
    if _rarely(draw):
        arr = arr.reshape(-1) if draw(st.booleans()) else arr[None]
    with np.errstate(all="ignore"):
        arr = arr.astype(dtype)
    buf = io.BytesIO()
    np.save(buf, arr, allow_pickle=True)
    return draw(mutated(buf.getvalue()))


_NEAR_VALID = {".off": off_files(), ".obj": obj_files(), ".ply": ply_files(), ".xyz": xyz_files(), ".npy": npy_files()}


# ------------------------------------------------------------------ properties


def _check_value(value, where: str) -> None:
    if isinstance(value, torch.Tensor) and value.is_floating_point():
        assert bool(torch.isfinite(value).all()), f"{where}: non-finite entries"
    elif isinstance(value, float):
        assert math.isfinite(value), f"{where}: {value}"
    elif isinstance(value, Mesh):
        _check_value(value.vertices, f"{where}.vertices")
        faces = value.faces
        assert faces.numel() == 0 or (int(faces.min()) >= 0 and int(faces.max()) < value.vertices.shape[0])


def _check_result(result) -> None:
    """Every float of a result finite, its ``score`` in [0, 1], ``to_dict`` serialisable."""
    import json

    assert dataclasses.is_dataclass(result), type(result)
    for f in dataclasses.fields(result):
        _check_value(getattr(result, f.name), f.name)
    score = getattr(result, "score", None)
    if score is not None:
        assert 0.0 <= float(score) <= 1.0, f"score {float(score)}"
    json.dumps(result.to_dict())


def _check_error(exc: TorchsymError, path: Path | None = None) -> None:
    text = str(exc)
    if path is not None:
        assert str(path) in text, text
    else:
        assert re.match(r"[A-Za-z_][\w.\[\]]*: ", text), f"no argument named: {text}"


def _read_everything(path: Path) -> None:
    """Every reader on ``path``: a typed error naming it, or checked data; the file unchanged."""
    before = path.read_bytes()
    readers = [load_input, read_pointcloud]
    suffix = path.suffix.lower()
    if suffix in MESH_SUFFIXES:
        readers.append(read_mesh)
    if suffix in IMAGE_SUFFIXES:
        readers = [load_input, read_image]
    for reader in readers:
        try:
            out = reader(path)
        except TorchsymError as exc:
            event(f"{reader.__name__}: {type(exc).__name__}")
            _check_error(exc, path)
        else:
            event(f"{reader.__name__}: read")
            _check_value(out[1] if isinstance(out, tuple) else out, f"{reader.__name__}({path.name})")
    assert path.read_bytes() == before


@pytest.mark.parametrize("suffix", sorted(set(POINT_SUFFIXES + IMAGE_SUFFIXES)))
@_fuzz(12)
@given(data=st.one_of(st.binary(max_size=400), st.binary(min_size=84, max_size=84 + 50 * 3)))
def test_readers_on_arbitrary_bytes(fuzz_dir, suffix, data):
    path = fuzz_dir / f"bytes{suffix}"
    path.write_bytes(data)
    _read_everything(path)


@pytest.mark.parametrize("suffix", sorted(_NEAR_VALID))
@_fuzz(60)
@given(st.data())
def test_readers_on_near_valid_files(fuzz_dir, suffix, data):
    path = fuzz_dir / f"near{suffix}"
    path.write_bytes(data.draw(_NEAR_VALID[suffix]))
    _read_everything(path)


@pytest.mark.slow
@pytest.mark.parametrize("suffix", [".xyz", ".npy", ".off"])
@_fuzz(6)
@given(st.data())
def test_detect_on_files(fuzz_dir, suffix, data):
    path = fuzz_dir / f"detect{suffix}"
    path.write_bytes(data.draw(_NEAR_VALID[suffix]))
    before = path.read_bytes()
    try:
        result = torchsym.detect(path, kind="pointcloud" if suffix == ".off" else None)
    except TorchsymError as exc:
        event(type(exc).__name__)
        _check_error(exc, path)
    else:
        event(type(result).__name__)
        _check_result(result)
    assert path.read_bytes() == before


@st.composite
def arrays(draw):
    """Tensors and arrays of the shapes the solvers take, and of many they do not."""
    shape = draw(st.sampled_from([(0, 3), (1, 3), (5, 3), (30, 3), (3, 30), (12, 2), (12, 5), (4,),
                                  (3, 20, 20), (3, 40, 40), (1, 33, 33), (2, 20, 20), (1, 1, 3, 3)]))
    dtype = draw(st.sampled_from([torch.float32, torch.float64, torch.int64, torch.uint8, torch.bool, torch.float16]))
    g = torch.Generator().manual_seed(draw(st.integers(0, 2**16)))
    x = torch.rand(shape, generator=g, dtype=torch.float64)
    if x.numel() and draw(st.booleans()):
        flat = x.view(-1)
        for _ in range(draw(st.integers(1, 3))):
            flat[draw(st.integers(0, flat.numel() - 1))] = draw(st.sampled_from(_SPECIAL))
    if draw(st.booleans()):
        x = x * draw(st.sampled_from([1e-200, 1e-8, 255.0, 1e8, 1e200]))
    with np.errstate(all="ignore"):
        x = x.to(dtype) if dtype.is_floating_point else x.clamp(-1e9, 1e9).nan_to_num().to(dtype)
    form = draw(st.sampled_from(["tensor", "tensor", "numpy", "sparse", "meta", "grad", "list"]))
    if form == "numpy":
        return x.numpy()
    if form == "sparse":
        return x.to_sparse()
    if form == "meta":
        return x.to("meta")
    if form == "grad" and x.is_floating_point():
        return x.requires_grad_(True)
    if form == "list":
        return x.tolist()
    return x


@pytest.mark.slow
@_fuzz(40)
@given(arrays())
def test_detect_on_arrays(x):
    torch.set_num_threads(1)
    try:
        result = torchsym.detect(x)
    except TorchsymError as exc:
        event(type(exc).__name__)
        _check_error(exc)
    else:
        event(type(result).__name__)
        _check_result(result)


@pytest.mark.parametrize("kind", ["bogus", 3])
def test_detect_unknown_kind(kind):
    with pytest.raises(TorchsymError, match=r"kind: expected one of pointcloud, points, image, mesh, multiview or None, got"):
        torchsym.detect(torch.rand(10, 3), kind=kind)


def _cli_files():
    near = st.sampled_from(sorted(_NEAR_VALID)).flatmap(lambda sfx: st.tuples(st.just(sfx), _NEAR_VALID[sfx]))
    junk = st.tuples(st.sampled_from([".off", ".obj", ".ply", ".stl", ".npy", ".xyz", ".png"]), st.binary(max_size=200))
    return st.one_of(near, junk)


@_fuzz(15)
@given(_cli_files())
def test_cli_in_process(fuzz_dir, file):
    """``main`` on a file: exit code 0 with a result, or 1 (the input failed) with one line naming the file;
    notes (a mesh sampled on its surface) are lines of their own."""
    import contextlib
    import io

    from torchsym.cli import main

    suffix, data = file
    path = fuzz_dir / f"cli{suffix}"
    path.write_bytes(data)
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        code = main(["detect", str(path), "--out", str(fuzz_dir / "out"), "-q", "--no-figures", "--kind", "pointcloud"])
    lines = [line for line in err.getvalue().splitlines() if line.strip() and not line.startswith("torchsym: note: ")]
    event(f"exit {code}")
    if code == 0:
        assert not lines and out.getvalue().startswith("cli: "), err.getvalue()
    else:
        assert code == 1 and len(lines) == 1 and lines[0].startswith("torchsym: error: ") and str(path) in lines[0], lines
    assert path.read_bytes() == data


@pytest.mark.slow
@_fuzz(1)
@given(st.lists(st.tuples(st.sampled_from([".off", ".obj", ".ply", ".npy", ".png"]), st.binary(min_size=1, max_size=200)),
                min_size=3, max_size=3))
@pytest.mark.slow
def test_cli_subprocess(fuzz_dir, files):
    """``python -m torchsym detect FOLDER`` over junk files (one process, its start-up is slow):
    exit code 1 (inputs failed), one error line per file and a summary, no traceback, files unchanged."""
    folder = fuzz_dir / "cli_folder"
    folder.mkdir(exist_ok=True)
    for q in folder.iterdir():
        q.unlink()
    paths = [folder / f"junk{i}{suffix}" for i, (suffix, _) in enumerate(files)]
    for path, (_, data) in zip(paths, files):
        path.write_bytes(data)
    env = {**os.environ, "PYTHONPATH": str(Path(torchsym.__file__).parents[1])}
    out = subprocess.run([sys.executable, "-m", "torchsym", "detect", str(folder), "--out", str(fuzz_dir / "out")],
                         capture_output=True, text=True, env=env, timeout=300)
    lines = [line for line in out.stderr.splitlines() if line.strip() and not line.startswith("torchsym: note: ")]
    assert out.returncode == 1 and "Traceback" not in out.stderr, out.stderr
    assert len(lines) == 4 and all(line.startswith("torchsym: error: ") for line in lines), out.stderr
    assert all(str(p) in line for p, line in zip(paths, lines)) and "3 of 3 inputs failed" in lines[3]
    assert [p.read_bytes() for p in paths] == [data for _, data in files]
