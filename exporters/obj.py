"""Wavefront OBJ files: ``v`` vertices, ``vn`` vertex normals, ``f`` polygon faces.

The writer keeps polygons as they are (no triangulation) and writes coordinates as the shortest
round-trip text of their float64 values, so writing and reading a mesh gives it back exactly. The
reader accepts the ``v``, ``v/vt``, ``v//vn`` and ``v/vt/vn`` corner forms, negative (relative)
indices, faces of any size, ``\\``-continued lines and any line ending (``\\n``, ``\\r\\n``, ``\\r``);
texture coordinates, normals, groups, objects, materials, lines and points are checked or skipped
but not returned.
"""

from __future__ import annotations

import re

import numpy as np

from splinekit.errors import FileFormatError, ParameterError

from . import _meshio, _objscan, _text

__all__ = ["NORMAL_DECIMALS", "export_obj", "import_obj"]

NORMAL_DECIMALS = 15
"""Decimals of the ``vn`` unit normals (within 1e-15 of the float64 normal): written in numpy
(:func:`exporters._text.fixed_rows`), while Python's shortest float text costs about a
microsecond per number and made the normals half of an OBJ file's time."""


def export_obj(path, mesh, normals=True) -> str:
    """Write ``mesh`` as a Wavefront OBJ file; returns the path written.

    Parameters
    ----------
    path : str or os.PathLike
        The target; written atomically (a temporary file beside it, renamed into place).
    mesh : splinekit.PolyMesh
        3-D vertices, polygon faces of any size (kept as polygons).
    normals : bool
        Also write the angle-weighted unit vertex normals (``vn``, one per vertex, referenced as
        ``f a//a b//b ...``; :data:`NORMAL_DECIMALS` decimals, trailing zeros dropped); zero
        vectors at isolated vertices.

    Vertex indices are 1-based, in the order of ``mesh.vertices``; faces keep their order and
    orientation.
    """
    mesh = _meshio.check_mesh(mesh, "export_obj")
    if not isinstance(normals, (bool, np.bool_)):
        raise ParameterError(f"normals must be True or False, got {normals!r}")
    V = mesh.vertices
    idx = mesh.face_indices + 1  # OBJ counts from 1
    N = mesh.vertex_normals if normals and len(mesh.face_indices) else None

    k = int(mesh.face_offsets[1]) if mesh.n_faces and mesh.topology.is_uniform else 0

    def write(fh):
        _meshio.write_part(fh, f"# written by splinekit: {len(V)} vertices, {mesh.n_faces} faces\n")
        _meshio.format_rows("v %r %r %r\n", V, fh)
        sink = lambda chunk: _meshio.write_part(fh, chunk)  # noqa: E731
        if N is not None:  # (a unit component may round to 1 + 2e-16)
            _text.fixed_rows(np.clip(N, -1.0, 1.0), [b"vn ", b" ", b" ", b"\n"], NORMAL_DECIMALS, sink)
        if k:  # all faces of k sides: the face lines built in numpy
            corners = idx.reshape(-1, k)
            if N is not None:
                literals = [b"f "] + [b"//", b" "] * (k - 1) + [b"//", b"\n"]
                _text.int_rows(np.repeat(corners, 2, axis=1), literals, sink)
            else:
                _text.int_rows(corners, [b"f "] + [b" "] * (k - 1) + [b"\n"], sink)
        elif N is not None:
            _meshio.format_polygons("f ", "%d//%d", np.stack([idx, idx], axis=1), mesh.face_offsets, fh)
        else:
            _meshio.format_polygons("f ", "%d", idx[:, None], mesh.face_offsets, fh)

    return _meshio.save(path, write, "OBJ file")


# -- reading ----------------------------------------------------------------------------------
_TOKEN = rb"[ \t]+([^ \t\r\n#]+)"
_VERTEX_RE = re.compile(rb"^[ \t]*v" + _TOKEN * 3, re.MULTILINE)
_KIND_RE = re.compile(rb"^[ \t]*(vt|vn|v|f)(?=[ \t\r\n#]|$)", re.MULTILINE)
_FACE_RE = re.compile(rb"^[ \t]*f(?=[ \t\r\n#]|$)([^#\r\n]*)", re.MULTILINE)


