"""Small files of every mesh and STEP format, written by hand for the reader tests and the fuzz
suite (plain functions, no fixtures). Import with ``from _readerfiles import ...`` (pytest puts
``tests/`` on ``sys.path``)."""

from __future__ import annotations

import json
import struct
import zipfile

import numpy as np

STEP_HEAD = (
    "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
    "FILE_NAME('x','2020-01-01T00:00:00',(''),(''),'','','');\n"
    "FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\n"
)
STEP_TAIL = "ENDSEC;\nEND-ISO-10303-21;\n"


def nested_step(depth: int) -> str:
    """A syntactically valid STEP file whose one point nests its coordinates ``depth`` lists deep."""
    return STEP_HEAD + "#1=CARTESIAN_POINT(''," + "(" * depth + "0." + ")" * depth + ");\n" + STEP_TAIL


CORE_NS = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
RELS = ('<?xml version="1.0"?><Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
        '<Relationship Target="/3D/3dmodel.model" Id="rel0" '
        'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>')


def write_3mf(path, model, rels=RELS, method=zipfile.ZIP_DEFLATED):
    """A 3MF package whose model part is ``model`` (str, bytes, or an iterable of bytes chunks)."""
    with zipfile.ZipFile(path, "w", compression=method) as z:
        if rels is not None:
            z.writestr("_rels/.rels", rels)
        if isinstance(model, (str, bytes)):
            z.writestr("3D/3dmodel.model", model)
        else:
            with z.open("3D/3dmodel.model", "w", force_zip64=True) as fh:
                for chunk in model:
                    fh.write(chunk)
    return path


def mesh_object(oid, V, T) -> str:
    vs = "".join(f'<vertex x="{x!r}" y="{y!r}" z="{z!r}"/>' for x, y, z in np.asarray(V, dtype=float).tolist())
    ts = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in np.asarray(T).tolist())
    return f'<object id="{oid}" type="model"><mesh><vertices>{vs}</vertices><triangles>{ts}</triangles></mesh></object>'


def model_xml(resources: str, build: str = "") -> str:
    return (f'<?xml version="1.0" encoding="UTF-8"?><model unit="millimeter" xmlns="{CORE_NS}">'
            f"<resources>{resources}</resources><build>{build}</build></model>")


TETRA_V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
TETRA_T = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def glb(doc, binary: bytes = b"") -> bytes:
    """A GLB file of the JSON document ``doc`` (any JSON value, or raw bytes) and a BIN chunk."""
    text = doc if isinstance(doc, bytes) else json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    if binary:
        chunks += struct.pack("<I4s", len(binary), b"BIN\0") + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks


def tetra_gltf(nodes, scene_nodes, n_points: int = 4):
    """A document with one triangle mesh of ``n_points`` points (a fan) and the given nodes."""
    P = np.zeros((n_points, 3), dtype="<f4")
    P[:, 0] = np.arange(n_points)
    P[1::2, 1] = 1.0
    T = np.stack([np.zeros(n_points - 2), np.arange(1, n_points - 1), np.arange(2, n_points)], axis=1).astype("<u4")
    binary = P.tobytes() + T.tobytes()
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": scene_nodes}], "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": P.nbytes},
                        {"buffer": 0, "byteOffset": P.nbytes, "byteLength": T.nbytes}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": n_points, "type": "VEC3"},
                      {"bufferView": 1, "componentType": 5125, "count": T.size, "type": "SCALAR"}],
    }
    return doc, binary


def write_bytes(path, content: bytes):
    path.write_bytes(content)
    return path
