"""glTF 2.0 binary files (``.glb``): one mesh, one node, one scene.

Layout: a 12-byte header (``glTF``, version 2, total length), a JSON chunk (padded with spaces to
4 bytes) and a BIN chunk holding float32 positions (with the ``min``/``max`` the specification
requires), optional float32 unit normals and uint32 triangle indices, each part 4-byte aligned.
glTF meshes are triangles: polygons are fan-triangulated. Coordinates are written as they are
(glTF readers take them as metres, +Y up).

The reader takes the triangle primitives of every node of the default scene, placed by the
node transforms (``matrix`` or translation/rotation/scale), into one mesh.
"""

from __future__ import annotations

import json
import struct

import numpy as np

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
    if np.abs(V).max() > _FLOAT32_MAX:
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
         "min": P.min(axis=0).tolist(), "max": P.max(axis=0).tolist()},
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

    return _meshio.save(path, write, "glTF binary file")


# -- reading ----------------------------------------------------------------------------------
_COMPONENTS = {5120: "i1", 5121: "u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


def _accessor(doc: dict, binary: bytes, k, what: str) -> np.ndarray:
    """``(count, width)`` values of accessor ``k`` (bufferView data, honouring ``byteStride``)."""
    try:
        acc = doc["accessors"][k]
        if "sparse" in acc:
            raise FileFormatError(f"{what}: accessor {k} is sparse, which import_glb does not support")
        dt = np.dtype(_COMPONENTS[acc["componentType"]])
        width = _WIDTH[acc["type"]]
        count = int(acc["count"])
        view = doc["bufferViews"][acc["bufferView"]]
        if view.get("buffer", 0) != 0 or doc["buffers"][0].get("uri") is not None:
            raise FileFormatError(f"{what}: accessor {k} refers to an external buffer, which import_glb does not support")
        start = int(view.get("byteOffset", 0)) + int(acc.get("byteOffset", 0))
        stride = int(view.get("byteStride", 0)) or dt.itemsize * width
        end = int(view.get("byteOffset", 0)) + int(view["byteLength"])
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        if isinstance(exc, FileFormatError):
            raise
        raise FileFormatError(f"{what}: accessor {k} is malformed or refers to a missing buffer view ({exc!r})") from None
    need = start + (count - 1) * stride + dt.itemsize * width if count else start
    if count < 0 or start < 0 or need > min(end, len(binary)):
        raise FileFormatError(f"{what}: accessor {k} reaches past the end of its buffer view or the BIN chunk")
    return np.ndarray((count, width), dtype=dt, buffer=binary, offset=start, strides=(stride, dt.itemsize))


def _node_matrix(node: dict, what: str) -> np.ndarray:
    """The 4 x 4 column-vector transform of a node (``matrix``, or T * R * S)."""
    if "matrix" in node:
        M = np.asarray(node["matrix"], dtype=np.float64)
        if M.shape != (16,):
            raise FileFormatError(f"{what}: a node matrix must have 16 numbers, got {node['matrix']!r}")
        return M.reshape(4, 4).T  # glTF stores column-major
    t = np.asarray(node.get("translation", [0, 0, 0]), dtype=np.float64)
    q = np.asarray(node.get("rotation", [0, 0, 0, 1]), dtype=np.float64)
    norm = np.linalg.norm(q) if q.shape == (4,) else np.nan
    # glTF requires a unit quaternion; a slightly off one is normalized, a zero or broken one refused
    if not (np.isfinite(norm) and norm > 0.5):
        raise FileFormatError(f"{what}: a node rotation must be a unit quaternion (x, y, z, w), got {node['rotation']!r}")
    x, y, z, w = q / norm
    s = np.asarray(node.get("scale", [1, 1, 1]), dtype=np.float64)
    R = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    M = np.eye(4)
    M[:3, :3] = R * s
    M[:3, 3] = t
    return M


def import_glb(path):
    """Read a binary glTF 2.0 file into one :class:`~splinekit.PolyMesh` of triangles.

    Takes every triangle primitive (mode 4) of the meshes reached from the default scene's nodes,
    with the node transforms applied; vertices are not merged (a glTF file may split them at seams).
    Malformed files (bad header or chunk lengths, accessors out of range, unsupported features such
    as external buffers, sparse accessors or Draco compression) raise
    :class:`~splinekit.errors.FileFormatError`.
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
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise FileFormatError(f"{what}: the JSON chunk is not valid JSON: {exc}") from None
    binary = b""
    at = 20 + json_len
    if at + 8 <= len(data):
        bin_len, kind = struct.unpack_from("<II", data, at)
        if kind == _BIN:
            if at + 8 + bin_len > len(data):
                raise FileFormatError(f"{what}: the BIN chunk declares {bin_len} bytes past the end of the file")
            binary = data[at + 8:at + 8 + bin_len]
    if "draco" in json.dumps(doc.get("extensionsRequired", [])).lower():
        raise FileFormatError(f"{what}: Draco-compressed meshes are not supported")
    try:
        scene = doc.get("scenes", [{}])[doc.get("scene", 0)] if doc.get("scenes") else {"nodes": list(range(len(doc.get("nodes", []))))}
        stack = [(n, np.eye(4)) for n in scene.get("nodes", [])]
        parts_v, parts_t, base, seen = [], [], 0, 0
        while stack:
            n, parent = stack.pop(0)
            seen += 1
            if seen > 100_000:
                raise FileFormatError(f"{what}: the node hierarchy has a cycle")
            node = doc["nodes"][n]
            M = parent @ _node_matrix(node, what)
            stack.extend((c, M) for c in node.get("children", []))
            if "mesh" not in node:
                continue
            for prim in doc["meshes"][node["mesh"]]["primitives"]:
                if prim.get("mode", 4) != 4:
                    continue
                P = _accessor(doc, binary, prim["attributes"]["POSITION"], what).astype(np.float64)
                if "indices" in prim:
                    T = _accessor(doc, binary, prim["indices"], what).astype(np.int64).reshape(-1)
                else:
                    T = np.arange(len(P), dtype=np.int64)
                if T.size % 3:
                    raise FileFormatError(f"{what}: a triangle primitive has {T.size} indices, not a multiple of 3")
                if T.size and (T.min() < 0 or T.max() >= len(P)):
                    raise FileFormatError(f"{what}: a primitive's index {int(T.max())} is outside 0..{len(P) - 1}")
                parts_v.append(P @ M[:3, :3].T + M[:3, 3])
                parts_t.append(T + base)
                base += len(P)
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        if isinstance(exc, FileFormatError):
            raise
        raise FileFormatError(f"{what}: malformed glTF document ({type(exc).__name__}: {exc})") from None
    V = np.concatenate(parts_v) if parts_v else np.zeros((0, 3))
    T = np.concatenate(parts_t) if parts_t else np.zeros(0, dtype=np.int64)
    _meshio.finite_or_raise(V, what)
    return _meshio.build_mesh(V, T, np.arange(T.size // 3 + 1, dtype=np.int64) * 3, what)
