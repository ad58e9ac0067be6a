"""glTF 2.0 binary files (``.glb``): one mesh, one node, one scene.

Layout: a 12-byte header (``glTF``, version 2, total length), a JSON chunk (padded with spaces to
4 bytes) and a BIN chunk holding float32 positions (with the ``min``/``max`` the specification
requires), optional float32 unit normals and uint32 triangle indices, each part 4-byte aligned.
glTF meshes are triangles: polygons are fan-triangulated. Coordinates are written as they are
(glTF readers take them as metres, +Y up).

The reader takes the triangle primitives of every node of the default scene, placed by the
node transforms (``matrix`` or translation/rotation/scale), into one mesh; it checks every JSON
value's type, requires the node hierarchy to be trees, and checks the size of the expanded scene
against the memory budget before expanding it.
"""

from __future__ import annotations

import json
import struct

import numpy as np

from splinekit import limits
from splinekit.errors import ExportError, FileFormatError, ParameterError

from . import _meshio

__all__ = ["export_glb", "import_glb"]

_MAGIC = 0x46546C67  # "glTF"
_JSON = 0x4E4F534A  # "JSON"
_BIN = 0x004E4942  # "BIN\0"
_FLOAT, _UBYTE, _USHORT, _UINT = 5126, 5121, 5123, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_FLOAT32_MAX = float(np.finfo(np.float32).max)


def _chunk(kind: int, payload: bytes, pad: bytes) -> bytes:
    payload = payload + pad * (-len(payload) % 4)
    return struct.pack("<II", len(payload), kind) + payload


