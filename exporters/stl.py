"""STL (stereolithography) files, binary and ASCII.

Binary layout (little endian): an 80-byte header, a ``uint32`` triangle count ``n``, then ``n``
records of 50 bytes: normal ``3 x float32``, three vertices ``3 x 3 x float32``, a ``uint16``
attribute (0). The file is exactly ``84 + 50 n`` bytes. ASCII files are
``solid name / facet normal ... / outer loop / vertex x y z (x3) / endloop / endfacet / endsolid``.

STL stores unconnected triangles: polygons are fan-triangulated on export, and the reader merges
exactly equal vertex positions back into shared vertices.
"""

from __future__ import annotations

import re

import numpy as np

from splinekit.errors import ExportError, FileFormatError, ParameterError

from . import _meshio

__all__ = ["STL_DTYPE", "export_stl", "import_stl"]

STL_DTYPE = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
"""One binary STL triangle record (50 bytes, packed)."""

_CHUNK = 16_384  # triangles built and written per pass: the buffers stay in cache
_FLOAT32_MAX = float(np.finfo(np.float32).max)

_ASCII_FACET = (
    "  facet normal %r %r %r\n    outer loop\n"
    "      vertex %r %r %r\n      vertex %r %r %r\n      vertex %r %r %r\n"
    "    endloop\n  endfacet\n"
)


def _check_name(name) -> str:
    if not isinstance(name, str):
        raise ParameterError(f"name must be a str, got {type(name).__name__}")
    if not name.isascii() or not name.isprintable():
        raise ParameterError(f"name must be printable ASCII on one line, got {name!r}")
    return name


def triangle_normals(mesh, tris: np.ndarray) -> np.ndarray:
    """Unit normals ``(T, 3)`` float64 of the triangles ``tris`` of ``mesh``, cached on the mesh.

    A triangle mesh's are its :attr:`~splinekit.PolyMesh.face_normals`; a polygon mesh's fan
    triangles get their own (kept with the mesh through :meth:`~splinekit.PolyMesh.derived`, so a
    second export does not compute them again). Both are the normals of the float64 triangles, zero
    for a zero-area one; the mesh is immutable, so they never go stale. Read-only.
    """
    if mesh.is_triangle_mesh:
        return mesh.face_normals

    def fan_normals(m):
        V, N = m.vertices, np.empty((len(tris), 3))
        for s in range(0, len(tris), _CHUNK):
            N[s:s + _CHUNK] = _meshio.triangle_normals(V[tris[s:s + _CHUNK]])
        N.setflags(write=False)
        return N

    return mesh.derived("stl.fan_triangle_normals", fan_normals)


def _write_records(fh, V: np.ndarray, tris: np.ndarray, normals: np.ndarray) -> None:
    """Write the binary STL records (:data:`STL_DTYPE`) of the triangles ``tris`` ``(T, 3)`` of ``V``
    with the unit ``normals`` ``(T, 3)`` float64, all values rounded to float32.

    The records are built and written a chunk at a time in one reused buffer: a fresh array for all
    of them cost more in page faults (about 3 of 7.6 ms for 100k triangles) than filling them.
    """
    T = len(tris)
    fill = _meshio.stl_fill_kernel(T)
    V = np.ascontiguousarray(V, dtype=np.float64)
    tris = np.ascontiguousarray(tris, dtype=np.int64)
    normals = np.ascontiguousarray(normals, dtype=np.float64)
    n = min(T, _CHUNK)
    buf = np.empty(n, dtype=STL_DTYPE)
    rows = buf.view(np.uint8).reshape(n, STL_DTYPE.itemsize)
    rows[:, 48:] = 0  # the attribute
    # (n, 12) float32 view of normal + corners inside the 50-byte records, for the kernel
    flat = np.ndarray((n, 12), dtype="<f4", buffer=buf, strides=(STL_DTYPE.itemsize, 4))
    V32 = None if fill is not None else V.astype(np.float32)
    block = None if fill is not None else np.empty((n, 4, 3), dtype="<f4")
    for s in range(0, T, _CHUNK):
        e = min(s + _CHUNK, T)
        if fill is not None:
            fill(V, tris[s:e], normals[s:e], flat[:e - s])
        else:
            # laid out as contiguous float32 (normal, 3 corners), then copied as 48-byte rows:
            # assigning the float fields of the unaligned 50-byte records costs about twice as much
            b = block[:e - s]
            b[:, 0] = normals[s:e]
            np.take(V32, tris[s:e], axis=0, out=b[:, 1:])
            rows[:e - s, :48] = b.reshape(e - s, 12).view(np.uint8)
        _meshio.write_part(fh, buf[:e - s])