def _line_number(text: bytes, kind: bytes, k: int) -> int:
    """1-based line of the ``k``-th line of ``kind`` (error path only)."""
    pattern = re.compile(rb"^[ \t]*" + kind + rb"(?=[ \t\r\n#]|$)", re.MULTILINE)
    for i, m in enumerate(pattern.finditer(text)):
        if i == k:
            return text.count(b"\n", 0, m.start()) + 1
    return text.count(b"\n") + 1


def _parse_ints(parts: np.ndarray, what: str, text: bytes, face_of_corner, name: str) -> np.ndarray:
    try:
        return parts.astype(np.int64)
    except (ValueError, OverflowError):
        # error path only: a token that is not an integer, or one beyond int64
        digits = np.array([p.lstrip(b"+-").isdigit() for p in parts.tolist()])
        ok = digits & np.array([d and abs(int(p)) < 2**63 for p, d in zip(parts.tolist(), digits.tolist())])
        c = int(np.flatnonzero(~ok)[0])
        f = int(face_of_corner[c])
        problem = "an out-of-range" if digits[c] else "a non-integer"
        raise FileFormatError(
            f"{what}: face {f} (line {_line_number(text, b'f', f)}) has {problem} {name} index {parts[c].decode('latin-1')!r}"
        ) from None


def _resolve(raw: np.ndarray, before: np.ndarray, total: int, what: str, text, face_of_corner, name: str):
    """0-based indices from OBJ indices ``raw`` (1-based, or negative: relative to the ``before``
    elements defined above the face); FileFormatError names the first face with a bad index."""
    idx = np.where(raw < 0, before + raw, raw - 1)
    bad = (raw == 0) | (idx < 0) | (idx >= total)
    if bad.any():
        c = int(np.flatnonzero(bad)[0])
        f = int(face_of_corner[c])
        relative = raw[c] < 0
        n = int(before[c]) if relative else total
        plural = "vertices" if name == "vertex" else name + "s"
        defined = f"{n} {plural} are defined{' above it' if relative else ''}"
        valid = f"valid: 1..{n} or -{n}..-1" if n else f"no {plural} to refer to"
        raise FileFormatError(
            f"{what}: face {f} (line {_line_number(text, b'f', f)}) refers to {name} {int(raw[c])}; "
            f"{defined} ({valid})"
        )
    return idx


