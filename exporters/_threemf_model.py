"""Reading the model part of a 3MF package (``3D/3dmodel.model``): the expat parser, the zip
members, the objects, components and build items, and the expanded build's size and order.

The model part is parsed with expat, fed in chunks straight from the zip member, so the XML text
is never held whole; vertex and triangle elements are collected as attribute dicts and turned
into arrays a chunk at a time. A document type declaration is refused outright (as defusedxml's
forbid_dtd does): without one no entity can be declared, so no entity expansion and no external
reference can happen. Expat is linear in the input.
"""

from __future__ import annotations

from itertools import chain
from operator import itemgetter
from xml.parsers import expat

import numpy as np

from splinekit import limits
from splinekit.errors import FileFormatError

# the 3MF core specification's XML namespace and the model part's relationship type (the writer's too)
_CORE_NS = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
_MODEL_TYPE = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"

_CHUNK_BYTES = 1 << 20
MODEL_BYTES_FACTOR = 4
"""Memory charged per byte of (uncompressed) model XML before reading it: the vertex and triangle
arrays (24 bytes for at least 27 bytes of text each), the attribute dicts of one chunk and the
mesh built from them."""
MAX_COMPONENT_DEPTH = 64
"""Deepest nesting of component objects accepted (real files use one or two levels)."""
MAX_RELS_BYTES = 1 << 20
"""Largest ``_rels/.rels`` part accepted (a real one is a few hundred bytes)."""

_CORE = _CORE_NS + " "
_VERTEX = (_CORE + "vertex", "vertex")
_TRIANGLE = (_CORE + "triangle", "triangle")


def _local(name: str):
    """The local name of an element of the core namespace or of no namespace, else None."""
    if name.startswith(_CORE):
        return name[len(_CORE):]
    return None if " " in name else name


class _Model:
    """The parts of a 3MF model document that :func:`import_3mf` uses, filled by expat's
    handlers: per object id its vertex and triangle ranges in the model's running vertex and
    triangle lists, or its components; the build items."""

    def __init__(self, what: str):
        self.what = what
        self.vertex_dicts, self.triangle_dicts = [], []  # of the current chunk
        self.vertex_parts, self.triangle_parts = [], []  # (n, 3) arrays of the chunks so far
        self.n_vertices = self.n_triangles = 0  # flushed so far
        self.objects = {}  # id -> {"mesh": (v0, v1, t0, t1) or None, "components": [(id, transform)]}
        self.items = []  # (object id, transform text)
        self.stack = []  # open structural elements: (local name, data)
        self.parser = None

    # handlers: start() is called for every element, so its common case comes first
    def start(self, name, attrs):
        if name in _VERTEX:
            self.vertex_dicts.append(attrs)
        elif name in _TRIANGLE:
            self.triangle_dicts.append(attrs)
        else:
            local = _local(name)
            if local in ("object", "mesh", "vertices", "triangles", "components", "component", "build", "item"):
                self._open(local, attrs)

    def end(self, name):
        if self.stack and name not in _VERTEX and name not in _TRIANGLE and _local(name) == self.stack[-1][0]:
            self._close(*self.stack.pop())

    def _where(self) -> str:
        p = self.parser
        return f"line {p.CurrentLineNumber}, column {p.CurrentColumnNumber + 1} (byte {p.CurrentByteIndex})"

    def _fail(self, problem: str):
        raise FileFormatError(f"{self.what}: {problem} at {self._where()} of the model part")

    def _open(self, local, attrs):
        parent = self.stack[-1][0] if self.stack else None
        data = None
        if local == "object":
            oid = attrs.get("id")
            if oid is None:
                self._fail("an <object> has no id")
            if oid in self.objects:
                self._fail(f"object id {oid!r} is used twice")
            data = oid
            self.objects[oid] = {"mesh": None, "components": None}
        elif local in ("mesh", "components"):  # an object holds one of them, once
            if parent != "object":
                self._fail(f"a <{local}> outside an <object>")
            data = self.stack[-1][1]
            obj = self.objects[data]
            if obj["mesh"] is not None or obj["components"] is not None:
                self._fail(f"object {data!r} has more than one <mesh> or <components>")
            obj[local] = [None, None] if local == "mesh" else []  # mesh: vertex and triangle ranges
        elif local in ("vertices", "triangles"):
            if parent != "mesh":
                self._fail(f"a <{local}> outside a <mesh>")
            if self.objects[self.stack[-1][1]]["mesh"][0 if local == "vertices" else 1] is not None:
                self._fail(f"a <mesh> has more than one <{local}>")
            data = self._flushed_count(local)
        elif local == "component":
            if parent != "components":
                self._fail("a <component> outside <components>")
            if attrs.get("objectid") is None:
                self._fail("a <component> has no objectid")
            self.objects[self.stack[-1][1]]["components"].append((attrs["objectid"], attrs.get("transform")))
        elif local == "item":
            if parent != "build":
                self._fail("an <item> outside <build>")
            if attrs.get("objectid") is None:
                self._fail("a build <item> has no objectid")
            self.items.append((attrs["objectid"], attrs.get("transform")))
        self.stack.append((local, data))

    def _flushed_count(self, local):
        return self.n_vertices + len(self.vertex_dicts) if local == "vertices" else self.n_triangles + len(self.triangle_dicts)

    def _close(self, local, data):
        if local in ("vertices", "triangles"):
            oid = self.stack[-1][1]  # the enclosing <mesh> holds the object id
            self.objects[oid]["mesh"][0 if local == "vertices" else 1] = (data, self._flushed_count(local))

    def flush(self):
        """Turn the attribute dicts collected so far into arrays."""
        if self.vertex_dicts:
            self.vertex_parts.append(self._array(self.vertex_dicts, ("x", "y", "z"), np.float64, "vertex", self.n_vertices))
            self.n_vertices += len(self.vertex_dicts)
            self.vertex_dicts = []
        if self.triangle_dicts:
            self.triangle_parts.append(self._array(self.triangle_dicts, ("v1", "v2", "v3"), np.int64, "triangle", self.n_triangles))
            self.n_triangles += len(self.triangle_dicts)
            self.triangle_dicts = []

    def _array(self, dicts, keys, dtype, tag, first) -> np.ndarray:
        """``(len(dicts), 3)`` values of the attributes ``keys`` (Python's float()/int() over the
        flat list of strings: a C loop, several times faster than numpy's string casts)."""
        convert = float if dtype is np.float64 else int
        try:
            text = list(chain.from_iterable(map(itemgetter(*keys), dicts)))
        except KeyError:
            k = next(i for i, d in enumerate(dicts) if not all(key in d for key in keys))  # error path only
            missing = next(key for key in keys if key not in dicts[k])
            raise FileFormatError(f"{self.what}: <{tag}> {first + k} of the model has no {missing} attribute") from None
        try:
            return np.array(list(map(convert, text)), dtype=dtype).reshape(-1, 3)
        except (ValueError, OverflowError):
            kind = "number" if dtype is np.float64 else "integer"
            k = next(i for i, t in enumerate(text) if not _parses(t, convert, dtype)) // 3  # error path only
            raise FileFormatError(
                f"{self.what}: <{tag}> {first + k} of the model has an attribute that is not a valid {kind}: "
                f"{text[3 * k:3 * k + 3]}"
            ) from None


