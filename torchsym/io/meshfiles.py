"""Parsers for the mesh formats OFF, OBJ, PLY (ASCII and binary) and STL, in NumPy.

Each parser returns ``(vertices (V, 3) float64, faces (F, 3) int64)`` after checking
everything a later step indexes with: declared counts against ``max_points`` and against
what the file holds, every face index inside ``[0, V)``, polygons of at least three
corners (larger ones are split into a fan of triangles). A file that breaks any of these
raises :class:`~torchsym.errors.InputFileError` naming the file and the line or element;
nothing is handed to a C++ reader, so no file can crash the process.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from torchsym.errors import InputFileError

__all__ = ["parse_mesh_file"]

#: faces accepted per allowed point (a closed triangle mesh has about twice as many faces as vertices)
FACES_PER_POINT = 4


class _Bad(Exception):
    """A format error, turned into InputFileError naming the file by :func:`parse_mesh_file`."""


def parse_mesh_file(p: Path, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertices ``(V, 3)`` float64 and triangles ``(F, 3)`` int64 of the mesh file ``p``.

    The format comes from the suffix (``.off .obj .ply .stl``); at most ``max_points``
    vertices and ``4 * max_points`` faces are accepted.

    Raises:
        InputFileError: an unreadable or malformed file, or one past the limits.
    """
    suffix = p.suffix.lower()
    try:
        size = p.stat().st_size
        if size > 256 * max_points + 4096:
            raise _Bad(f"{size} bytes is more than a file of max_points={max_points} points takes")
        data = p.read_bytes()
        parser = {".off": _parse_off, ".obj": _parse_obj, ".ply": _parse_ply, ".stl": _parse_stl}[suffix]
        v, f = parser(data, max_points)
    except _Bad as exc:
        raise InputFileError(f"path: cannot read {str(p)!r} as a {suffix} mesh or point cloud ({exc})") from None
    except OSError as exc:
        raise InputFileError(f"path: cannot read {str(p)!r} ({exc.strerror or exc})") from None
    return v, f


def _text(data: bytes) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _count(token: str, what: str, limit: int) -> int:
    try:
        n = int(token)
    except ValueError:
        raise _Bad(f"{what}: expected a count, got {token!r}") from None
    if n < 0 or n > limit:
        raise _Bad(f"{what}: expected a count in [0, {limit}], got {n}")
    return n


def _floats(rows: list[list[str]], where: str) -> np.ndarray:
    """``rows`` of at least three number tokens as ``(len(rows), 3)`` float64."""
    try:
        return np.array([r[:3] for r in rows], dtype=np.float64).reshape(len(rows), 3)
    except (ValueError, OverflowError):
        for i, r in enumerate(rows):
            try:
                np.array(r[:3], dtype=np.float64).reshape(3)
            except (ValueError, OverflowError):
                raise _Bad(f"{where} {i}: expected three numbers x y z, got {' '.join(r)!r}") from None
        raise  # pragma: no cover


def _index_array(tokens: list[str], where: str) -> np.ndarray:
    try:
        return np.array(tokens, dtype=np.int64)
    except (ValueError, OverflowError):
        raise _Bad(f"{where}: expected integer vertex indices, got {' '.join(tokens)!r}") from None


def _fan(polygons: list[np.ndarray], n_vertices: int, where: str) -> np.ndarray:
    """Triangles ``(F, 3)`` from polygons of vertex indices, split as fans; indices checked."""
    if not polygons:
        return np.zeros((0, 3), dtype=np.int64)
    lengths = np.array([q.shape[0] for q in polygons])
    if (lengths < 3).any():
        i = int(np.argmax(lengths < 3))
        raise _Bad(f"{where} {i}: expected at least 3 corners, got {lengths[i]}")
    flat = np.concatenate(polygons).astype(np.int64)
    outside = (flat < 0) | (flat >= n_vertices)
    if outside.any():
        j = int(np.argmax(outside))
        i = int(np.searchsorted(np.cumsum(lengths), j, side="right"))
        raise _Bad(f"{where} {i}: vertex index {int(flat[j])} outside [0, {n_vertices})")
    if (lengths == lengths[0]).all():
        table = flat.reshape(len(polygons), int(lengths[0]))  # (F, k)
        k = table.shape[1]
        return np.stack([table[:, [0, j, j + 1]] for j in range(1, k - 1)], axis=1).reshape(-1, 3)
    tris = [np.stack([np.full(q.shape[0] - 2, q[0]), q[1:-1], q[2:]], axis=1) for q in polygons]
    return np.concatenate(tris).astype(np.int64)


