"""Helpers shared by the mesh writers and readers (STL, OBJ, PLY, 3MF, glTF binary).

- formats: the suffix table, :func:`format_of`, and the checks on the mesh handed to a writer;
- writing: :func:`save` (atomic: a temporary file beside the target, renamed into place; an
  unwritable folder or a failing write raises :class:`~splinekit.errors.ExportError` and leaves the
  target untouched), :func:`write_part` (every byte a writer produces goes through it) and the
  vectorized text formatting (:func:`format_rows`, :func:`format_polygons`);
- reading: :func:`read_bytes`, :func:`merge_vertices`, :func:`build_mesh`;
- :func:`export_mesh` / :func:`import_mesh`, which dispatch on the file suffix to the writer and
  reader each format module registers (:func:`register`).

Floats written as text use Python's shortest round-trip ``repr``, so a float64 coordinate read back
with ``float()`` is bit-for-bit the value that was written.
"""

from __future__ import annotations

import os
import stat

import numpy as np

from splinekit import _kernels, limits
from splinekit._atomic import atomic_write, checked_path, write_target
from splinekit.errors import (
    FileFormatError,
    MeshTopologyError,
    ParameterError,
)
from splinekit.mesh import PolyMesh
from splinekit.mesh._rows import cross_rows
from splinekit.mesh.geometry import triangulate
from splinekit.mesh.topology import Topology

__all__ = [
    "SUFFIXES",
    "build_mesh",
    "check_mesh",
    "check_target",
    "export_mesh",
    "finite_or_raise",
    "format_of",
    "format_polygons",
    "format_rows",
    "import_mesh",
    "merge_vertices",
    "read_bytes",
    "register",
    "reserve",
    "save",
    "triangles",
    "write_part",
]

SUFFIXES = {".stl": "stl", ".obj": "obj", ".ply": "ply", ".3mf": "3mf", ".glb": "glb"}
"""Suffix -> format name, for :func:`exporters.export_mesh` / :func:`exporters.import_mesh`."""

ROWS_PER_CHUNK = 65_536
"""Text is formatted and written this many rows at a time: the Python floats of one chunk
stay small (a 1M-triangle ASCII STL would otherwise hold 12M of them at once)."""


# -- formats and meshes -----------------------------------------------------------------------
def _supported() -> str:
    return ", ".join(SUFFIXES)


def format_of(path, format=None) -> str:
    """The format name (``"stl"``, ``"obj"``, ``"ply"``, ``"3mf"``, ``"glb"``) of ``path``.

    ``format`` overrides the suffix (with or without the dot, any case). An unknown format raises
    :class:`~splinekit.errors.FileFormatError` naming it and listing the supported ones.
    """
    if format is None:
        path = _fspath(path)
        suffix = os.path.splitext(path)[1].lower()
        if suffix not in SUFFIXES:
            shown = repr(suffix) if suffix else "no suffix"
            raise FileFormatError(
                f"unsupported mesh format {shown} for {os.path.basename(path)!r}; supported: {_supported()}"
            )
        return SUFFIXES[suffix]
    if not isinstance(format, str):
        raise FileFormatError(f"format must be a string such as 'stl', got {format!r}; supported: {_supported()}")
    key = "." + format.lower().lstrip(".")
    if key not in SUFFIXES:
        raise FileFormatError(f"unsupported mesh format {format!r}; supported: {_supported()}")
    return SUFFIXES[key]


def _fspath(path) -> str:
    """``path`` as a str; ParameterError if it is not a path, is empty or holds a NUL byte."""
    return checked_path(path)


def check_mesh(mesh, what: str):
    """``mesh`` if it is a PolyMesh with 3-D vertices, else :class:`ParameterError`."""
    if not isinstance(mesh, PolyMesh):
        raise ParameterError(f"{what} needs a splinekit.PolyMesh, got {type(mesh).__name__}")
    if mesh.vertices.ndim != 2 or mesh.vertices.shape[1] != 3:
        raise ParameterError(f"{what} needs 3-D vertices, got vertices of shape {mesh.vertices.shape}")
    return mesh