def _parses(token: str, convert, dtype) -> bool:
    try:
        np.array([convert(token)], dtype=dtype)
    except (ValueError, OverflowError):
        return False
    return True


class _DoctypeRefused(Exception):
    pass


def _refuse_dtd(*_):
    raise _DoctypeRefused


def _expat(start=None, end=None):
    parser = expat.ParserCreate(namespace_separator=" ")
    parser.StartDoctypeDeclHandler = _refuse_dtd
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    if start is not None:
        parser.StartElementHandler = start
    if end is not None:
        parser.EndElementHandler = end
    return parser


def _parse(parser, chunks, what: str, part: str, after_chunk=None) -> None:
    """Feed ``chunks`` to ``parser``; XML errors and a DTD become FileFormatError naming ``part``."""
    try:
        for chunk in chunks:
            parser.Parse(chunk, False)
            if after_chunk is not None:
                after_chunk()
        parser.Parse(b"", True)
    except expat.ExpatError as exc:
        raise FileFormatError(
            f"{what}: the {part} part is not well-formed XML: {expat.ErrorString(exc.code)} "
            f"at line {exc.lineno}, column {exc.offset + 1} (byte {parser.ErrorByteIndex})"
        ) from None
    except _DoctypeRefused:
        raise FileFormatError(
            f"{what}: the {part} part has a document type declaration (<!DOCTYPE ...>) at line "
            f"{parser.CurrentLineNumber}, which 3MF does not allow (it could declare entities)"
        ) from None


def _member(package, name: str, what: str):
    info = package.getinfo(name)
    if info.flag_bits & 0x1:
        raise FileFormatError(f"{what}: the part {name!r} is encrypted")
    return info


