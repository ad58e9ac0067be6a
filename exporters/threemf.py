"""3MF (3D Manufacturing Format) files: a zip package holding one mesh object.

The package has the three parts a 3MF consumer needs: ``[Content_Types].xml``, ``_rels/.rels``
(pointing at the model) and ``3D/3dmodel.model`` (core specification 1.x, namespace
``http://schemas.microsoft.com/3dmanufacturing/core/2015/02``) with one ``<object>`` whose
``<mesh>`` lists ``<vertex x y z>`` and ``<triangle v1 v2 v3>`` elements, and one build item.
3MF meshes are triangles: polygons are fan-triangulated. Coordinates are written as the shortest
round-trip text of their float64 values.

The reader takes the mesh objects of such a package (every ``<object>`` with a ``<mesh>``, placed
by the build items' ``transform`` attributes, and objects made of ``<components>``), with a real
XML parser (expat, no DTD allowed), reading zip members with a size limit and checking the size
of the expanded build against the memory budget before expanding it.
"""

from __future__ import annotations

import io
import re
import struct
import zipfile
import zlib
from xml.sax.saxutils import quoteattr

import numpy as np

from splinekit import limits
from splinekit.errors import FileFormatError, ParameterError, SplineKitError

from . import _meshio, _text
# the reader's limits (MAX_..., MODEL_BYTES_FACTOR) stay importable from this module
from ._threemf_model import (  # noqa: F401
    _CORE_NS,
    _MODEL_TYPE,
    MAX_COMPONENT_DEPTH,
    MAX_RELS_BYTES,
    MODEL_BYTES_FACTOR,
    _model_target,
    _parents_first,
    _read_model,
    _sizes,
    _transform,
)

__all__ = ["UNITS", "export_3mf", "import_3mf"]

UNITS = ("micron", "millimeter", "centimeter", "inch", "foot", "meter")
"""The units a 3MF model may declare (the coordinates are written unchanged)."""

_CONTENT_TYPES = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">\n'
    ' <Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>\n'
    ' <Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>\n'
    "</Types>\n"
)
_RELS = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">\n'
    f' <Relationship Target="/3D/3dmodel.model" Id="rel0" Type="{_MODEL_TYPE}"/>\n'
    "</Relationships>\n"
)


# characters outside XML 1.0's Char production (controls other than tab / newline / return,
# surrogates, U+FFFE and U+FFFF)
_NOT_XML_CHAR = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def export_3mf(path, mesh, *, name="splinekit", unit="millimeter") -> str:
    """Write ``mesh`` as a 3MF package; returns the path written.

    Parameters
    ----------
    path : str or os.PathLike
        The target; written atomically (a temporary file beside it, renamed into place).
    mesh : splinekit.PolyMesh
        3-D vertices and at least one face; polygons are fan-triangulated from their first corner.
    name : str
        The object's name (any text XML can hold, escaped; control characters other than tab and
        line breaks, and lone surrogates, raise :class:`~splinekit.errors.ParameterError`).
    unit : str
        The model unit, one of :data:`UNITS`; the coordinates are written as they are, in this unit.
    """
    mesh = _meshio.check_mesh(mesh, "export_3mf")
    if not isinstance(name, str):
        raise ParameterError(f"name must be a str, got {type(name).__name__}")
    bad = _NOT_XML_CHAR.search(name)
    if bad is not None:  # no escape makes these legal in XML 1.0; UTF-8 cannot hold a lone surrogate
        raise ParameterError(
            f"name = {name!r} has the character U+{ord(bad.group()):04X} at position {bad.start()}, "
            "which an XML document cannot hold"
        )
    if unit not in UNITS:
        raise ParameterError(f"unit must be one of {', '.join(UNITS)}; got {unit!r}")
    if mesh.n_faces == 0:
        raise ParameterError("export_3mf needs a mesh with at least one face, got an empty mesh")
    tris = _meshio.triangles(mesh)
    head = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<model unit="{unit}" xml:lang="en-US" xmlns="{_CORE_NS}">\n'
        ' <metadata name="Application">splinekit</metadata>\n'
        " <resources>\n"
        f'  <object id="1" type="model" name={quoteattr(name)}>\n'
        "   <mesh>\n"
        "    <vertices>\n"
    )
    middle = "    </vertices>\n    <triangles>\n"
    tail = "    </triangles>\n   </mesh>\n  </object>\n </resources>\n" ' <build>\n  <item objectid="1"/>\n </build>\n</model>\n'

    def write(fh):
        with zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED) as package:
            package.writestr("[Content_Types].xml", _CONTENT_TYPES)
            package.writestr("_rels/.rels", _RELS)
            with package.open("3D/3dmodel.model", "w", force_zip64=True) as model:
                _meshio.write_part(model, head.encode("utf-8"))
                _meshio.format_rows('     <vertex x="%r" y="%r" z="%r"/>\n', mesh.vertices, model)
                _meshio.write_part(model, middle)
                _text.int_rows(tris, [b'     <triangle v1="', b'" v2="', b'" v3="', b'"/>\n'],
                               lambda chunk: _meshio.write_part(model, chunk))
                _meshio.write_part(model, tail)

    return _meshio.save(path, write, "3MF file")


# -- reading (the model part is parsed by ._threemf_model) ---------------------------------------
BYTES_PER_VERTEX = 64
"""Memory charged per vertex of the expanded build: float64 coordinates, the transformed copy and
the mesh built from it."""
BYTES_PER_TRIANGLE = 160
"""Memory charged per triangle of the expanded build (indices, offsets and the mesh topology)."""
BYTES_PER_PLACEMENT = 1024
"""Memory (and work) charged per placed copy of a mesh object, so that instancing a tiny object
millions of times is refused too."""
_ZIP_ERRORS = (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, EOFError, NotImplementedError,
               RuntimeError, OSError, ValueError, OverflowError, struct.error, UnicodeError, KeyError,
               IndexError, TypeError, LookupError)


