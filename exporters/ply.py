"""Stanford PLY files: binary little endian (default), binary big endian (read only) and ASCII.

The writer stores ``double`` x, y, z per vertex (float64, so a round trip is exact in every mode)
and one ``list uchar int vertex_indices`` per face (``list int int`` when a face has more than 255
corners); polygons are kept. The reader takes any PLY whose ``vertex`` element has scalar
``x``, ``y``, ``z`` properties and whose optional ``face`` element has a ``vertex_indices`` (or
``vertex_index``) list; other properties and elements are parsed past and ignored.
"""

from __future__ import annotations

import re

import numpy as np

from splinekit.errors import ExportError, FileFormatError, ParameterError

from . import _meshio

__all__ = ["export_ply", "import_ply"]

_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_INT32_MAX = 2**31 - 1
_END_HEADER = re.compile(rb"^[ \t]*end_header[ \t\r]*$", re.MULTILINE)


def _header(fmt: str, n_vertices: int, n_faces: int, count_type: str) -> bytes:
    return (
        f"ply\nformat {fmt} 1.0\ncomment written by splinekit\n"
        f"element vertex {n_vertices}\nproperty double x\nproperty double y\nproperty double z\n"
        f"element face {n_faces}\nproperty list {count_type} int vertex_indices\nend_header\n"
    ).encode("ascii")


def _binary_faces(indices: np.ndarray, offsets: np.ndarray, count_dtype: str) -> np.ndarray:
    """The face records as one flat ``uint8`` array: per face its corner count (``count_dtype``,
    little endian) followed by its ``int32`` vertex indices."""
    sizes = np.diff(offsets)
    F = sizes.size
    cdt = np.dtype(count_dtype).newbyteorder("<")
    if F and (sizes == sizes[0]).all():  # one record layout: a structured array
        k = int(sizes[0])
        rec = np.empty(F, dtype=[("n", cdt), ("i", "<i4", (k,))])
        rec["n"] = k
        rec["i"] = indices.reshape(F, k)
        return rec.view(np.uint8)
    c = cdt.itemsize
    starts = np.arange(F, dtype=np.int64) * c + offsets[:-1] * 4  # byte offset of each record
    out = np.empty(F * c + indices.size * 4, dtype=np.uint8)
    out[starts[:, None] + np.arange(c)] = sizes.astype(cdt).view(np.uint8).reshape(F, c)
    corner_face = np.repeat(np.arange(F), sizes)
    at = starts[corner_face] + c + (np.arange(indices.size) - offsets[:-1][corner_face]) * 4
    out[at[:, None] + np.arange(4)] = indices.astype("<i4").view(np.uint8).reshape(-1, 4)
    return out


def export_ply(path, mesh, binary=True) -> str:
    """Write ``mesh`` as a PLY file; returns the path written.

    Parameters
    ----------
    path : str or os.PathLike
        The target; written atomically (a temporary file beside it, renamed into place).
    mesh : splinekit.PolyMesh
        3-D vertices, polygon faces of any size (kept as polygons, in order).
    binary : bool
        ``binary_little_endian`` (float64 coordinates, int32 indices) or ``ascii`` (shortest
        round-trip text of the float64 coordinates). Both round-trip exactly.

    A mesh with 2**31 vertices or more does not fit PLY's ``int`` indices:
    :class:`~splinekit.errors.ExportError`.
    """
    mesh = _meshio.check_mesh(mesh, "export_ply")
    if not isinstance(binary, (bool, np.bool_)):
        raise ParameterError(f"binary must be True or False, got {binary!r}")
    V = mesh.vertices
    if len(V) > _INT32_MAX:
        raise ExportError(f"{len(V)} vertices do not fit the 32-bit indices of PLY")
    idx, offsets = mesh.face_indices, mesh.face_offsets
    sizes = np.diff(offsets)
    count_type = "uchar" if not sizes.size or sizes.max() <= 255 else "int"
    header = _header("binary_little_endian" if binary else "ascii", len(V), mesh.n_faces, count_type)

    if binary:
        faces = _binary_faces(idx, offsets, "u1" if count_type == "uchar" else "i4")

        def write(fh):
            _meshio.write_part(fh, header)
            _meshio.write_part(fh, np.ascontiguousarray(V, dtype="<f8"))
            _meshio.write_part(fh, faces)
    else:

        def write(fh):
            _meshio.write_part(fh, header)
            _meshio.format_rows("%r %r %r\n", V, fh)
            _meshio.format_polygons("%d ", "%d", idx[:, None], offsets, fh, face_values=sizes)

    return _meshio.save(path, write, "PLY file")