def export_glb(path, mesh, normals=True) -> str:
    """Write ``mesh`` as a binary glTF 2.0 file; returns the path written.

    Parameters
    ----------
    path : str or os.PathLike
        The target; written atomically (a temporary file beside it, renamed into place).
    mesh : splinekit.PolyMesh
        3-D vertices and at least one face; polygons are fan-triangulated from their first corner.
    normals : bool
        Also store the angle-weighted unit vertex normals (``NORMAL``); a vertex without one
        (isolated, or on degenerate faces only) gets ``(0, 0, 1)``, since glTF normals must have
        unit length.

    Positions are float32 (coordinates beyond its range raise
    :class:`~splinekit.errors.ExportError`), indices uint32.
    """
    mesh = _meshio.check_mesh(mesh, "export_glb")
    if not isinstance(normals, (bool, np.bool_)):
        raise ParameterError(f"normals must be True or False, got {normals!r}")
    if mesh.n_faces == 0:
        raise ParameterError("export_glb needs a mesh with at least one face, got an empty mesh")
    V = mesh.vertices
    # per-column extremes by a loop over the three columns: numpy's min/max along axis 0 of an
    # (n, 3) array costs about 20 times more (1.3 ms against 60 us for 50k vertices)
    lo = np.array([V[:, c].min() for c in range(3)])
    hi = np.array([V[:, c].max() for c in range(3)])
    if max(-lo.min(), hi.max()) > _FLOAT32_MAX:
        i = int(np.flatnonzero((np.abs(V) > _FLOAT32_MAX).any(axis=1))[0])
        raise ExportError(f"vertex {i} = {V[i].tolist()} is beyond the float32 range of glTF positions")
    if len(V) >= 2**32 - 1:
        raise ExportError(f"{len(V)} vertices do not fit glTF's 32-bit indices")
    P = np.ascontiguousarray(V, dtype="<f4")
    index = np.ascontiguousarray(_meshio.triangles(mesh), dtype="<u4")
    parts = [P]
    if normals:
        N = np.asarray(mesh.vertex_normals, dtype="<f4").copy()
        N[~(np.abs(N).sum(axis=1) > 0)] = (0.0, 0.0, 1.0)
        parts.append(N)
    parts.append(index)
    offsets = np.cumsum([0] + [p.nbytes for p in parts])  # every part is a multiple of 4 bytes

    views = [
        {"buffer": 0, "byteOffset": int(offsets[k]), "byteLength": int(p.nbytes),
         "target": _ELEMENT_ARRAY_BUFFER if p is index else _ARRAY_BUFFER}
        for k, p in enumerate(parts)
    ]
    accessors = [
        {"bufferView": 0, "componentType": _FLOAT, "count": len(P), "type": "VEC3",
         # rounding to float32 keeps the order: the extremes of P are those of V, rounded
         "min": lo.astype("<f4").tolist(), "max": hi.astype("<f4").tolist()},
    ]
    attributes = {"POSITION": 0}
    if normals:
        accessors.append({"bufferView": 1, "componentType": _FLOAT, "count": len(P), "type": "VEC3"})
        attributes["NORMAL"] = 1
    accessors.append({"bufferView": len(parts) - 1, "componentType": _UINT, "count": int(index.size), "type": "SCALAR"})
    document = {
        "asset": {"version": "2.0", "generator": "splinekit"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": attributes, "indices": len(accessors) - 1, "mode": 4}]}],
        "buffers": [{"byteLength": int(offsets[-1])}],
        "bufferViews": views,
        "accessors": accessors,
    }
    json_chunk = _chunk(_JSON, json.dumps(document, separators=(",", ":")).encode("utf-8"), b" ")
    bin_header = struct.pack("<II", int(offsets[-1]), _BIN)
    total = 12 + len(json_chunk) + len(bin_header) + int(offsets[-1])

    def write(fh):
        _meshio.write_part(fh, struct.pack("<III", _MAGIC, 2, total) + json_chunk + bin_header)
        for p in parts:
            _meshio.write_part(fh, p)

    return _meshio.save(path, write, "glTF binary file", size=total)


# -- reading ----------------------------------------------------------------------------------
# The JSON document is untrusted: every value is checked for its type and range before use
# (a helper per kind below), so a malformed file raises FileFormatError, never AttributeError,
# TypeError or RecursionError, and no Python negative index wraps around.
_COMPONENTS = {5120: "i1", 5121: "u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_INDEX_TYPES = (_UBYTE, _USHORT, _UINT)
BYTES_PER_VERTEX = 64
"""Memory charged per vertex of the expanded scene (float64 position, its transformed copy and the
mesh built from it)."""
BYTES_PER_INDEX = 56
"""Memory charged per triangle corner of the expanded scene (indices and mesh topology)."""
BYTES_PER_PLACEMENT = 1024
"""Memory (and work) charged per placed primitive, so that millions of tiny copies are refused too."""


class _Doc:
    """Typed access to a glTF JSON document; every failure names the file and the JSON path."""

    def __init__(self, doc, what: str):
        self.what = what
        if not isinstance(doc, dict):
            self.fail("the JSON document", "must be an object")
        self.doc = doc

    def fail(self, where: str, problem: str):
        raise FileFormatError(f"{self.what}: {where} {problem}")

    def list(self, container: dict, key: str, where: str) -> list:
        value = container.get(key, [])
        if not isinstance(value, list):
            self.fail(f"{where}.{key}", f"must be an array, got {type(value).__name__}")
        return value

    def obj(self, value, where: str) -> dict:
        if not isinstance(value, dict):
            self.fail(where, f"must be an object, got {type(value).__name__}")
        return value

    def int(self, value, where: str, lo: int = 0, hi: int | None = None) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < lo or (hi is not None and value > hi):
            bound = f"{lo}..{hi}" if hi is not None else f">= {lo}"
            self.fail(where, f"must be an integer {bound}, got {value!r:.80}")
        return value

    def index(self, value, array: str, where: str) -> int:
        """``value`` as an index into the top-level array ``array`` (which must exist)."""
        n = len(self.list(self.doc, array, "glTF"))
        if n == 0:
            self.fail(where, f"refers to {array}[{value!r:.40}], but the document has no {array}")
        return self.int(value, f"{where} (an index into {array})", 0, n - 1)

    def numbers(self, value, n: int, where: str) -> np.ndarray:
        ok = isinstance(value, list) and len(value) == n and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        out = np.array(value, dtype=np.float64) if ok else None
        if out is None or not np.isfinite(out).all():
            self.fail(where, f"must be {n} finite numbers, got {value!r:.200}")
        return out


def _accessor(d: _Doc, binary: bytes, k: int, cache: dict) -> tuple:
    """``(count, dtype, width, offset, stride)`` of accessor ``k``, its data checked to lie inside
    its buffer view and the BIN chunk (cached per accessor)."""
    if k in cache:
        return cache[k]
    where = f"accessor {k}"
    acc = d.obj(d.doc["accessors"][k], where)
    if "sparse" in acc:
        d.fail(where, "is sparse, which import_glb does not support")
    if acc.get("normalized", False) is not False:
        d.fail(where, "is normalized, which import_glb does not support")
    ctype = acc.get("componentType")
    if isinstance(ctype, bool) or not isinstance(ctype, int) or ctype not in _COMPONENTS:
        d.fail(f"{where}.componentType", f"must be one of {sorted(_COMPONENTS)}, got {ctype!r:.40}")
    kind = acc.get("type")
    if not isinstance(kind, str) or kind not in _WIDTH:
        d.fail(f"{where}.type", f"must be one of {', '.join(_WIDTH)}, got {kind!r:.40}")
    dt, width = np.dtype(_COMPONENTS[ctype]), _WIDTH[kind]
    count = d.int(acc.get("count"), f"{where}.count")
    if "bufferView" not in acc:
        d.fail(where, "has no bufferView (an all-zero accessor), which import_glb does not support")
    v = d.index(acc["bufferView"], "bufferViews", f"{where}.bufferView")
    view = d.obj(d.doc["bufferViews"][v], f"bufferViews[{v}]")
    buffers = d.list(d.doc, "buffers", "glTF")
    if d.index(view.get("buffer"), "buffers", f"bufferViews[{v}].buffer") != 0 or \
            d.obj(buffers[0], "buffers[0]").get("uri") is not None:
        d.fail(where, "refers to an external buffer, which import_glb does not support")
    view_start = d.int(view.get("byteOffset", 0), f"bufferViews[{v}].byteOffset")
    view_length = d.int(view.get("byteLength"), f"bufferViews[{v}].byteLength")
    start = view_start + d.int(acc.get("byteOffset", 0), f"{where}.byteOffset")
    element = dt.itemsize * width
    stride = d.int(view.get("byteStride", 0), f"bufferViews[{v}].byteStride", 0, 252) or element
    if stride < element:
        d.fail(f"bufferViews[{v}].byteStride", f"is {stride}, less than the {element} bytes of one element of {where}")
    need = start + (count - 1) * stride + element if count else start
    if need > min(view_start + view_length, len(binary)):
        d.fail(where, "reaches past the end of its buffer view or the BIN chunk")
    cache[k] = (count, dt, width, start, stride)
    return cache[k]


def _values(binary: bytes, spec: tuple) -> np.ndarray:
    count, dt, width, start, stride = spec
    return np.ndarray((count, width), dtype=dt, buffer=binary, offset=start, strides=(stride, dt.itemsize))


def _node_matrix(d: _Doc, node: dict, where: str) -> np.ndarray:
    """The 4 x 4 column-vector transform of a node (``matrix``, or T * R * S)."""
    if "matrix" in node:
        return d.numbers(node["matrix"], 16, f"{where}.matrix").reshape(4, 4).T  # glTF stores column-major
    t = d.numbers(node.get("translation", [0, 0, 0]), 3, f"{where}.translation")
    q = node.get("rotation", [0, 0, 0, 1])
    ok = isinstance(q, list) and len(q) == 4 and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in q)
    norm = np.linalg.norm(np.array(q, dtype=np.float64)) if ok else np.nan
    # glTF requires a unit quaternion; a slightly off one is normalized, a zero or broken one refused
    if not (np.isfinite(norm) and norm > 0.5):
        d.fail(f"{where}.rotation", f"must be a unit quaternion (x, y, z, w), got {q!r:.200}")
    x, y, z, w = np.array(q, dtype=np.float64) / norm
    s = d.numbers(node.get("scale", [1, 1, 1]), 3, f"{where}.scale")
    R = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    M = np.eye(4)
    M[:3, :3] = R * s
    M[:3, 3] = t
    return M


def _scene_nodes(d: _Doc) -> list:
    """``(node index, world matrix)`` of every node of the default scene, parents first.

    glTF requires the node hierarchy to be disjoint trees: a node that is the child of two nodes,
    listed twice, or its own ancestor is refused (such a graph would let a few KB of JSON place
    a mesh exponentially many times). The walk is iterative, so depth is no limit.
    """
    nodes = d.list(d.doc, "nodes", "glTF")
    parent = {}
    for i, node in enumerate(nodes):
        for c in d.list(d.obj(node, f"nodes[{i}]"), "children", f"nodes[{i}]"):
            c = d.index(c, "nodes", f"nodes[{i}].children")
            if c in parent:
                d.fail(f"nodes[{c}]", f"is a child of nodes[{parent[c]}] and nodes[{i}]; glTF nodes form trees")
            parent[c] = i
    scenes = d.list(d.doc, "scenes", "glTF")
    if scenes:
        s = d.index(d.doc.get("scene", 0), "scenes", "glTF.scene")
        roots = [d.index(n, "nodes", f"scenes[{s}].nodes") for n in d.list(d.obj(scenes[s], f"scenes[{s}]"), "nodes", f"scenes[{s}]")]
    else:  # no scene: every root node
        roots = [i for i in range(len(nodes)) if i not in parent]
    out, seen = [], set()
    stack = [(n, np.eye(4)) for n in reversed(roots)]
    while stack:
        n, M = stack.pop()
        if n in seen:
            d.fail(f"nodes[{n}]", "is reached twice from the scene (listed twice, or its own ancestor); glTF nodes form trees")
        seen.add(n)
        with np.errstate(over="ignore", invalid="ignore"):
            W = M @ _node_matrix(d, nodes[n], f"nodes[{n}]")
        out.append((n, W))
        stack.extend((c, W) for c in reversed(nodes[n].get("children", [])))
    return out


def import_glb(path):
    """Read a binary glTF 2.0 file into one :class:`~splinekit.PolyMesh` of triangles.

    Takes every triangle primitive (mode 4) of the meshes reached from the default scene's nodes,
    with the node transforms applied; vertices are not merged (a glTF file may split them at seams).
    The size of the expanded scene (every placed primitive) is estimated before anything is copied
    and checked against the memory budget (:func:`splinekit.limits.check`).

    Malformed files (bad header or chunk lengths, JSON of the wrong types or shape, indices out of
    range, a node graph that is not a set of trees, accessors out of range, non-finite results,
    unsupported features such as external buffers, sparse accessors or Draco compression) raise
    :class:`~splinekit.errors.FileFormatError` naming the file and the JSON element;
    :class:`~splinekit.errors.ResourceLimitError` when the expansion exceeds the budget.
    """
    data = _meshio.read_bytes(path, "glTF binary file")
    what = f"glTF binary file {_meshio._fspath(path)!r}"
    if len(data) < 20:
        raise FileFormatError(f"{what}: {len(data)} bytes is too short for a GLB header (truncated file?)")
    magic, version, total = struct.unpack_from("<III", data, 0)
    if magic != _MAGIC:
        raise FileFormatError(f"{what}: not a GLB file (magic {data[:4]!r}, expected b'glTF')")
    if version != 2:
        raise FileFormatError(f"{what}: glTF version {version}; only version 2 is supported")
    if total != len(data):
        raise FileFormatError(f"{what}: the header declares {total} bytes but the file has {len(data)} (truncated file?)")
    json_len, kind = struct.unpack_from("<II", data, 12)
    if kind != _JSON or 20 + json_len > len(data):
        raise FileFormatError(f"{what}: the first chunk must be JSON and fit in the file")
    try:
        doc = json.loads(data[20:20 + json_len].decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:  # JSONDecodeError is a ValueError
        reason = "it nests too deeply" if isinstance(exc, RecursionError) else str(exc)
        raise FileFormatError(f"{what}: the JSON chunk is not valid JSON: {reason}") from None
    binary = b""
    at = 20 + json_len
    if at + 8 <= len(data):
        bin_len, kind = struct.unpack_from("<II", data, at)
        if kind == _BIN:
            if at + 8 + bin_len > len(data):
                raise FileFormatError(f"{what}: the BIN chunk declares {bin_len} bytes past the end of the file")
            binary = data[at + 8:at + 8 + bin_len]
    d = _Doc(doc, what)
    for ext in d.list(doc, "extensionsRequired", "glTF"):
        if not isinstance(ext, str) or "draco" in ext.lower() or "meshopt" in ext.lower():
            d.fail("glTF.extensionsRequired", f"names {ext!r:.80}: compressed meshes are not supported (Draco, meshopt)")

    # every placed primitive, grouped by its (position, index) accessors, before reading any data
    groups: dict = {}
    cache: dict = {}
    n_vertices = n_corners = n_placements = 0
    for n, W in _scene_nodes(d):
        node = doc["nodes"][n]
        if "mesh" not in node:
            continue
        m = d.index(node["mesh"], "meshes", f"nodes[{n}].mesh")
        mesh = d.obj(doc["meshes"][m], f"meshes[{m}]")
        for p, prim in enumerate(d.list(mesh, "primitives", f"meshes[{m}]")):
            where = f"meshes[{m}].primitives[{p}]"
            prim = d.obj(prim, where)
            if d.int(prim.get("mode", 4), f"{where}.mode") != 4:
                continue
            attributes = d.obj(prim.get("attributes"), f"{where}.attributes")
            if "POSITION" not in attributes:
                d.fail(f"{where}.attributes", "has no POSITION")
            pos = d.index(attributes["POSITION"], "accessors", f"{where}.attributes.POSITION")
            spec = _accessor(d, binary, pos, cache)
            if spec[2] != 3:
                d.fail(f"accessor {pos}", "holds POSITION, which must be of type VEC3")
            idx = None
            if "indices" in prim:
                idx = d.index(prim["indices"], "accessors", f"{where}.indices")
                ispec = _accessor(d, binary, idx, cache)
                if ispec[2] != 1 or doc["accessors"][idx]["componentType"] not in _INDEX_TYPES:
                    d.fail(f"accessor {idx}", "holds indices, which must be SCALAR unsigned integers")
                corners = ispec[0]
            else:
                corners = spec[0]
            if corners % 3:
                d.fail(where, f"is a triangle primitive with {corners} indices, not a multiple of 3")
            groups.setdefault((pos, idx), []).append(W)
            n_vertices, n_corners, n_placements = n_vertices + spec[0], n_corners + corners, n_placements + 1
    limits.check(
        n_vertices * BYTES_PER_VERTEX + n_corners * BYTES_PER_INDEX + n_placements * BYTES_PER_PLACEMENT,
        f"expanding the scene of {what} ({n_vertices} vertices, {n_corners // 3} triangles in {n_placements} placed primitives)",
    )

    parts_v, parts_t, base = [], [], 0
    for (pos, idx), matrices in groups.items():
        P = _values(binary, cache[pos]).astype(np.float64)
        if idx is not None:
            T = _values(binary, cache[idx]).astype(np.int64).reshape(-1)
            if T.size and T.max() >= len(P):
                d.fail(f"accessor {idx}", f"holds the index {int(T.max())}, outside 0..{len(P) - 1} of accessor {pos}")
        else:
            T = np.arange(len(P), dtype=np.int64)
        W = np.stack(matrices)  # (k, 4, 4)
        with np.errstate(over="ignore", invalid="ignore"):
            X = np.einsum("vj,kij->kvi", P, W[:, :3, :3]) + W[:, None, :3, 3]  # (k, nv, 3)
        parts_v.append(X.reshape(-1, 3))
        parts_t.append((T[None] + (base + np.arange(len(W)) * len(P))[:, None]).reshape(-1))
        base += len(W) * len(P)
    V = np.concatenate(parts_v) if parts_v else np.zeros((0, 3))
    T = np.concatenate(parts_t) if parts_t else np.zeros(0, dtype=np.int64)
    _meshio.finite_or_raise(V, what)
    return _meshio.build_mesh(V, T, np.arange(T.size // 3 + 1, dtype=np.int64) * 3, what)


_meshio.register("glb", export_glb, import_glb)