def import_obj(path):
    """Read a Wavefront OBJ file into a :class:`~splinekit.PolyMesh` (polygons kept).

    All ``v`` lines give the vertices (extra components such as ``w`` or colours are ignored), all
    ``f`` lines the faces, in file order (groups and objects are merged). Indices may be 1-based or
    negative (``-1`` is the last vertex defined above the face); ``vt``/``vn`` references are
    checked for range but not returned. Malformed input raises
    :class:`~splinekit.errors.FileFormatError` naming the line: a ``v`` line with fewer than three
    numbers, a non-finite coordinate, a face with fewer than three corners, an index of 0 or out of
    range. Non-manifold connectivity raises :class:`~splinekit.errors.MeshTopologyError`.
    """
    data = _meshio.read_bytes(path, "OBJ file")
    what = f"OBJ file {_meshio._fspath(path)!r}"
    # lines may end in \n, \r\n or \r alone (classic Mac OS): one convention from here on
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    text = data.replace(b"\\\n", b" ")  # continued lines

    fast = _objscan.scan(text)  # plain files (what exporters write); None: the general path below
    if fast is not None:
        V, kinds, sizes, fields = fast
        is_v, is_vt, is_vn, is_f = (kinds == k for k in (1, 2, 3, 4))
        n_v, n_vt, n_vn = int(is_v.sum()), int(is_vt.sum()), int(is_vn.sum())
        face_of_corner = np.repeat(np.arange(sizes.size), sizes)
        v_before, vt_before, vn_before = (np.cumsum(is_k)[is_f] for is_k in (is_v, is_vt, is_vn))
        idx = _resolve(fields["v"], v_before[face_of_corner], n_v, what, text, face_of_corner, "vertex")
        for name, before, total, label in (("vt", vt_before, n_vt, "texture coordinate"), ("vn", vn_before, n_vn, "normal")):
            if name in fields:
                _resolve(fields[name], before[face_of_corner], total, what, text, face_of_corner, label)
        offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        return _meshio.build_mesh(V, idx, offsets, what)

    kinds = np.array(_KIND_RE.findall(text), dtype="S2")
    is_v, is_vt, is_vn, is_f = (kinds == k for k in (b"v", b"vt", b"vn", b"f"))
    n_v, n_vt, n_vn = int(is_v.sum()), int(is_vt.sum()), int(is_vn.sum())

    coords = _VERTEX_RE.findall(text)
    if len(coords) != n_v:
        # error path only: the first v line the vertex pattern does not match (tokens are separated
        # by spaces or tabs only, so "1\x0c2" is one token, as it is above)
        lines = re.finditer(rb"^[ \t]*v(?=[ \t\r\n#]|$)", text, re.MULTILINE)
        bad = next(i for i, line in enumerate(lines) if not _VERTEX_RE.match(text, line.start()))
        raise FileFormatError(
            f"{what}: vertex {bad} (line {_line_number(text, b'v', bad)}) has fewer than 3 coordinates "
            "(separated by spaces or tabs)"
        )
    V = np.array(coords, dtype=bytes).reshape(-1, 3)
    try:
        V = V.astype(np.float64)
    except ValueError:
        ok = np.array([_meshio.is_float(t) for t in V.ravel().tolist()]).reshape(-1, 3).all(axis=1)  # error path only
        i = int(np.flatnonzero(~ok)[0])
        raise FileFormatError(
            f"{what}: vertex {i} (line {_line_number(text, b'v', i)}) has a non-numeric coordinate in {b' '.join(coords[i]).decode('latin-1')!r}"
        ) from None
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise FileFormatError(f"{what}: vertex {i} (line {_line_number(text, b'v', i)}) is not finite: {V[i].tolist()}")

    # per face: how many v / vt / vn lines come before it (for negative indices)
    v_before = np.cumsum(is_v)[is_f]
    vt_before = np.cumsum(is_vt)[is_f]
    vn_before = np.cumsum(is_vn)[is_f]

    lines = _FACE_RE.findall(text)
    # one token list for all faces, a "#" after each face (a face's text never holds "#")
    tokens = np.array(b" # ".join(lines).split() + [b"#"], dtype=bytes) if lines else np.zeros(0, "S1")
    marks = np.flatnonzero(tokens == b"#")
    sizes = np.diff(np.concatenate([[-1], marks])) - 1
    if sizes.size and sizes.min() < 3:
        f = int(np.flatnonzero(sizes < 3)[0])
        raise FileFormatError(
            f"{what}: face {f} (line {_line_number(text, b'f', f)}) has {int(sizes[f])} corners; a face needs at least 3"
        )
    corners = tokens[tokens != b"#"]
    face_of_corner = np.repeat(np.arange(sizes.size), sizes)
    # the v, vt and vn fields of each corner ('' where absent)
    head, _, rest = _partition(corners)
    vt_s, _, vn_s = _partition(rest)
    raw_v = _parse_ints(head, what, text, face_of_corner, "vertex")
    idx = _resolve(raw_v, v_before[face_of_corner], n_v, what, text, face_of_corner, "vertex")
    for field, before, total, name in ((vt_s, vt_before, n_vt, "texture coordinate"), (vn_s, vn_before, n_vn, "normal")):
        present = field != b""
        if present.any():
            raw = _parse_ints(field[present], what, text, face_of_corner[present], name)
            _resolve(raw, before[face_of_corner[present]], total, what, text, face_of_corner[present], name)
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    return _meshio.build_mesh(V, idx, offsets, what)


def _partition(tokens: np.ndarray):
    """Split each token at its first ``/``: (before, separator, after), as byte-string arrays."""
    if not tokens.size:
        empty = np.zeros(0, dtype="S1")
        return empty, empty, empty
    parts = np.char.partition(tokens, b"/")
    return parts[:, 0], parts[:, 1], parts[:, 2]


_meshio.register("obj", export_obj, import_obj)