# -- reading ----------------------------------------------------------------------------------
class _Element:
    def __init__(self, name: str, count: int):
        self.name, self.count = name, count
        self.props: list[tuple[str, np.dtype, np.dtype | None]] = []  # (name, value dtype, list count dtype)


def _parse_header(data: bytes, what: str):
    """``(format, elements, body offset)`` of a PLY file."""
    if not data.startswith((b"ply\n", b"ply\r\n")):
        raise FileFormatError(f"{what}: not a PLY file (it must start with a 'ply' line)")
    # the header ends at the first line that is 'end_header' itself (not one that mentions it,
    # such as a comment); a regular expression anchored at line starts finds it in one pass
    m = _END_HEADER.search(data)
    if m is None:
        raise FileFormatError(f"{what}: PLY header has no 'end_header' line (truncated file?)")
    end = m.start()
    body = data.find(b"\n", m.end())
    if body < 0:
        raise FileFormatError(f"{what}: PLY header ends without a newline after 'end_header'")
    fmt, elements = None, []
    for number, raw in enumerate(data[:end].decode("latin-1").split("\n"), start=1):
        words = raw.split()
        if not words or words[0] in ("ply", "comment", "obj_info"):
            continue
        try:
            if words[0] == "format":
                fmt = words[1]
                if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
                    raise FileFormatError(f"{what}: unknown PLY format {fmt!r} (line {number})")
            elif words[0] == "element":
                count = int(words[2])
                if count < 0:
                    raise ValueError
                elements.append(_Element(words[1], count))
            elif words[0] == "property":
                if not elements:
                    raise FileFormatError(f"{what}: PLY property before any element (line {number})")
                if words[1] == "list":
                    elements[-1].props.append((words[4], np.dtype(_TYPES[words[3]]), np.dtype(_TYPES[words[2]])))
                else:
                    elements[-1].props.append((words[2], np.dtype(_TYPES[words[1]]), None))
            else:
                raise FileFormatError(f"{what}: unknown PLY header line {number}: {raw!r}")
        except (IndexError, KeyError, ValueError) as exc:
            if isinstance(exc, FileFormatError):
                raise
            raise FileFormatError(f"{what}: malformed PLY header line {number}: {raw!r}") from None
    if fmt is None:
        raise FileFormatError(f"{what}: PLY header has no 'format' line")
    names = [el.name for el in elements]
    for el in elements:
        if el.name in ("vertex", "face") and names.count(el.name) > 1:
            raise FileFormatError(f"{what}: PLY header declares {names.count(el.name)} '{el.name}' elements; one is expected")
        props = [p[0] for p in el.props]
        twice = next((p for p in props if props.count(p) > 1), None)
        if twice is not None:
            raise FileFormatError(f"{what}: PLY element '{el.name}' declares the property {twice!r} twice")
    return fmt, elements, body + 1