def import_3mf(path):
    """Read the mesh objects of a 3MF package into one :class:`~splinekit.PolyMesh` of triangles.

    Every build item's object is placed with the item's ``transform``; an object made of
    components places each component's object with the component's transform, recursively (up
    to :data:`MAX_COMPONENT_DEPTH` levels). Without build items, every mesh object is taken as it
    is. The size of the expanded build is estimated before anything is copied and checked
    against the memory budget (:func:`splinekit.limits.check`), and so is the model part's
    uncompressed size before it is read.

    Raises :class:`~splinekit.errors.FileFormatError` (naming the file, and where known the line
    and byte of the model part) on a malformed package: not a zip, a missing part, a part that
    inflates past its declared size, XML that is not well-formed or declares a DTD, a bad number,
    an index out of range, a reference to a missing object, a component cycle, a transform that
    gives non-finite coordinates; :class:`~splinekit.errors.ResourceLimitError` when the model or
    its expansion would exceed the memory budget.
    """
    what = f"3MF file {_meshio._fspath(path)!r}"
    raw = _meshio.read_bytes(path, "3MF file")
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as package:
            names = set(package.namelist())
            target = _model_target(package, names, what)
            if target not in names:
                raise FileFormatError(f"{what}: the package has no model part {target!r}")
            model = _read_model(package, target, what)
    except SplineKitError:
        raise
    except _ZIP_ERRORS as exc:
        raise FileFormatError(f"{what}: not a readable 3MF (zip) package: {type(exc).__name__}: {exc}") from None
    V_all = np.concatenate(model.vertex_parts) if model.vertex_parts else np.zeros((0, 3))
    T_all = np.concatenate(model.triangle_parts) if model.triangle_parts else np.zeros((0, 3), dtype=np.int64)
    for oid, obj in model.objects.items():
        if obj["mesh"] is None:
            continue
        (v0, v1), (t0, t1) = obj["mesh"][0] or (0, 0), obj["mesh"][1] or (0, 0)
        _meshio.finite_or_raise(V_all[v0:v1], f"{what}: object {oid}")
        T = T_all[t0:t1]
        bad = (T < 0) | (T >= v1 - v0)
        if bad.any():
            t = int(np.flatnonzero(bad.any(axis=1))[0])
            raise FileFormatError(f"{what}: object {oid}: triangle {t} refers to vertex {T[t].tolist()}, outside 0..{v1 - v0 - 1}")
    if not any(obj["mesh"] is not None for obj in model.objects.values()):
        raise FileFormatError(f"{what}: the model has no mesh object")
    items = model.items or [(oid, None) for oid, obj in model.objects.items() if obj["mesh"] is not None]
    roots = [(oid, _transform(text, what, f"build item {k} (object {oid!r})")) for k, (oid, text) in enumerate(items)]

    # estimate the expansion, then check it against the budget, before copying anything
    size = _sizes(model, what)
    n_v = n_t = n_p = 0
    for oid, _ in roots:
        v, t, p = size(oid, 0)
        n_v, n_t, n_p = n_v + v, n_t + t, n_p + p
    limits.check(
        n_v * BYTES_PER_VERTEX + n_t * BYTES_PER_TRIANGLE + n_p * BYTES_PER_PLACEMENT,
        f"expanding the build of {what} ({n_v} vertices, {n_t} triangles in {n_p} placed objects)",
    )

    # placements: per object id the (k, 4, 4) world matrices of its copies, parents before children
    placements: dict = {}
    for oid, M in roots:
        placements.setdefault(oid, []).append(M[None])
    order = _parents_first(model, [oid for oid, _ in roots], size)
    parts_v, parts_t, base = [], [], 0
    with np.errstate(over="ignore", invalid="ignore"):
        for oid in order:
            P = np.concatenate(placements.pop(oid))
            obj = model.objects[oid]
            if obj["mesh"] is None:
                for child, text in obj["components"]:
                    if size(child, 0)[2]:  # skip subtrees without vertices
                        C = _transform(text, what, f"a component of object {oid!r}")
                        placements.setdefault(child, []).append(C @ P)
                continue
            (v0, v1), (t0, t1) = obj["mesh"][0] or (0, 0), obj["mesh"][1] or (0, 0)
            V = V_all[v0:v1]
            X = np.einsum("vi,kij->kvj", V, P[:, :3, :3]) + P[:, None, 3, :3]  # (k, nv, 3)
            parts_v.append(X.reshape(-1, 3))
            parts_t.append((T_all[t0:t1][None] + (base + np.arange(len(P)) * (v1 - v0))[:, None, None]).reshape(-1, 3))
            base += len(P) * (v1 - v0)
    V = np.concatenate(parts_v) if parts_v else np.zeros((0, 3))
    T = np.concatenate(parts_t) if parts_t else np.zeros((0, 3), dtype=np.int64)
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise FileFormatError(
            f"{what}: the build's transforms take vertex {int(np.flatnonzero(bad)[0])} of the expanded mesh "
            f"beyond the float64 range ({V[bad][0].tolist()})"
        )
    return _meshio.build_mesh(V, T.ravel(), np.arange(len(T) + 1, dtype=np.int64) * 3, what)


_meshio.register("3mf", export_3mf, import_3mf)