def triangles(mesh) -> np.ndarray:
    """``(T, 3)`` int64 vertex indices: the faces fan-triangulated from their first corner
    (:func:`splinekit.mesh.geometry.triangulate`); a triangle mesh's own faces, uncopied."""
    if mesh.topology.n_faces and mesh.is_triangle_mesh:
        return mesh.face_indices.reshape(-1, 3)
    return triangulate(mesh)[0]


def triangle_normals(P: np.ndarray, scale: bool = True) -> np.ndarray:
    """Unit normals ``(T, 3)`` float64 of the triangles ``P`` ``(T, 3, 3)`` (counter-clockwise,
    right-hand rule); zero for a zero-area triangle (never NaN).

    With ``scale``, each triangle is first scaled by a power of two that brings its largest
    coordinate near 1 (exact, so the result is the same), and coordinates up to the float64
    limits neither overflow nor underflow in the cross product; float32 coordinates cannot, so
    they may skip it.
    """
    P = np.asarray(P, dtype=np.float64)
    if scale:
        big = np.abs(P).reshape(len(P), -1).max(axis=1) if len(P) else np.zeros(0)
        P = np.ldexp(P, -np.frexp(big)[1][:, None, None])
    a = P[:, 1] - P[:, 0]
    b = P[:, 2] - P[:, 0]
    n = cross_rows(a, b, np.empty((len(P), 3)))
    length = np.sqrt(np.einsum("ij,ij->i", n, n))
    ok = length > 0  # zero area: a zero vector, never NaN
    n /= np.where(ok, length, 1.0)[:, None]
    n[~ok] = 0.0
    return n


MIN_COMPILED_TRIANGLES = _kernels.MIN_WORK
"""Binary STL records of at least this many triangles are filled by a numba kernel (one pass, no
temporaries, :mod:`exporters._stl_kernel`) when :mod:`splinekit._kernels` serves compiled code;
smaller meshes, and every mesh without numba, take the numpy path. Both give the same bytes (the
tests compare them): the mesh's cached float64 normals and the corners, rounded to float32."""


RECORD_WORK = 1 / 8
"""A binary STL record in :mod:`splinekit._kernels` work units, so that a first export loads the
kernel only where the saving pays for numba's import. The numpy path fills a record in 0.08-0.14
microseconds of CPU (a quarter of a curve point) and the kernel saves only about half of that
(the rest is the write), measured in one loaded run: counted as one unit, a first export of 2M
triangles loaded the kernel and took 1.7 times the numpy path's wall time (1.9 its CPU); as a third, 6M
triangles took 1.3-2.1 times its CPU. As an eighth, a first export loads it from 16M triangles
on; once numba is up (another family loaded it) every export of MIN_COMPILED_TRIANGLES or more
takes the kernel (2x faster warm)."""


def stl_fill_kernel(n_triangles: int):
    """The compiled ``fill`` that writes binary STL records, or None (use numpy).

    Called as ``fill(V, tris, N, out)``: ``V`` ``(n, 3)`` float64, ``tris`` ``(T, 3)`` int64, ``N``
    ``(T, 3)`` float64 unit normals, ``out`` ``(T, 12)`` float32 (a view of the records: normal then
    the three corners, all rounded to float32, as the numpy path does).
    """
    K = _kernels.load("exporters._stl_kernel", work=n_triangles * RECORD_WORK,
                      min_work=MIN_COMPILED_TRIANGLES * RECORD_WORK)
    return None if K is None else K.fill


# -- writing ----------------------------------------------------------------------------------
def write_part(fh, data) -> None:
    """Write ``data`` (bytes, str encoded as ASCII, or a numpy array's raw bytes) to ``fh``.

    Every writer sends its output through this one function (the tests replace it to fail
    midway and check that the target survives)."""
    if isinstance(data, str):
        data = data.encode("ascii")
    if isinstance(data, np.ndarray):
        if data.flags.c_contiguous:
            data.tofile(fh)  # no copy of a large array
            return
        data = data.tobytes()
    fh.write(data)


def check_target(path, what: str) -> str:
    """``path`` as a str if a file can be written there, checked before the work of a writer:
    ParameterError for a ``path`` that is not a path, ExportError (naming ``what``) if its folder is
    missing or ``path`` is a folder, a device, a FIFO, a socket or a read-only file (see
    :func:`splinekit._atomic.write_target`; :func:`save` checks again when it writes)."""
    path = _fspath(path)
    write_target(path, what)
    return path