class _Stream:
    """The body of a PLY file as a sequence of units: bytes (binary) or numeric tokens (ASCII)."""

    def __init__(self, data: bytes, start: int, fmt: str, what: str):
        self.what = what
        self.binary = fmt != "ascii"
        if self.binary:
            self.data, self.size, self.order = data, len(data), "<" if fmt == "binary_little_endian" else ">"
        else:
            tokens = data[start:].split()
            try:
                self.tokens = np.array(tokens, dtype=bytes).astype(np.float64) if tokens else np.zeros(0)
            except ValueError:
                bad = next(i for i, t in enumerate(tokens) if not _meshio.is_float(t))
                raise FileFormatError(f"{what}: ASCII PLY value {bad} after the header is not a number: {tokens[bad]!r}") from None
            self.size = self.tokens.size

    def width(self, dtype: np.dtype) -> int:
        return dtype.itemsize if self.binary else 1

    def column(self, pos: int, dtype: np.dtype, stride: int, m: int, k: int = 1) -> np.ndarray:
        """``(m, k)`` values: ``k`` consecutive items from each of ``m`` records ``stride`` units apart."""
        if self.binary:
            dt = dtype.newbyteorder(self.order)
            return np.ndarray((m, k), dtype=dt, buffer=self.data, offset=pos, strides=(stride, dt.itemsize))
        return np.lib.stride_tricks.as_strided(self.tokens[pos:], shape=(m, k), strides=(stride * 8, 8))

    def scalar(self, pos: int, dtype: np.dtype):
        return self.column(pos, dtype, 0, 1)[0, 0]


def _read_element(stream: _Stream, pos: int, el: _Element, wanted: set):
    """Parse element ``el`` starting at unit ``pos``.

    Returns ``(values, end)``: ``values[name]`` is an ``(count,)`` array for a wanted scalar
    property, ``(flat items, sizes)`` for a wanted list. Records are taken in runs that share one
    layout (the same list lengths), each run with whole-array reads; a file whose consecutive faces
    alternate in size therefore costs one short step per face.
    """
    what = stream.what
    out_scalar = {name: [] for name, _, c in el.props if c is None and name in wanted}
    out_list = {name: ([], []) for name, _, c in el.props if c is not None and name in wanted}
    done, window = 0, 64
    while done < el.count:
        # the layout of the record at pos: offsets of every property, given its list lengths
        layout, off, lengths = [], 0, []
        for name, dt, cdt in el.props:
            if cdt is None:
                layout.append((name, dt, off, None))
                off += stream.width(dt)
                continue
            if pos + off + stream.width(cdt) > stream.size:
                raise FileFormatError(f"{what}: PLY {el.name} {done} is truncated")
            k = stream.scalar(pos + off, cdt)
            if not (np.isfinite(k) and k >= 0 and k == int(k)):  # an ASCII length may be inf or nan
                raise FileFormatError(f"{what}: PLY {el.name} {done} has an invalid list length {k!r}")
            k = int(k)
            layout.append((name, dt, off + stream.width(cdt), k))
            lengths.append((off, cdt, k))
            off += stream.width(cdt) + k * stream.width(dt)
        rec = off
        if rec == 0:  # an element without properties holds no data
            break
        fit = (stream.size - pos) // rec
        if fit < 1:
            raise FileFormatError(f"{what}: PLY {el.name} {done} is truncated (file ends at {stream.size})")
        # extend the run while the following records have the same list lengths
        m, limit = 1, min(el.count - done, fit)
        while m < limit:
            step = min(window, limit - m)
            same = np.ones(step, dtype=bool)
            for loff, cdt, k in lengths:
                same &= stream.column(pos + m * rec + loff, cdt, rec, step)[:, 0] == k
            if same.all():
                m += step
                window *= 2
            else:
                m += int(np.argmin(same))
                window = 64
                break
        if m < el.count - done and m == fit:
            raise FileFormatError(f"{what}: PLY {el.name} {done + m} is truncated (file ends at {stream.size})")
        for name, dt, poff, k in layout:
            if k is None and name in out_scalar:
                out_scalar[name].append(stream.column(pos + poff, dt, rec, m)[:, 0])
            elif k is not None and name in out_list:
                out_list[name][0].append(stream.column(pos + poff, dt, rec, m, k).ravel())
                out_list[name][1].append(np.full(m, k, dtype=np.int64))
        pos += m * rec
        done += m
    values = {name: np.concatenate(parts) if parts else np.zeros(0) for name, parts in out_scalar.items()}
    for name, (items, sizes) in out_list.items():
        values[name] = (
            np.concatenate(items) if items else np.zeros(0),
            np.concatenate(sizes) if sizes else np.zeros(0, dtype=np.int64),
        )
    return values, pos


