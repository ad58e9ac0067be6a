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

from splinekit import limits
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
_GIANT_STEPS = 4096  # the most Python steps of the chain of records (see _record_starts)
_CHUNK = 1 << 18  # units laid out per vectorized step when chaining records
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

        size = len(header) + V.nbytes + faces.nbytes
    else:
        size = None

        def write(fh):
            _meshio.write_part(fh, header)
            _meshio.format_rows("%r %r %r\n", V, fh)
            _meshio.format_polygons("%d ", "%d", idx[:, None], offsets, fh, face_values=sizes)

    return _meshio.save(path, write, "PLY file", size=size)


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
        """``(m, k)`` values (no copy): ``k`` consecutive items from each of ``m`` records ``stride`` units apart."""
        if self.binary:
            dt = dtype.newbyteorder(self.order)
            return np.ndarray((m, k), dtype=dt, buffer=self.data, offset=pos, strides=(stride, dt.itemsize))
        return np.lib.stride_tricks.as_strided(self.tokens[pos:], shape=(m, k), strides=(stride * 8, 8))

    def every(self, pos: int, dtype: np.dtype) -> np.ndarray:
        """A value of ``dtype`` starting at every unit from ``pos`` to the end (no copy): unit
        ``pos + u`` is entry ``u`` (binary: overlapping unaligned reads, one per byte)."""
        if not self.binary:
            return self.tokens[pos:]
        dt = dtype.newbyteorder(self.order)
        m = max(self.size - pos - dt.itemsize + 1, 0)
        return np.ndarray((m,), dtype=dt, buffer=self.data, offset=min(pos, self.size), strides=(1,))


def _walk(stream: _Stream, pos: int, el: _Element, q: np.ndarray, wanted=frozenset()):
    """Lay out a record of ``el`` at each of the unit positions ``pos + q`` ``(m,)``, all at once.

    Returns ``(length, ok, values)``: the record length in units ``(m,)`` int64, whether a
    record fits there (every list length readable, finite, whole and >= 0, and the record inside
    the file) ``(m,)`` bool, and for the ``wanted`` properties their values as :func:`_read_element`
    gives them (read only where every record is known to be valid).
    """
    n = stream.size - pos
    length = np.zeros(q.shape, dtype=np.int64)
    ok = np.ones(q.shape, dtype=bool)
    values = {}
    for name, dt, cdt in el.props:
        w = stream.width(dt)
        if cdt is None:
            if name in wanted:
                values[name] = stream.every(pos, dt)[q + length]
            length += w
            continue
        wc = stream.width(cdt)
        at = q + length
        readable = at <= n - wc
        counts = stream.every(pos, cdt)
        k = counts[np.where(readable, at, 0)] if counts.size else np.zeros(q.shape, dtype=cdt)
        valid = readable & (k >= 0)
        if k.dtype.kind == "f":  # ASCII: a length must be a whole finite number
            valid &= np.isfinite(k) & (k == np.floor(k))
        k = np.where(valid, np.minimum(k.astype(np.float64 if k.dtype.kind == "f" else np.int64), n), 0)
        k = k.astype(np.int64)  # clipped to the file's length first: an ASCII 1e300 has no int64 value
        ok &= valid
        if name in wanted:
            first = at + wc  # the unit of each record's first item
            offsets = np.concatenate([[0], np.cumsum(k)])
            item = np.repeat(first, k) + (np.arange(offsets[-1]) - np.repeat(offsets[:-1], k)) * w
            values[name] = (stream.every(pos, dt)[item], k)
        length += wc + k * w
    ok &= q + length <= n
    return length, ok, values


def _explain(stream: _Stream, pos: int, el: _Element, index: int):
    """Raise the FileFormatError that says why record ``index`` of ``el`` at unit ``pos`` is bad."""
    what, off = stream.what, 0
    for _, dt, cdt in el.props:
        if cdt is not None:
            if pos + off + stream.width(cdt) > stream.size:
                raise FileFormatError(f"{what}: PLY {el.name} {index} is truncated")
            k = stream.every(pos + off, cdt)[0]
            if not (np.isfinite(k) and k >= 0 and k == int(k)):  # an ASCII length may be inf or nan
                raise FileFormatError(f"{what}: PLY {el.name} {index} has an invalid list length {k!r}")
            off += stream.width(cdt) + int(k) * stream.width(dt)
        else:
            off += stream.width(dt)
    raise FileFormatError(f"{what}: PLY {el.name} {index} is truncated (file ends at {stream.size})")