def reserve(fh, size: int) -> None:
    """Allocate ``size`` bytes for the file ``fh`` is about to fill (``posix_fallocate``), where the
    platform and file system allow; otherwise nothing.

    Why: renaming a new file over an existing one makes ext4 (its default ``auto_da_alloc``) allocate
    the new file's delayed blocks inside the rename. Measured on ext4 (the project's 2-core machine),
    the rename cost 7 ms for 5 MB and 35 ms for 50 MB; with the blocks allocated up front the whole
    atomic write of 5 MB took 3.1 ms instead of 7.1 ms (a plain truncating ``open(path, "wb")`` write:
    5.4 ms). What the rename still costs is freeing the replaced file (2.9 ms for 5 MB, as unlinking
    it would). The file grows to ``size`` at once: :func:`save` truncates it to what was written.
    """
    allocate = getattr(os, "posix_fallocate", None)
    if allocate is None or size <= 0:
        return
    try:
        allocate(fh.fileno(), 0, size)
    except OSError:  # not supported here (or no space: the write itself then reports it)
        pass


def save(path, write, what: str, size: int | None = None) -> str:
    """Write a file atomically: ``write(fh)`` fills a temporary binary file beside ``path``, which is
    then renamed onto ``path``. Returns ``path`` as a string.

    Through :func:`splinekit._atomic.atomic_write`: a missing or unwritable folder, a ``path`` that is
    not a regular file, or an OSError while writing raises :class:`~splinekit.errors.ExportError`
    (naming ``what`` and the path); in every failure the temporary file is removed and an existing
    target is left byte-for-byte as it was. A symbolic link is kept and the file it names replaced.

    ``size``, when the writer knows it (binary formats), is the file's length in bytes: the space is
    reserved before writing (:func:`reserve`), which makes the final rename cheap; the file ends where
    ``write`` stopped, whatever ``size`` said.
    """
    path = check_target(path, what)

    def fill(tmp):
        with open(tmp, "wb") as fh:
            if size:
                reserve(fh, size)
            write(fh)
            if size:
                fh.truncate()  # at the end of what was written

    return atomic_write(path, fill, what)


def format_rows(template: str, values: np.ndarray, fh) -> None:
    """Write one ``template % row`` per row of ``values`` ``(n, k)`` to ``fh``.

    The rows are formatted a chunk at a time with one ``%`` over a repeated template (the loop
    runs in C); ``%r`` in the template gives the shortest round-trip text of a float64.
    """
    values = np.asarray(values)
    n = len(values)
    for start in range(0, n, ROWS_PER_CHUNK):
        block = values[start:start + ROWS_PER_CHUNK]
        write_part(fh, (template * len(block)) % tuple(block.ravel().tolist()))


def format_polygons(prefix: str, corner: str, values: np.ndarray, offsets: np.ndarray, fh,
                    face_values: np.ndarray | None = None) -> None:
    """Write one line per face: ``prefix`` then the face's corners, each formatted with ``corner``.

    ``values`` ``(H, c)`` holds the ``c`` numbers of each corner (``corner`` has ``c`` ``%``
    fields), face ``f`` owning rows ``offsets[f]:offsets[f + 1]``; corners are separated by spaces.
    ``face_values`` ``(F, p)`` fills ``p`` ``%`` fields of ``prefix`` (such as a PLY face's corner
    count). Faces of any sizes are written in order without a Python loop per face: a per-corner
    template (prefix on first corners, newline after last ones) is joined in C and applied with
    one ``%`` per chunk of faces.
    """
    offsets = np.asarray(offsets, dtype=np.int64)
    values = np.asarray(values)
    if values.ndim == 1:
        values = values[:, None]
    c = values.shape[1]
    n_faces = offsets.size - 1
    fv = None if face_values is None else np.asarray(face_values).reshape(n_faces, -1 if n_faces else 1)
    p = 0 if fv is None else fv.shape[1]
    pieces = np.array([corner + " ", prefix + corner + " ", corner + "\n", prefix + corner + "\n"], dtype=object)
    for f0 in range(0, n_faces, ROWS_PER_CHUNK):
        f1 = min(f0 + ROWS_PER_CHUNK, n_faces)
        h0, h1 = int(offsets[f0]), int(offsets[f1])
        starts = offsets[f0:f1] - h0
        first = np.zeros(h1 - h0, dtype=np.int64)
        first[starts] = 1
        last = np.zeros(h1 - h0, dtype=np.int64)
        last[offsets[f0 + 1:f1 + 1] - h0 - 1] = 2
        template = "".join(pieces[first + last].tolist())
        block = values[h0:h1]
        if p:
            # interleave: the p face values go just before the values of the face's first corner
            flat = np.empty((h1 - h0) * c + (f1 - f0) * p, dtype=np.result_type(block, fv))
            face = np.repeat(np.arange(f1 - f0), np.diff(offsets[f0:f1 + 1]))
            at = (np.arange(h1 - h0) * c + (face + 1) * p)[:, None] + np.arange(c)
            flat[at] = block
            flat[(starts * c + np.arange(f1 - f0) * p)[:, None] + np.arange(p)] = fv[f0:f1]
            block = flat
        write_part(fh, template % tuple(block.ravel().tolist()))