def import_ply(path):
    """Read a PLY file (ASCII, binary little or big endian) into a :class:`~splinekit.PolyMesh`.

    Vertices come from the ``x``, ``y``, ``z`` properties of the ``vertex`` element (as float64),
    faces from the ``vertex_indices`` (or ``vertex_index``) list of the ``face`` element; polygons
    are kept. Malformed files (bad header, truncated data, non-numeric or non-finite values, a face
    with fewer than 3 corners, an index out of range) raise :class:`~splinekit.errors.FileFormatError`;
    non-manifold connectivity raises :class:`~splinekit.errors.MeshTopologyError`.
    """
    data = _meshio.read_bytes(path, "PLY file")
    what = f"PLY file {_meshio._fspath(path)!r}"
    fmt, elements, start = _parse_header(data, what)
    stream = _Stream(data, start, fmt, what)
    pos = start if stream.binary else 0
    V = faces = None
    for el in elements:
        if el.name == "vertex":
            names = {p[0] for p in el.props if p[2] is None}
            missing = [c for c in "xyz" if c not in names]
            if missing:
                raise FileFormatError(f"{what}: the PLY vertex element has no scalar {', '.join(missing)} property")
            values, pos = _read_element(stream, pos, el, {"x", "y", "z"})
            V = np.stack([values["x"], values["y"], values["z"]], axis=1).astype(np.float64)
        elif el.name == "face":
            lists = [p for p in el.props if p[2] is not None and p[0] in ("vertex_indices", "vertex_index")]
            if not lists:
                raise FileFormatError(f"{what}: the PLY face element has no 'vertex_indices' list property")
            if lists[0][1].kind == "f" and stream.binary:
                raise FileFormatError(f"{what}: PLY face indices must be integers, got type {lists[0][1]}")
            values, pos = _read_element(stream, pos, el, {lists[0][0]})
            faces = values[lists[0][0]]
        else:
            _, pos = _read_element(stream, pos, el, set())
    if V is None:
        raise FileFormatError(f"{what}: PLY file has no vertex element")
    _meshio.finite_or_raise(V, what)
    if faces is None:
        idx, sizes = np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    else:
        raw, sizes = faces
        if raw.dtype.kind == "f" and raw.size and not np.array_equal(raw, np.round(raw)):
            c = int(np.flatnonzero(raw != np.round(raw))[0])
            f = int(np.searchsorted(np.cumsum(sizes), c, side="right"))
            raise FileFormatError(f"{what}: PLY face {f} has a non-integer vertex index {float(raw[c])!r}")
        if sizes.size and sizes.min() < 3:
            f = int(np.flatnonzero(sizes < 3)[0])
            raise FileFormatError(f"{what}: PLY face {f} has {int(sizes[f])} corners; a face needs at least 3")
        # the range check comes before the cast: an ASCII index beyond int64 (or inf) has no int64 value
        bad = (raw < 0) | (raw >= len(V))
        if bad.any():
            c = int(np.flatnonzero(bad)[0])
            f = int(np.searchsorted(np.cumsum(sizes), c, side="right"))
            shown = int(raw[c]) if np.isfinite(raw[c]) else float(raw[c])
            raise FileFormatError(
                f"{what}: PLY face {f} refers to vertex {shown}, outside 0..{len(V) - 1}"
            )
        idx = raw.astype(np.int64)
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    return _meshio.build_mesh(V, idx, offsets, what)


_meshio.register("ply", export_ply, import_ply)