def _record_starts(stream: _Stream, pos: int, el: _Element) -> tuple[np.ndarray, int, int | None]:
    """Where each record of ``el`` starts ``(count,)`` int64 (units from ``pos``), where the
    element ends, and the record length when every record has the first one's layout (else None).

    A record's length depends on its list lengths, so record ``i + 1`` starts where record ``i``
    ends: a chain through the file. It is followed for every record at once by pointer doubling:
    ``nxt[u]``, where a record laid out at unit ``u`` would end (computed for every unit ``u`` of
    the rest of the file, vectorized), squared ``s`` times and followed in giant steps of ``2**s``
    records, then in ``2**s`` vectorized baby steps. The work is ``s ~ log2(count / 4096)``
    gathers of the file's length and about ``4096 + count / 4096`` Python steps (at most 8192 up
    to 16.7M records), none per record (one step per record cost 2 s per 100k faces when
    consecutive faces differ in size). Files whose records all share the first record's layout
    (all triangles, say) skip the chain.
    """
    n, count = stream.size - pos, el.count
    if count == 0 or not el.props:
        return np.zeros(count, dtype=np.int64), pos, None
    length, ok, _ = _walk(stream, pos, el, np.zeros(1, dtype=np.int64))
    if not ok[0]:
        _explain(stream, pos, el, 0)
    rec = int(length[0])
    if rec * count <= n:  # the same layout everywhere? (then its list lengths repeat every rec units)
        starts = np.arange(count, dtype=np.int64) * rec
        same, off = True, 0
        for _, dt, cdt in el.props:
            if cdt is not None:
                k = stream.every(pos + off, cdt)[::rec][:count]
                same = same and bool((k == k[0]).all())
                off += stream.width(cdt) + int(k[0]) * stream.width(dt)
            else:
                off += stream.width(dt)
        if same:
            return starts, pos + rec * count, rec
    # a record takes at least its scalars and list counts: more records than fit cannot be valid,
    # and the chain below follows at most one past that many (a header may claim any count)
    shortest = sum(stream.width(dt if cdt is None else cdt) for _, dt, cdt in el.props)
    count = min(count, n // shortest + 1)
    index = np.int32 if n + 2 < 2**31 else np.int64
    limits.check(3 * (n + 2) * np.dtype(index).itemsize, f"reading the {el.count:,} records of PLY {el.name!r} in {stream.what}")
    end = n + 1  # the sink: where the chain goes after a record that does not fit
    nxt = np.empty(n + 2, dtype=index)
    for lo in range(0, n, _CHUNK):  # bounded temporaries; a handful of steps per file
        q = np.arange(lo, min(lo + _CHUNK, n), dtype=np.int64)
        length, ok, _ = _walk(stream, pos, el, q)
        nxt[lo:lo + q.size] = np.where(ok, q + length, end)
    nxt[n:] = end
    # baby step, giant step: jump = nxt composed 2**s times (s squarings of the table), then the
    # starts of records 0, B, 2B, ... (B = 2**s) one jump each (at most _GIANT_STEPS Python steps,
    # whatever the count), then the B - 1 records after each of those, one gather per row
    s = (-(-(count + 1) // _GIANT_STEPS) - 1).bit_length()  # the least s with (count + 1) / 2**s <= _GIANT_STEPS
    jump = nxt
    for _ in range(s):
        jump = jump[jump]
    giant = np.empty(-(-(count + 1) // (1 << s)), dtype=index)
    p = 0
    for i in range(giant.size):
        giant[i] = p
        p = int(jump[p])
    del jump
    block = np.empty((1 << s, giant.size), dtype=index)
    block[0] = giant
    for r in range(1, 1 << s):
        block[r] = nxt[block[r - 1]]
    del nxt
    chain = block.T.ravel()
    chain = chain[:count + 1].astype(np.int64)
    bad = np.flatnonzero(chain[1:] == end)
    if bad.size:
        i = int(bad[0])
        _explain(stream, pos + int(chain[i]), el, i)
    if count < el.count:  # unreachable: so many records of at least `shortest` units overrun the file
        raise FileFormatError(f"{stream.what}: PLY {el.name} {count} is truncated (file ends at {stream.size})")
    return chain[:-1], pos + int(chain[-1]), None


def _read_element(stream: _Stream, pos: int, el: _Element, wanted: set):
    """Parse element ``el`` starting at unit ``pos``.

    Returns ``(values, end)``: ``values[name]`` is an ``(count,)`` array for a wanted scalar
    property, ``(flat items, sizes)`` for a wanted list (see :func:`_record_starts`).
    """
    starts, end, rec = _record_starts(stream, pos, el)
    if rec is None:
        _, _, values = _walk(stream, pos, el, starts, wanted)
    else:  # one layout: strided views, no gather (50x faster for an all-triangle file)
        values, off = {}, 0
        for name, dt, cdt in el.props:
            k = None
            if cdt is not None:
                k = int(stream.every(pos + off, cdt)[0])
                off += stream.width(cdt)
            if name in wanted:
                col = stream.column(pos + off, dt, rec, el.count, 1 if k is None else k)
                values[name] = col[:, 0] if k is None else (col.ravel(), np.full(el.count, k, dtype=np.int64))
            off += (1 if k is None else k) * stream.width(dt)
    for name, _, cdt in el.props:
        if name in wanted and name not in values:
            values[name] = np.zeros(0) if cdt is None else (np.zeros(0), np.zeros(0, dtype=np.int64))
    return values, end


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