# -- reading ----------------------------------------------------------------------------------
READ_BYTES_FACTOR = 10
"""Memory a mesh reader needs per byte of its file, charged to the budget before reading: the peak
of an import over the file size is 4.5 (ASCII STL, OBJ) to 8 (binary STL and PLY) on a
330k-triangle mesh."""


def read_bytes(path, what: str) -> bytes:
    """The whole file; a missing or unreadable file raises :class:`FileFormatError` naming it, one
    whose import would exceed the memory budget (:data:`READ_BYTES_FACTOR` times its size)
    :class:`~splinekit.errors.ResourceLimitError` before reading."""
    path = _fspath(path)
    try:
        # non-blocking open: a FIFO would otherwise wait for a writer; only regular files are read
        # (a device such as /dev/zero never ends)
        with open(os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0)), "rb") as fh:
            info = os.fstat(fh.fileno())
            if not stat.S_ISREG(info.st_mode):
                raise FileFormatError(f"cannot read {what} {path!r}: it is not a regular file")
            limits.check(info.st_size * READ_BYTES_FACTOR, f"reading the {info.st_size}-byte {what} {path!r}")
            return fh.read()
    except OSError as exc:
        reason = exc.strerror or str(exc) or type(exc).__name__
        raise FileFormatError(f"cannot read {what} {path!r}: {reason}") from exc


def finite_or_raise(V: np.ndarray, what: str, item: str = "vertex") -> None:
    """Raise :class:`FileFormatError` naming the first row of ``V`` with a NaN or infinite value."""
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise FileFormatError(f"{what}: {item} {i} has non-finite coordinates {V[i].tolist()}")


def _mix(h: np.ndarray) -> np.ndarray:
    """The splitmix64 finaliser of ``h`` (uint64), in place: a bijection that spreads every input
    bit over all output bits (integer overflow wraps, as intended)."""
    h ^= h >> np.uint64(30)
    h *= np.uint64(0xBF58476D1CE4E5B9)
    h ^= h >> np.uint64(27)
    h *= np.uint64(0x94D049BB133111EB)
    h ^= h >> np.uint64(31)
    return h


def row_hash(U: np.ndarray) -> np.ndarray:
    """A 64-bit hash ``(m,)`` of each row of the ``(m, 3)`` uint64 array ``U``.

    Each column is folded in through a full mix (``h = mix(mix(mix(u0) ^ u1) ^ u2)``). A cheaper
    multiply-xor of the columns collided on symmetric meshes, whose mirrored points differ only in
    sign bits that cancelled (5,000 points of a torus from float32 data gave 2,600 hashes, and every
    read then fell back to the exact row sort: 3x slower).
    """
    h = _mix(U[:, 0].copy())
    for c in range(1, U.shape[1]):
        h ^= U[:, c]
        _mix(h)
    return h


