"""3MF (3D Manufacturing Format) files: a zip package holding one mesh object.

The package has the three parts a 3MF consumer needs: ``[Content_Types].xml``, ``_rels/.rels``
(pointing at the model) and ``3D/3dmodel.model`` (core specification 1.x, namespace
``http://schemas.microsoft.com/3dmanufacturing/core/2015/02``) with one ``<object>`` whose
``<mesh>`` lists ``<vertex x y z>`` and ``<triangle v1 v2 v3>`` elements, and one build item.
3MF meshes are triangles: polygons are fan-triangulated. Coordinates are written as the shortest
round-trip text of their float64 values.

The reader takes the mesh objects of such a package (every ``<object>`` with a ``<mesh>``, placed
by the build items' ``transform`` attributes).
"""

from __future__ import annotations

import io
import re
import zipfile
from xml.sax.saxutils import quoteattr

import numpy as np

from splinekit.errors import FileFormatError, ParameterError

from . import _meshio

__all__ = ["UNITS", "export_3mf", "import_3mf"]

UNITS = ("micron", "millimeter", "centimeter", "inch", "foot", "meter")
"""The units a 3MF model may declare (the coordinates are written unchanged)."""

_CORE_NS = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
_MODEL_TYPE = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"
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
                _meshio.format_rows('     <triangle v1="%d" v2="%d" v3="%d"/>\n', tris, model)
                _meshio.write_part(model, tail)

    return _meshio.save(path, write, "3MF file")


# -- reading ----------------------------------------------------------------------------------
_OBJECT_RE = re.compile(rb"<(?:\w+:)?object\b([^>]*)>(.*?)</(?:\w+:)?object\s*>", re.DOTALL)
_ITEM_RE = re.compile(rb"<(?:\w+:)?item\b([^>]*?)/?>", re.DOTALL)


def _attribute(tag_text: bytes, name: bytes):
    m = re.search(rb"(?:^|\s)" + name + rb"\s*=\s*(\"[^\"]*\"|'[^']*')", tag_text)
    return None if m is None else m.group(1)[1:-1]


def _numbers(block: bytes, tag: bytes, names, dtype, what: str, label: str) -> np.ndarray:
    """``(n, len(names))`` attribute values of every ``<tag .../>`` in ``block``."""
    n = len(re.findall(rb"<(?:\w+:)?" + tag + rb"\b", block))
    columns = []
    for attr in names:
        found = re.findall(rb"<(?:\w+:)?" + tag + rb"\b[^>]*?\s" + attr + rb"\s*=\s*[\"']([^\"']*)[\"']", block)
        if len(found) != n:
            raise FileFormatError(f"{what}: {label}: a <{tag.decode()}> element has no {attr.decode()} attribute")
        columns.append(np.array(found, dtype=bytes) if found else np.zeros(0, "S1"))
    try:
        return np.stack(columns, axis=1).astype(dtype) if n else np.zeros((0, len(names)), dtype)
    except ValueError:
        kind = "number" if np.dtype(dtype).kind == "f" else "integer"
        raise FileFormatError(f"{what}: {label}: a <{tag.decode()}> attribute is not a valid {kind}") from None


def _transform(text, what: str) -> np.ndarray:
    """The 4 x 3 affine matrix of a 3MF ``transform`` attribute (row vectors: p' = [p 1] @ M)."""
    if text is None:
        return np.vstack([np.eye(3), np.zeros(3)])
    try:
        values = np.array(text.split(), dtype=bytes).astype(np.float64)
    except ValueError:
        values = np.zeros(0)
    if values.size != 12 or not np.isfinite(values).all():
        raise FileFormatError(f"{what}: a build item has a malformed transform {text.decode('latin-1')!r} (12 numbers expected)")
    return values.reshape(4, 3)


def import_3mf(path):
    """Read the mesh objects of a 3MF package into one :class:`~splinekit.PolyMesh` of triangles.

    Every build item's object is placed with the item's ``transform``; without build items, every
    mesh object is taken as it is. Objects made of components, missing parts and malformed XML
    raise :class:`~splinekit.errors.FileFormatError`.
    """
    what = f"3MF file {_meshio._fspath(path)!r}"
    raw = _meshio.read_bytes(path, "3MF file")
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as package:
            names = package.namelist()
            target = "3D/3dmodel.model"
            if "_rels/.rels" in names:
                rels = package.read("_rels/.rels")
                for rel in re.findall(rb"<(?:\w+:)?Relationship\b[^>]*>", rels):
                    if _attribute(rel, b"Type") == _MODEL_TYPE.encode():
                        target = _attribute(rel, b"Target").decode("utf-8").lstrip("/")
            if target not in names:
                raise FileFormatError(f"{what}: the package has no model part {target!r}")
            model = package.read(target)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, KeyError) as exc:
        raise FileFormatError(f"{what}: not a readable 3MF (zip) package: {exc}") from None
    objects = {}
    for attrs, body in _OBJECT_RE.findall(model):
        oid = _attribute(attrs, b"id")
        if oid is None:
            raise FileFormatError(f"{what}: an <object> has no id")
        label = f"object {oid.decode('latin-1')}"
        if re.search(rb"<(?:\w+:)?components\b", body):
            raise FileFormatError(f"{what}: {label} is made of components, which import_3mf does not support")
        if not re.search(rb"<(?:\w+:)?mesh\b", body):
            continue
        V = _numbers(body, b"vertex", (b"x", b"y", b"z"), np.float64, what, label)
        T = _numbers(body, b"triangle", (b"v1", b"v2", b"v3"), np.int64, what, label)
        _meshio.finite_or_raise(V, f"{what}: {label}")
        bad = (T < 0) | (T >= len(V))
        if bad.any():
            t = int(np.flatnonzero(bad.any(axis=1))[0])
            raise FileFormatError(f"{what}: {label}: triangle {t} refers to vertex {T[t].tolist()}, outside 0..{len(V) - 1}")
        objects[oid] = (V, T)
    if not objects:
        raise FileFormatError(f"{what}: the model has no mesh object")
    items = [(_attribute(a, b"objectid"), _transform(_attribute(a, b"transform"), what)) for a in _ITEM_RE.findall(model)]
    if not items:
        items = [(oid, _transform(None, what)) for oid in objects]
    parts_v, parts_t, base = [], [], 0
    for oid, M in items:
        if oid not in objects:
            raise FileFormatError(f"{what}: a build item refers to object {oid!r}, which has no mesh")
        V, T = objects[oid]
        parts_v.append(V @ M[:3] + M[3])
        parts_t.append(T + base)
        base += len(V)
    V = np.concatenate(parts_v)
    T = np.concatenate(parts_t)
    return _meshio.build_mesh(V, T.ravel(), np.arange(len(T) + 1, dtype=np.int64) * 3, what)