def export_stl(path, mesh, binary=True, *, name="splinekit") -> str:
    """Write ``mesh`` as an STL file; returns the path written.

    Parameters
    ----------
    path : str or os.PathLike
        The target; written atomically (a temporary file beside it, renamed into place).
    mesh : splinekit.PolyMesh
        3-D vertices; polygon faces are fan-triangulated from their first corner.
    binary : bool
        Binary STL (float32 coordinates) or ASCII STL (shortest round-trip text of the float64
        coordinates, so an ASCII round trip is exact).
    name : str
        The solid's name (ASCII); in the header of a binary file.

    Normals are the unit normals of the float64 triangles (right-hand rule), zero for zero-area
    ones: a triangle mesh's cached :attr:`~splinekit.PolyMesh.face_normals`, so exporting a mesh
    again, or one whose normals were asked for already, does not compute them again.
    Coordinates beyond the float32 range raise :class:`~splinekit.errors.ExportError` in binary mode;
    an unwritable folder raises :class:`~splinekit.errors.ExportError` and leaves no file behind.
    """
    mesh = _meshio.check_mesh(mesh, "export_stl")
    if not isinstance(binary, (bool, np.bool_)):
        raise ParameterError(f"binary must be True or False, got {binary!r}")
    name = _check_name(name)
    V = mesh.vertices
    tris = _meshio.triangles(mesh)
    if binary:
        if V.size and np.abs(V).max() > _FLOAT32_MAX:
            i = int(np.flatnonzero((np.abs(V) > _FLOAT32_MAX).any(axis=1))[0])
            raise ExportError(f"vertex {i} = {V[i].tolist()} is beyond the float32 range of binary STL")
        # a header starting with "solid" would make other readers take the file for ASCII
        header = f"binary STL {name}".encode("ascii")[:80].ljust(80, b" ")
        normals = triangle_normals(mesh, tris)

        def write(fh):
            _meshio.write_part(fh, header + np.uint32(len(tris)).astype("<u4").tobytes())
            _write_records(fh, V, tris, normals)

        return _meshio.save(path, write, "STL file", size=84 + STL_DTYPE.itemsize * len(tris))

    normals = triangle_normals(mesh, tris)

    def write_ascii(fh):
        _meshio.write_part(fh, f"solid {name}\n")
        for s in range(0, len(tris), _meshio.ROWS_PER_CHUNK):
            P = V[tris[s:s + _meshio.ROWS_PER_CHUNK]]
            rows = np.concatenate([normals[s:s + _meshio.ROWS_PER_CHUNK], P.reshape(-1, 9)], axis=1)
            _meshio.format_rows(_ASCII_FACET, rows, fh)
        _meshio.write_part(fh, f"endsolid {name}\n")

    return _meshio.save(path, write_ascii, "STL file")


# -- reading ----------------------------------------------------------------------------------
_NUM = rb"\s+(\S+)"
_FACET_RE = re.compile(
    rb"facet\s+normal\s+\S+\s+\S+\s+\S+\s+outer\s+loop"
    + (rb"\s+vertex" + _NUM * 3) * 3
    + rb"\s+endloop\s+endfacet(?=\s|$)"
)


_SOLIDS_RE = re.compile(rb"(?:\s*solid(?:[ \t][^\r\n]*)?\s+endsolid(?:[ \t][^\r\n]*)?)+\s*")
_SOLID_LINES_RE = re.compile(rb"(?:\s*(?:endsolid|solid)(?:[ \t][^\r\n]*)?(?=[\r\n]|$))*\s*")


def _ascii_problem(text: bytes) -> str:
    """Where an ASCII STL stops making sense (error path only: one step per facet)."""
    pos, k = 0, 0
    for m in _FACET_RE.finditer(text):
        if _SOLID_LINES_RE.match(text, pos).end() < m.start():
            break
        pos, k = m.end(), k + 1
    at = _SOLID_LINES_RE.match(text, pos).end()
    line = text.count(b"\n", 0, at) + 1
    if at == len(text):
        return f"ends at line {line} without an 'endsolid' line after its last facet (truncated file?)"
    if text.startswith(b"facet", at):
        return (
            f"facet {k} (line {line}) is malformed or truncated; expected "
            "'facet normal nx ny nz / outer loop / 3 x vertex x y z / endloop / endfacet'"
        )
    snippet = text[at:at + 30].split(b"\n")[0].decode("latin-1")
    return f"has unexpected text {snippet!r} at line {line}, after facet {k - 1}"