def merge_vertices(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge exactly equal rows of ``points`` ``(m, 3)`` float64.

    Returns ``(vertices (n, 3), index (m,))`` with ``points == vertices[index]``; vertices keep
    the order of their first occurrence. ``-0.0`` and ``0.0`` count as equal.

    Rows are grouped by sorting a 64-bit hash of their bits (one integer sort instead of a
    row-wise sort, several times faster); every row is then compared with its group's
    representative, and should two different rows ever share a hash, an exact row sort is used.
    """
    P = np.ascontiguousarray(points, dtype=np.float64) + 0.0  # + 0.0 turns -0.0 into 0.0
    m = len(P)
    if not m:
        return P.reshape(0, 3), np.zeros(0, dtype=np.int64)
    U = P.view(np.uint64)
    h = row_hash(U)
    order = np.argsort(h)
    sorted_h = h[order]
    new = np.empty(m, dtype=bool)
    new[0] = True
    np.not_equal(sorted_h[1:], sorted_h[:-1], out=new[1:])
    starts = np.flatnonzero(new)
    group = np.empty(m, dtype=np.int64)
    group[order] = np.cumsum(new) - 1
    first = np.minimum.reduceat(order, starts)  # first occurrence of each group
    if not (U[first][group] == U).all():  # a hash collision: fall back to an exact row sort
        rows = P.view(np.dtype((np.void, 8 * P.shape[1]))).ravel()
        _, first, group = np.unique(rows, return_index=True, return_inverse=True)
        group = group.ravel()
    by_first = np.argsort(first, kind="stable")  # groups in first-occurrence order
    rank = np.empty_like(by_first)
    rank[by_first] = np.arange(by_first.size)
    return P[first[by_first]], rank[group]


def build_mesh(vertices: np.ndarray, face_indices: np.ndarray, face_offsets: np.ndarray, what: str):
    """A :class:`~splinekit.PolyMesh`; topology problems are re-raised with ``what`` (the file) named."""
    V = np.ascontiguousarray(vertices, dtype=np.float64)
    try:
        topology = Topology(len(V), face_indices, face_offsets, check=True)
    except MeshTopologyError as exc:
        raise type(exc)(f"{what}: {exc}") from exc
    return PolyMesh.from_topology(V, topology)


# -- dispatch ---------------------------------------------------------------------------------
_FORMATS: dict = {}
"""Format name -> ``(writer, reader)``; each format module registers itself when it is imported
(:func:`register`), so this module needs none of them and they all import it."""


def register(format: str, writer, reader) -> None:
    """Make ``writer(path, mesh, **options)`` and ``reader(path)`` the ones :func:`export_mesh` and
    :func:`import_mesh` use for ``format`` (a name of :data:`SUFFIXES`)."""
    if format not in SUFFIXES.values():
        raise ParameterError(f"unknown mesh format {format!r}; SUFFIXES names {sorted(set(SUFFIXES.values()))}")
    _FORMATS[format] = (writer, reader)


def _registered(format: str):
    try:
        return _FORMATS[format]
    except KeyError:  # only when exporters/__init__.py stops importing a format module
        raise FileFormatError(f"the {format} reader and writer are not loaded (import exporters)") from None


def export_mesh(path, mesh, format=None, **options) -> str:
    """Write ``mesh`` in the format named by ``path``'s suffix (or by ``format``); returns the path.

    Suffixes: ``.stl`` (binary), ``.obj``, ``.ply`` (binary), ``.3mf``, ``.glb``; ``options`` go to
    the format's writer (``binary=False`` for ASCII STL or PLY, ``normals=False``, ``name=``,
    ``unit=``). An unsupported format raises :class:`~splinekit.errors.FileFormatError` naming it and
    listing the supported ones.
    """
    writer, _ = _registered(format_of(path, format))
    return writer(path, mesh, **options)


def import_mesh(path, format=None):
    """Read a mesh file (``.stl``, ``.obj``, ``.ply``, ``.3mf``, ``.glb``, by suffix unless
    ``format`` is given) into a :class:`~splinekit.PolyMesh`."""
    _, reader = _registered(format_of(path, format))
    return reader(path)


def is_float(token: bytes) -> bool:
    """Whether a text token parses as a float (to name a bad token in error messages)."""
    try:
        float(token)
    except ValueError:
        return False
    return True