def _triangles(faces: np.ndarray, n_vertices: int, where: str) -> np.ndarray:
    """Check a ``(F, 3)`` index array against ``n_vertices``."""
    if faces.size and (faces.min() < 0 or faces.max() >= n_vertices):
        row = int(np.nonzero(((faces < 0) | (faces >= n_vertices)).any(axis=1))[0][0])
        raise _Bad(f"{where} {row}: vertex indices {faces[row].tolist()} outside [0, {n_vertices})")
    return faces.astype(np.int64)


# --------------------------------------------------------------------------- OFF


def _data_lines(text: str) -> list[list[str]]:
    """Token lists of the non-empty lines, ``#`` comments removed."""
    if "#" in text:
        text = re.sub(r"#[^\n]*", "", text)
    return [tokens for tokens in map(str.split, text.splitlines()) if tokens]


def _parse_off(data: bytes, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    rows = _data_lines(_text(data))
    if not rows or not re.fullmatch(r"(ST)?[CN]{0,2}OFF", rows[0][0]):
        got = rows[0][0][:20] if rows else "an empty file"
        raise _Bad(f"expected the keyword OFF (or COFF, NOFF...) first, got {got!r}")
    head = rows[0][1:]
    if head and head[0].upper() == "BINARY":
        raise _Bad("binary OFF is not supported; save it as ASCII OFF or PLY")
    start = 1
    if not head:
        if len(rows) < 2:
            raise _Bad("expected a line with the vertex and face counts after OFF")
        head, start = rows[1], 2
    if len(head) < 2:
        raise _Bad(f"expected the counts 'n_vertices n_faces [n_edges]', got {' '.join(head)!r}")
    nv = _count(head[0], "vertex count", max_points)
    nf = _count(head[1], "face count", FACES_PER_POINT * max_points)
    if len(rows) - start < nv + nf:
        raise _Bad(f"the header declares {nv} vertices and {nf} faces, but the file holds {len(rows) - start} lines of them")
    v = _floats(rows[start:start + nv], "vertex")
    face_rows = rows[start + nv:start + nv + nf]
    if face_rows and all(len(r) == 4 and r[0] == "3" for r in face_rows):
        f = _triangles(_index_array([t for r in face_rows for t in r[1:]], "faces").reshape(-1, 3), nv, "face")
        return v, f
    polygons = []
    for i, r in enumerate(face_rows):
        k = _count(r[0], f"face {i}: corner count", 1 << 20)
        if len(r) < k + 1:
            raise _Bad(f"face {i}: declares {k} corners, got {len(r) - 1} numbers")
        polygons.append(_index_array(r[1:k + 1], f"face {i}"))
    return v, _fan(polygons, nv, "face")


# --------------------------------------------------------------------------- OBJ


def _parse_obj(data: bytes, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    vrows: list[list[str]] = []
    polygons: list[np.ndarray] = []
    for lineno, line in enumerate(_text(data).splitlines(), 1):
        tokens = line.split("#", 1)[0].split()
        if not tokens:
            continue
        if tokens[0] == "v":
            if len(tokens) < 4:
                raise _Bad(f"line {lineno}: expected 'v x y z', got {line.strip()[:60]!r}")
            vrows.append(tokens[1:4])
            if len(vrows) > max_points:
                raise _Bad(f"more than max_points={max_points} vertices")
        elif tokens[0] == "f":
            if len(tokens) < 4:
                raise _Bad(f"line {lineno}: a face needs at least 3 corners, got {line.strip()[:60]!r}")
            idx = _index_array([t.split("/", 1)[0] for t in tokens[1:]], f"line {lineno}")
            # OBJ counts from 1; negative indices count back from the last vertex so far
            polygons.append(np.where(idx < 0, len(vrows) + idx, idx - 1))
            if len(polygons) > FACES_PER_POINT * max_points:
                raise _Bad(f"more than {FACES_PER_POINT * max_points} faces")
    v = _floats(vrows, "vertex") if vrows else np.zeros((0, 3))
    return v, _fan(polygons, v.shape[0], "face")


# --------------------------------------------------------------------------- PLY

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def _ply_header(data: bytes, max_points: int) -> tuple[str, list[tuple[str, int, list[tuple]]], int]:
    """``(format, elements, body offset)``; an element is ``(name, count, properties)``,
    a property ``(name, type)`` or ``(name, count type, item type)`` for a list."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise _Bad("expected a PLY header: 'ply' first and an 'end_header' line")
    nl = data.find(b"\n", end)
    body = len(data) if nl < 0 else nl + 1
    fmt = ""
    elements: list[tuple[str, int, list[tuple]]] = []
    for line in _text(data[:end]).splitlines()[1:]:
        t = line.split()
        if not t or t[0] in ("comment", "obj_info"):
            continue
        if t[0] == "format" and len(t) >= 2:
            fmt = t[1]
        elif t[0] == "element" and len(t) == 3:
            limit = max_points if t[1] == "vertex" else FACES_PER_POINT * max_points
            elements.append((t[1], _count(t[2], f"element {t[1]}", limit), []))
        elif t[0] == "property" and elements and len(t) == 3 and t[1] in _PLY_TYPES:
            elements[-1][2].append((t[2], _PLY_TYPES[t[1]]))
        elif (t[0] == "property" and elements and len(t) == 5 and t[1] == "list"
              and t[2] in _PLY_TYPES and t[3] in _PLY_TYPES and not _PLY_TYPES[t[2]].startswith("f")):
            elements[-1][2].append((t[4], _PLY_TYPES[t[2]], _PLY_TYPES[t[3]]))
        else:
            raise _Bad(f"header line {line.strip()[:60]!r} is not a PLY declaration")
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise _Bad(f"expected format ascii, binary_little_endian or binary_big_endian, got {fmt!r}")
    names = [e[0] for e in elements]
    if "vertex" not in names:
        raise _Bad("the header declares no 'element vertex'")
    vprops = [q[0] for q in elements[names.index("vertex")][2] if len(q) == 2]
    if not {"x", "y", "z"} <= set(vprops):
        raise _Bad(f"expected vertex properties x, y and z, got {vprops}")
    return fmt, elements, body


def _parse_ply(data: bytes, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    fmt, elements, offset = _ply_header(data, max_points)
    read = _ply_ascii if fmt == "ascii" else _ply_binary
    columns = read(data, offset, elements, "<" if fmt == "binary_little_endian" else ">")
    vert = columns["vertex"]
    try:
        v = np.stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"], axis=1).reshape(-1, 3)
    except (ValueError, OverflowError):
        raise _Bad("expected numbers for the vertex coordinates x, y, z") from None
    face = next((e for e in elements if e[0] == "face"), None)
    lists = [q for q in (face[2] if face else []) if len(q) == 3 and not q[2].startswith("f")]
    named = [q for q in lists if q[0] in ("vertex_indices", "vertex_index")]
    f = np.zeros((0, 3), dtype=np.int64)
    if lists:
        f = _fan([np.asarray(a, dtype=np.int64) for a in columns["face"][(named or lists)[0][0]]], v.shape[0], "face")
    return v, f


def _ply_ascii(data: bytes, offset: int, elements: list, _: str) -> dict[str, dict]:
    rows = [line.split() for line in _text(data[offset:]).splitlines()]
    rows = [r for r in rows if r]
    out: dict[str, dict] = {}
    at = 0
    for name, count, props in elements:
        if len(rows) - at < count:
            raise _Bad(f"element {name}: the header declares {count} rows, the file holds {len(rows) - at}")
        block, at = rows[at:at + count], at + count
        if all(len(q) == 2 for q in props):
            if any(len(r) != len(props) for r in block):
                i = next(i for i, r in enumerate(block) if len(r) != len(props))
                raise _Bad(f"{name} {i}: expected {len(props)} numbers, got {len(block[i])}")
            try:
                table = np.array(block, dtype=np.float64).reshape(count, len(props))
            except (ValueError, OverflowError):
                raise _Bad(f"element {name}: expected numbers in every row") from None
            out[name] = {q[0]: table[:, j] for j, q in enumerate(props)}
            continue
        out[name] = {q[0]: [] for q in props}
        for i, r in enumerate(block):
            k = 0
            for q in props:
                if k >= len(r):
                    raise _Bad(f"{name} {i}: row ends before property {q[0]!r}")
                if len(q) == 2:
                    out[name][q[0]].append(r[k])
                    k += 1
                else:
                    n = _count(r[k], f"{name} {i}: list length", 1 << 20)
                    if k + 1 + n > len(r):
                        raise _Bad(f"{name} {i}: declares {n} entries, got {len(r) - k - 1}")
                    items = r[k + 1:k + 1 + n]
                    if q[2].startswith("f"):
                        out[name][q[0]].append(np.zeros(n))  # float lists (texture coordinates) unused
                    else:
                        out[name][q[0]].append(_index_array(items, f"{name} {i}"))
                    k += 1 + n
    return out


def _ply_binary(data: bytes, offset: int, elements: list, order: str) -> dict[str, dict]:
    out: dict[str, dict] = {}
    for name, count, props in elements:
        if all(len(q) == 2 for q in props):
            dtype = np.dtype([(q[0], order + q[1]) for q in props])
            need = count * dtype.itemsize
            if len(data) - offset < need:
                raise _Bad(f"element {name}: {count} rows need {need} bytes, the file holds {len(data) - offset}")
            table = np.frombuffer(data, dtype=dtype, count=count, offset=offset)
            out[name] = {q[0]: table[q[0]] for q in props}
            offset += need
        else:
            out[name], offset = _ply_binary_lists(data, offset, name, count, props, order)
    return out


def _ply_binary_lists(data: bytes, offset: int, name: str, count: int, props: list, order: str) -> tuple[dict, int]:
    """Rows with list properties: every row at once when all lists of the first row's length
    repeat, else row by row; every read is checked against the bytes left."""
    cols: dict[str, list] = {q[0]: [] for q in props}
    for i in range(count):
        for q in props:
            if len(q) == 2:
                size = np.dtype(q[1]).itemsize
                if offset + size > len(data):
                    raise _Bad(f"{name} {i}: the file ends inside the row")
                cols[q[0]].append(np.frombuffer(data, order + q[1], 1, offset)[0])
                offset += size
                continue
            csize, isize = np.dtype(q[1]).itemsize, np.dtype(q[2]).itemsize
            if offset + csize > len(data):
                raise _Bad(f"{name} {i}: the file ends inside the row")
            n = int(np.frombuffer(data, order + q[1], 1, offset)[0])
            if n < 0 or offset + csize + n * isize > len(data):
                raise _Bad(f"{name} {i}: a list of {n} entries runs past the end of the file")
            cols[q[0]].append(np.frombuffer(data, order + q[2], n, offset + csize))
            offset += csize + n * isize
        if i == 0 and count > 1:
            fast = _ply_uniform_rows(data, offset, name, count - 1, props, order, cols)
            if fast is not None:
                return cols, fast
    return cols, offset


def _ply_uniform_rows(data: bytes, offset: int, name: str, count: int, props: list, order: str, cols: dict) -> int | None:
    """Read ``count`` further rows shaped like the first (lists of its lengths) into ``cols``;
    the new offset, or None (``cols`` untouched) when the rows differ."""
    fields = []
    for q in props:
        if len(q) == 2:
            fields.append((q[0], order + q[1]))
        else:
            fields += [(q[0] + "#n", order + q[1]), (q[0], order + q[2], (len(cols[q[0]][0]),))]
    dtype = np.dtype(fields)
    if len(data) - offset < count * dtype.itemsize:
        return None
    table = np.frombuffer(data, dtype=dtype, count=count, offset=offset)
    lists = [q for q in props if len(q) == 3]
    if any((table[q[0] + "#n"] != len(cols[q[0]][0])).any() for q in lists):
        return None
    for q in props:
        if len(q) == 2:
            cols[q[0]] = np.concatenate([np.asarray(cols[q[0]]), table[q[0]]])
        else:
            cols[q[0]] = cols[q[0]] + list(table[q[0]])
    return offset + count * dtype.itemsize


# --------------------------------------------------------------------------- STL


def _parse_stl(data: bytes, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Binary STL (84-byte header, 50 bytes per triangle) or ASCII ``solid ... vertex x y z``;
    corners at the same position become one vertex, in order of first appearance."""
    n = int(np.frombuffer(data, "<u4", 1, 80)[0]) if len(data) >= 84 else -1
    if n >= 0 and len(data) == 84 + 50 * n:
        if n > FACES_PER_POINT * max_points:
            raise _Bad(f"{n} triangles is more than {FACES_PER_POINT * max_points}")
        rec = np.frombuffer(data, dtype=[("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("a", "<u2")], count=n, offset=84)
        corners = rec["v"].reshape(-1, 3).astype(np.float64)
    elif data.lstrip().startswith(b"solid"):
        found = re.findall(rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)", data)
        if len(found) % 3:
            raise _Bad(f"expected three 'vertex' lines per facet, got {len(found)} in all")
        if len(found) > 3 * FACES_PER_POINT * max_points:
            raise _Bad(f"{len(found) // 3} triangles is more than {FACES_PER_POINT * max_points}")
        try:
            corners = np.array(found, dtype=np.float64).reshape(-1, 3)
        except (ValueError, OverflowError):
            raise _Bad("expected numbers after every 'vertex'") from None
    else:
        raise _Bad("neither binary STL (84 + 50 x triangles bytes) nor ASCII STL (starting with 'solid')")
    if corners.shape[0] == 0:
        return corners, np.zeros((0, 3), dtype=np.int64)
    uniq, first, inverse = np.unique(corners, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.shape[0])
    if uniq.shape[0] > max_points:
        raise _Bad(f"{uniq.shape[0]} distinct vertices is more than max_points={max_points}")
    return uniq[order], rank[inverse.reshape(-1)].reshape(-1, 3).astype(np.int64)