def _chunks(package, info, what: str):
    """The uncompressed bytes of member ``info``, a chunk at a time; never more than the size its
    header declares (a member that inflates past it is refused, so a zip bomb cannot get through
    a check made on the declared size)."""
    total = 0
    with package.open(info) as fh:
        while True:
            chunk = fh.read(_CHUNK_BYTES)
            if not chunk:
                break
            total += len(chunk)
            if total > info.file_size:
                raise FileFormatError(f"{what}: the part {info.filename!r} inflates past the {info.file_size} bytes its header declares")
            yield chunk
    if total != info.file_size:
        raise FileFormatError(f"{what}: the part {info.filename!r} has {total} bytes, its header declares {info.file_size}")


def _model_target(package, names, what: str) -> str:
    """The model part named by ``_rels/.rels`` (default ``3D/3dmodel.model``)."""
    if "_rels/.rels" not in names:
        return "3D/3dmodel.model"
    info = _member(package, "_rels/.rels", what)
    if info.file_size > MAX_RELS_BYTES:
        raise FileFormatError(f"{what}: the _rels/.rels part declares {info.file_size} bytes; at most {MAX_RELS_BYTES} are accepted")
    targets = []

    def start(name, attrs):
        if name.rsplit(" ", 1)[-1] == "Relationship" and attrs.get("Type") == _MODEL_TYPE:
            targets.append(attrs.get("Target"))

    _parse(_expat(start), _chunks(package, info, what), what, "_rels/.rels")
    if not targets:
        return "3D/3dmodel.model"
    if not isinstance(targets[0], str) or not targets[0].strip("/"):
        raise FileFormatError(f"{what}: the model relationship in _rels/.rels has no Target")
    return targets[0].lstrip("/")


def _read_model(package, target: str, what: str) -> _Model:
    info = _member(package, target, what)
    limits.check(info.file_size * MODEL_BYTES_FACTOR, f"reading the {info.file_size}-byte model part of {what}")
    model = _Model(what)
    model.parser = _expat(model.start, model.end)
    _parse(model.parser, _chunks(package, info, what), what, "model", model.flush)
    model.flush()
    return model


def _transform(text, what: str, where: str) -> np.ndarray:
    """The 4 x 4 row-vector affine matrix of a 3MF ``transform`` attribute (p' = [p 1] @ M)."""
    M = np.eye(4)
    if text is None:
        return M
    try:
        values = np.array(text.split()).astype(np.float64)
    except ValueError:
        values = np.zeros(0)
    if values.size != 12 or not np.isfinite(values).all():
        raise FileFormatError(f"{what}: {where} has a malformed transform {text[:200]!r} (12 finite numbers expected)")
    M[:, :3] = values.reshape(4, 3)
    return M


def _sizes(model: _Model, what: str):
    """Per object id ``(vertices, triangles, placements)`` of its full expansion (Python ints, so
    exponential instancing is counted exactly), checking references, cycles and depth."""
    sizes, visiting = {}, set()

    def size(oid, depth):
        if oid in sizes:
            return sizes[oid]
        if oid not in model.objects:
            raise FileFormatError(f"{what}: a build item or component refers to object {oid!r}, which is not defined")
        if oid in visiting:
            raise FileFormatError(f"{what}: object {oid!r} contains itself through its components")
        if depth > MAX_COMPONENT_DEPTH:
            raise FileFormatError(f"{what}: components nest more than {MAX_COMPONENT_DEPTH} levels deep")
        obj = model.objects[oid]
        if obj["mesh"] is not None:
            (v0, v1), (t0, t1) = obj["mesh"][0] or (0, 0), obj["mesh"][1] or (0, 0)
            total = (v1 - v0, t1 - t0, 1 if v1 > v0 else 0)
        else:
            visiting.add(oid)
            total = (0, 0, 0)
            for child, _ in obj["components"] or ():
                n = size(child, depth + 1)
                total = tuple(a + b for a, b in zip(total, n))
            visiting.discard(oid)
        sizes[oid] = total
        return total

    return size


def _parents_first(model: _Model, roots, size) -> list:
    """The object ids reachable from ``roots`` (through components whose expansion has vertices),
    each after every object that contains it (a reverse post-order; cycles are already refused)."""
    post, done = [], set()
    for root in dict.fromkeys(roots):
        if root in done or not size(root, 0)[2]:
            continue
        stack = [(root, iter(_children(model, root, size)))]
        done.add(root)
        while stack:
            oid, children = stack[-1]
            child = next(children, None)
            if child is None:
                post.append(oid)
                stack.pop()
            elif child not in done:
                done.add(child)
                stack.append((child, iter(_children(model, child, size))))
    return post[::-1]


def _children(model: _Model, oid, size) -> list:
    obj = model.objects[oid]
    if obj["mesh"] is not None:
        return []
    return [child for child, _ in obj["components"] or () if size(child, 0)[2]]