def _read_ascii(data: bytes, what: str) -> np.ndarray:
    """Triangle corners ``(T, 3, 3)`` float64 of an ASCII STL file."""
    text = data.lower()
    facets = _FACET_RE.findall(text)
    # every byte must belong to a facet or a solid / endsolid line: remove the facets, check the rest
    rest = _FACET_RE.sub(b" ", text)
    if not _SOLIDS_RE.fullmatch(rest):
        raise FileFormatError(f"{what}: ASCII STL {_ascii_problem(text)}")
    if not facets:
        return np.zeros((0, 3, 3))
    tokens = np.array(facets, dtype=bytes)
    try:
        P = tokens.astype(np.float64)
    except ValueError:
        bad = next(i for i, row in enumerate(facets) for t in row if not _meshio.is_float(t))
        raise FileFormatError(
            f"{what}: ASCII STL facet {bad} has a non-numeric vertex coordinate in {b' '.join(facets[bad]).decode('latin-1')!r}"
        ) from None
    return P.reshape(-1, 3, 3)


def _read_binary(data: bytes, what: str) -> np.ndarray:
    """Triangle corners ``(T, 3, 3)`` float64 of a binary STL file (size already checked)."""
    n = int.from_bytes(data[80:84], "little")
    records = np.frombuffer(data, dtype=STL_DTYPE, count=n, offset=84)
    return records["vertices"].astype(np.float64)


def _binary_size_problem(data: bytes) -> str:
    if len(data) < 84:
        return f"{len(data)} bytes is shorter than the 84-byte header of a binary STL (truncated file?)"
    n = int.from_bytes(data[80:84], "little")
    expected = 84 + 50 * n
    return (
        f"the binary STL header declares {n} triangles ({expected} bytes) but the file has {len(data)} bytes"
        + (" (truncated file?)" if len(data) < expected else "")
    )


def import_stl(path):
    """Read a binary or ASCII STL file into a :class:`~splinekit.PolyMesh` of triangles.

    A file whose size is exactly ``84 + 50 n`` (``n`` the count at byte 80) is binary, even when
    its header starts with ``solid``; otherwise a file starting with ``solid`` is ASCII. Exactly
    equal vertex positions are merged (in order of first appearance), and triangles that become
    degenerate (two corners at one position) are dropped, since a face needs distinct vertices;
    stored normals are ignored. Malformed files (truncated, wrong size, non-numeric or non-finite
    values) raise :class:`~splinekit.errors.FileFormatError`; non-manifold connectivity raises
    :class:`~splinekit.errors.MeshTopologyError` naming the file.
    """
    data = _meshio.read_bytes(path, "STL file")
    what = f"STL file {_meshio._fspath(path)!r}"
    binary_ok = len(data) >= 84 and len(data) == 84 + 50 * int.from_bytes(data[80:84], "little")
    if binary_ok:
        P = _read_binary(data, what)
    elif data.lstrip()[:5].lower() == b"solid":
        try:
            P = _read_ascii(data, what)
        except FileFormatError as exc:
            if b"\0" in data:  # not text at all: report it as the binary file it probably is
                raise FileFormatError(f"{what}: {_binary_size_problem(data)}") from exc
            raise
    else:
        raise FileFormatError(f"{what}: {_binary_size_problem(data)}")
    corners = P.reshape(-1, 3)
    bad = ~np.isfinite(corners).all(axis=1)
    if bad.any():
        c = int(np.flatnonzero(bad)[0])
        raise FileFormatError(f"{what}: triangle {c // 3} has a non-finite vertex {corners[c].tolist()}")
    V, index = _meshio.merge_vertices(corners)
    F = index.reshape(-1, 3)
    keep = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])
    if not keep.all():
        F = F[keep]
        used = np.zeros(len(V), dtype=bool)
        used[F.ravel()] = True
        if not used.all():  # drop vertices only the degenerate triangles used
            new = np.cumsum(used) - 1
            V, F = V[used], new[F]
    return _meshio.build_mesh(V, F.ravel(), np.arange(len(F) + 1, dtype=np.int64) * 3, what)


_meshio.register("stl", export_stl, import_stl)
