"""Mesh writers and readers (exporters: STL, OBJ, PLY, 3MF, glTF binary).

Checked against things other than the code under test:

- round trips give back the same vertices and faces: exactly for OBJ, PLY and ASCII STL (float64
  written as shortest round-trip text or as doubles), to float32 for binary STL; vertices of
  formats that merge or reorder are matched to the originals by exact row lookup;
- an independent reader (trimesh; the standard library's zipfile / ElementTree / struct for the
  byte layouts) loads every written file and finds the same counts, volume and bounds;
- files written by hand in the tests (a binary STL whose header starts with "solid", OBJ with
  negative and v/vt/vn indices, big-endian and ASCII PLY with extra properties) read correctly;
- atomic writing: a write that fails midway leaves an existing target byte-for-byte intact and
  no temporary file; unwritable folders, unsupported suffixes and malformed files raise the
  documented errors.
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import exporters
from exporters import _meshio
from splinekit.errors import (
    ExportError,
    FileFormatError,
    MeshTopologyError,
    ParameterError,
    SplineKitError,
)
from splinekit.mesh import PolyMesh, primitives

FORMATS = [".stl", ".obj", ".ply", ".3mf", ".glb"]


# -- helpers ------------------------------------------------------------------------------------
def mixed_mesh() -> PolyMesh:
    """An open, consistently oriented mesh with a pentagon, quads and triangles (a 'house' strip)."""
    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [0, 1, 0], [0.5, 1.8, 0.1], [1.5, 1.7, -0.2]],
                 dtype=np.float64)
    faces = [[0, 1, 4, 6, 5], [1, 2, 3, 4], [4, 3, 7], [4, 7, 6]]
    return PolyMesh(V, faces)


def random_coordinates(mesh: PolyMesh, seed: int, spread: int = 30) -> PolyMesh:
    """Same connectivity, vertices with random mantissas and exponents (hard cases for text)."""
    rng = np.random.default_rng(seed)
    V = rng.standard_normal(mesh.vertices.shape) * 10.0 ** rng.integers(-spread, spread, mesh.vertices.shape)
    return mesh.with_vertices(V)


def row_lookup(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``p`` with ``A[p] == B`` exactly (rows of B found in A); fails if any row is missing."""
    keys = {tuple(r): i for i, r in enumerate(A.tolist())}
    missing = [tuple(r) for r in B.tolist() if tuple(r) not in keys]
    assert not missing, f"{len(missing)} rows not found, e.g. {missing[:2]}"
    return np.array([keys[tuple(r)] for r in B.tolist()], dtype=np.int64)


def canonical_faces(faces_flat: np.ndarray, offsets: np.ndarray) -> set:
    """Faces as a set of tuples, each rotated to start at its smallest index (orientation kept)."""
    out = set()
    for f in range(len(offsets) - 1):
        face = [int(v) for v in faces_flat[offsets[f]:offsets[f + 1]]]
        k = face.index(min(face))
        out.add(tuple(face[k:] + face[:k]))
    return out


def fan_triangles(mesh: PolyMesh) -> np.ndarray:
    """The fan triangulation written by the triangle formats, computed here from the faces."""
    tris = []
    for f in range(mesh.n_faces):
        face = mesh.face_indices[mesh.face_offsets[f]:mesh.face_offsets[f + 1]]
        tris += [(face[0], face[j], face[j + 1]) for j in range(1, len(face) - 1)]
    return np.array(tris, dtype=np.int64).reshape(-1, 3)


def angle_weighted_normals(mesh: PolyMesh) -> np.ndarray:
    """Unit vertex normals, sum over faces of (corner angle) x (unit normal of the face's vector
    area), computed face by face here (zero at vertices with no faces)."""
    V = mesh.vertices
    N = np.zeros_like(V)
    for face in mesh.faces:
        P = V[face]
        area = 0.5 * sum(np.cross(P[0], P[j]) + np.cross(P[j], P[j + 1]) + np.cross(P[j + 1], P[0])
                         for j in range(1, len(face) - 1))
        n = area / np.linalg.norm(area)
        for k, v in enumerate(face):
            a, b = P[(k + 1) % len(face)] - P[k], P[k - 1] - P[k]
            N[v] += np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b) * n
    length = np.linalg.norm(N, axis=1, keepdims=True)
    return np.divide(N, length, out=np.zeros_like(N), where=length > 0)


def assert_same_polygons(got: PolyMesh, want_vertices: np.ndarray, want_flat, want_offsets) -> None:
    """``got`` has exactly the vertices ``want_vertices`` (any order) and the same faces."""
    assert got.vertices.shape == want_vertices.shape
    p = row_lookup(want_vertices, got.vertices)  # got vertex i is want vertex p[i]
    assert np.array_equal(want_vertices[p], got.vertices)
    assert canonical_faces(p[got.face_indices], got.face_offsets) == canonical_faces(np.asarray(want_flat), np.asarray(want_offsets))


def stl_reference_volume(V: np.ndarray, tris: np.ndarray) -> float:
    a, b, c = V[tris[:, 0]], V[tris[:, 1]], V[tris[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def folder_listing(path) -> list:
    return sorted(os.listdir(os.path.dirname(path)))


@pytest.fixture(params=["icosphere", "torus", "box", "mixed"])
def mesh(request):
    return {
        "icosphere": lambda: primitives.icosphere(2, radius=1.5, center=(0.1, -0.2, 0.3)),
        "torus": lambda: primitives.torus(12, 7, R=2.0, r=0.5),
        "box": lambda: primitives.box((1.0, 2.0, 3.0), center=(0.5, 0.25, -1.0)),
        "mixed": mixed_mesh,
    }[request.param]()


# -- exact round trips --------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["obj", "obj-no-normals", "ply-binary", "ply-ascii"])
def test_polygon_round_trip_is_exact(tmp_path, mesh, kind):
    mesh = random_coordinates(mesh, seed=len(kind))
    path = tmp_path / f"m.{kind[:3]}"
    if kind.startswith("obj"):
        exporters.export_obj(path, mesh, normals=kind == "obj")
    else:
        exporters.export_ply(path, mesh, binary=kind == "ply-binary")
    got = exporters.import_mesh(path)
    # polygons kept, vertices in order: the very same mesh, bit for bit
    assert np.array_equal(got.vertices, mesh.vertices)
    assert np.array_equal(got.face_offsets, mesh.face_offsets)
    assert np.array_equal(got.face_indices, mesh.face_indices)


def test_ascii_stl_round_trip_is_exact(tmp_path, mesh):
    mesh = random_coordinates(mesh, seed=3)
    path = tmp_path / "m.stl"
    exporters.export_stl(path, mesh, binary=False, name="part 7")
    assert path.read_bytes().startswith(b"solid part 7\n")
    got = exporters.import_stl(path)
    tris = fan_triangles(mesh)
    assert_same_polygons(got, mesh.vertices, tris.ravel(), np.arange(len(tris) + 1) * 3)


def test_binary_stl_round_trip_to_float32(tmp_path, mesh):
    path = tmp_path / "m.stl"
    exporters.export_stl(path, mesh)
    got = exporters.import_stl(path)
    V32 = mesh.vertices.astype(np.float32).astype(np.float64)
    tris = fan_triangles(mesh)
    assert_same_polygons(got, V32, tris.ravel(), np.arange(len(tris) + 1) * 3)
    assert np.abs(got.vertices - mesh.vertices[row_lookup(V32, got.vertices)]).max() <= 1e-7 * np.abs(mesh.vertices).max()


@settings(max_examples=25, deadline=None)
@given(coords=hnp.arrays(np.float64, (8, 3), elements=st.floats(allow_nan=False, allow_infinity=False, width=64)))
def test_text_formats_round_trip_any_float64(coords):
    """Any finite float64 (subnormals, extremes, -0.0) survives OBJ, ASCII PLY and ASCII STL text."""
    mesh = mixed_mesh().with_vertices(coords)
    with tempfile.TemporaryDirectory() as folder:
        for name, write in (("a.obj", exporters.export_obj), ("a.ply", lambda p, m: exporters.export_ply(p, m, binary=False))):
            path = os.path.join(folder, name)
            write(path, mesh)
            got = exporters.import_mesh(path)
            assert np.array_equal(got.vertices.view(np.uint64), mesh.vertices.view(np.uint64))  # bits, even -0.0
            assert got == mesh
        if len(np.unique(coords + 0.0, axis=0)) == len(coords):  # STL merges equal positions
            path = os.path.join(folder, "a.stl")
            exporters.export_stl(path, mesh, binary=False)
            got = exporters.import_stl(path)
            tris = fan_triangles(mesh)
            assert_same_polygons(got, mesh.vertices + 0.0, tris.ravel(), np.arange(len(tris) + 1) * 3)


def test_written_normals_are_the_angle_weighted_vertex_normals(tmp_path, mesh):
    """OBJ ``vn`` lines (read here as text) and the glTF NORMAL accessor hold the angle-weighted unit
    normal of each vertex, computed independently above; on the sphere they are nearly radial."""
    want = angle_weighted_normals(mesh)
    exporters.export_obj(tmp_path / "n.obj", mesh)
    lines = (tmp_path / "n.obj").read_text().splitlines()
    vn = np.array([[float(t) for t in line.split()[1:]] for line in lines if line.startswith("vn ")])
    assert vn.shape == mesh.vertices.shape
    assert np.abs(vn - want).max() <= 1e-12
    faces = [line.split()[1:] for line in lines if line.startswith("f ")]
    assert all(c.split("//")[0] == c.split("//")[1] for f in faces for c in f)  # vertex k uses normal k
    exporters.export_glb(tmp_path / "n.glb", mesh)
    data = (tmp_path / "n.glb").read_bytes()
    doc = json.loads(data[20:20 + struct.unpack_from("<I", data, 12)[0]])
    blob = data[28 + struct.unpack_from("<I", data, 12)[0]:]
    acc = doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"]]
    view = doc["bufferViews"][acc["bufferView"]]
    N = np.frombuffer(blob, dtype="<f4", count=3 * acc["count"], offset=view["byteOffset"]).reshape(-1, 3)
    assert np.abs(N - want).max() <= 1e-7  # float32
    if mesh.n_faces == primitives.icosphere(2).n_faces:  # the sphere centred at (0.1, -0.2, 0.3)
        radial = mesh.vertices - [0.1, -0.2, 0.3]
        radial /= np.linalg.norm(radial, axis=1, keepdims=True)
        assert np.einsum("ij,ij->i", vn, radial).min() > 0.99


# -- an independent reader: trimesh -------------------------------------------------------------
@pytest.mark.parametrize("suffix", FORMATS)
def test_trimesh_reads_what_we_write(tmp_path, mesh, suffix):
    import trimesh  # the test extra installs it: no skip
    if suffix == ".3mf":
        import lxml  # noqa: F401  (trimesh's 3MF loader needs it)
    path = tmp_path / f"m{suffix}"
    # trimesh's binary PLY reader assumes one face size (test_binary_ply_layout checks mixed ones)
    options = {"binary": False} if suffix == ".ply" and not mesh.topology.is_uniform else {}
    exporters.export_mesh(path, mesh, **options)
    loaded = trimesh.load(str(path), force="mesh", process=suffix in (".stl",))  # STL: merge vertices
    tris = fan_triangles(mesh)
    assert len(loaded.vertices) == mesh.n_vertices
    assert len(loaded.faces) == len(tris)
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    assert np.allclose(loaded.bounds, [lo, hi], rtol=0, atol=1e-6)
    if mesh.is_closed:
        assert loaded.is_watertight
        assert loaded.volume == pytest.approx(stl_reference_volume(mesh.vertices, tris), rel=1e-6)
    else:
        assert loaded.area == pytest.approx(mesh.area, rel=1e-6)


def test_trimesh_reads_ascii_formats(tmp_path):
    import trimesh  # the test extra installs it: no skip
    mesh = primitives.torus(10, 6)
    exporters.export_stl(tmp_path / "a.stl", mesh, binary=False)
    exporters.export_ply(tmp_path / "a.ply", mesh, binary=False)
    for name in ("a.stl", "a.ply"):
        loaded = trimesh.load(str(tmp_path / name), force="mesh")
        assert loaded.is_watertight
        assert loaded.volume == pytest.approx(stl_reference_volume(mesh.vertices, fan_triangles(mesh)), rel=1e-12)


def test_we_read_what_trimesh_writes(tmp_path):
    import trimesh  # the test extra installs it: no skip
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=2.0)
    for name, kwargs in (("t.stl", {}), ("ta.stl", {"file_type": "stl_ascii"}), ("t.ply", {}),
                         ("ta.ply", {"encoding": "ascii"}), ("t.obj", {}), ("t.glb", {})):
        sphere.export(str(tmp_path / name), **kwargs)
        got = exporters.import_mesh(tmp_path / name)
        assert got.n_faces == len(sphere.faces), name
        if name.endswith(".glb"):
            continue  # glTF keeps trimesh's vertices unmerged (trimesh may split them)
        assert got.n_vertices == len(sphere.vertices), name
        assert got.is_closed
        assert got.volume == pytest.approx(sphere.volume, rel=1e-6), name


# -- closed meshes stay closed ------------------------------------------------------------------
@pytest.mark.parametrize("make", [lambda: primitives.icosphere(3), lambda: primitives.torus(24, 9)])
@pytest.mark.parametrize("binary", [True, False])
def test_closed_mesh_stays_watertight_through_stl(tmp_path, make, binary):
    mesh = make()
    exporters.export_stl(tmp_path / "c.stl", mesh, binary=binary)
    got = exporters.import_stl(tmp_path / "c.stl")
    assert got.is_closed
    assert got.euler_characteristic == mesh.euler_characteristic
    assert got.n_vertices == mesh.n_vertices
    assert len(got.edges) == 3 * got.n_faces // 2
    assert got.volume == pytest.approx(mesh.volume, rel=1e-6)


# -- byte layouts, read with the standard library -----------------------------------------------
def test_binary_stl_layout(tmp_path):
    mesh = primitives.box(2.0)
    path = tmp_path / "b.stl"
    exporters.export_stl(path, mesh, name="cube")
    data = path.read_bytes()
    n = struct.unpack_from("<I", data, 80)[0]
    assert n == 12 and len(data) == 84 + 50 * n
    assert not data.startswith(b"solid")  # other readers would take it for ASCII
    rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("p", "<f4", (3, 3)), ("a", "<u2")]), offset=84)
    assert (rec["a"] == 0).all()
    tris = fan_triangles(mesh)
    assert np.array_equal(rec["p"], mesh.vertices[tris].astype(np.float32))
    P = mesh.vertices[tris]
    normals = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    assert np.allclose(rec["n"], normals, atol=1e-7)


@pytest.mark.parametrize("numba", ["0", "1"])
def test_binary_stl_large_mesh_both_paths(tmp_path, monkeypatch, numba):
    """Above the compiled-kernel threshold: same layout and values with and without numba."""
    monkeypatch.setenv("SPLINEKIT_NUMBA", numba)
    mesh = primitives.icosphere(5, radius=3.0)
    assert mesh.n_faces >= _meshio.MIN_COMPILED_TRIANGLES
    # numba is a core dependency: the flag alone decides which path writes the records
    assert (_meshio.stl_fill_kernel(mesh.n_faces) is not None) == (numba == "1")
    assert _meshio.stl_fill_kernel(_meshio.MIN_COMPILED_TRIANGLES - 1) is None
    exporters.export_stl(tmp_path / "big.stl", mesh)
    rec = np.frombuffer((tmp_path / "big.stl").read_bytes(), offset=84,
                        dtype=np.dtype([("n", "<f4", 3), ("p", "<f4", (3, 3)), ("a", "<u2")]))
    P = mesh.vertices.astype(np.float32)[mesh.faces]
    assert np.array_equal(rec["p"], P)
    # the normal of the float64 triangle, rounded to float32 (within half a float32 ulp of 1)
    P64 = mesh.vertices[mesh.faces]
    normals = np.cross(P64[:, 1] - P64[:, 0], P64[:, 2] - P64[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    assert np.abs(rec["n"] - normals).max() <= 6e-8
    # outward on a sphere centred at the origin
    assert (np.einsum("ij,ij->i", rec["n"], P64.mean(axis=1)) > 0).all()


def test_binary_stl_paths_give_identical_bytes(tmp_path, monkeypatch):
    mesh = primitives.icosphere(5)
    outputs = []
    for flag in ("0", "1"):
        monkeypatch.setenv("SPLINEKIT_NUMBA", flag)
        exporters.export_stl(tmp_path / f"{flag}.stl", mesh)
        outputs.append((tmp_path / f"{flag}.stl").read_bytes())
    assert outputs[0] == outputs[1]


def test_binary_ply_layout(tmp_path):
    """Read back a binary PLY of mixed polygons with struct, one record at a time."""
    mesh = random_coordinates(mixed_mesh(), seed=5)
    exporters.export_ply(tmp_path / "m.ply", mesh)
    data = (tmp_path / "m.ply").read_bytes()
    start = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:start].decode().splitlines()
    assert header[:2] == ["ply", "format binary_little_endian 1.0"]
    assert "element vertex 8" in header and "element face 4" in header
    assert "property list uchar int vertex_indices" in header
    V = np.frombuffer(data, dtype="<f8", count=24, offset=start).reshape(8, 3)
    assert np.array_equal(V, mesh.vertices)
    at, faces = start + 24 * 8, []
    for _ in range(4):
        (k,) = struct.unpack_from("<B", data, at)
        faces.append(list(struct.unpack_from(f"<{k}i", data, at + 1)))
        at += 1 + 4 * k
    assert at == len(data)
    assert faces == [f.tolist() for f in mesh.faces]


def test_glb_layout(tmp_path):
    mesh = mixed_mesh()
    path = tmp_path / "m.glb"
    exporters.export_glb(path, mesh)
    data = path.read_bytes()
    magic, version, total = struct.unpack_from("<4sII", data)
    assert (magic, version, total) == (b"glTF", 2, len(data))
    json_len, json_kind = struct.unpack_from("<I4s", data, 12)
    assert json_kind == b"JSON" and json_len % 4 == 0
    doc = json.loads(data[20:20 + json_len])
    bin_len, bin_kind = struct.unpack_from("<I4s", data, 20 + json_len)
    assert bin_kind == b"BIN\0" and bin_len % 4 == 0 and 28 + json_len + bin_len == len(data)
    blob = data[28 + json_len:]
    prim = doc["meshes"][0]["primitives"][0]

    def accessor(k, dtype, width):
        acc = doc["accessors"][k]
        view = doc["bufferViews"][acc["bufferView"]]
        assert view["byteOffset"] % 4 == 0
        return np.frombuffer(blob, dtype=dtype, count=acc["count"] * width, offset=view["byteOffset"]).reshape(-1, width)

    P = accessor(prim["attributes"]["POSITION"], "<f4", 3)
    assert np.array_equal(P, mesh.vertices.astype(np.float32))
    acc = doc["accessors"][prim["attributes"]["POSITION"]]
    assert acc["min"] == P.min(axis=0).tolist() and acc["max"] == P.max(axis=0).tolist()
    N = accessor(prim["attributes"]["NORMAL"], "<f4", 3)
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0, atol=1e-6)
    assert doc["accessors"][prim["indices"]]["componentType"] == 5125
    assert np.array_equal(accessor(prim["indices"], "<u4", 1).reshape(-1, 3), fan_triangles(mesh))
    # without normals there is no NORMAL attribute
    exporters.export_glb(path, mesh, normals=False)
    data = path.read_bytes()
    doc = json.loads(data[20:20 + struct.unpack_from("<I", data, 12)[0]])
    assert set(doc["meshes"][0]["primitives"][0]["attributes"]) == {"POSITION"}


def test_3mf_package_read_with_the_standard_library(tmp_path):
    mesh = random_coordinates(primitives.torus(6, 5), seed=11)
    path = tmp_path / "m.3mf"
    exporters.export_3mf(path, mesh, name='bracket <v2> & "final"\ttab\nline', unit="inch")
    with zipfile.ZipFile(path) as package:
        assert {"[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"} <= set(package.namelist())
        rels = ET.fromstring(package.read("_rels/.rels"))
        assert [r.get("Target") for r in rels] == ["/3D/3dmodel.model"]
        ET.fromstring(package.read("[Content_Types].xml"))
        root = ET.fromstring(package.read("3D/3dmodel.model"))
    ns = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}
    assert root.get("unit") == "inch"
    obj = root.find("m:resources/m:object", ns)
    assert obj.get("name") == 'bracket <v2> & "final"\ttab\nline'
    V = np.array([[float(v.get(c)) for c in "xyz"] for v in obj.iterfind("m:mesh/m:vertices/m:vertex", ns)])
    T = np.array([[int(t.get(c)) for c in ("v1", "v2", "v3")] for t in obj.iterfind("m:mesh/m:triangles/m:triangle", ns)])
    assert np.array_equal(V, mesh.vertices)
    assert np.array_equal(T, fan_triangles(mesh))
    assert root.find("m:build/m:item", ns).get("objectid") == obj.get("id")


def test_3mf_and_glb_round_trip(tmp_path, mesh):
    tris = fan_triangles(mesh)
    exporters.export_3mf(tmp_path / "m.3mf", mesh)
    got = exporters.import_3mf(tmp_path / "m.3mf")
    assert np.array_equal(got.vertices, mesh.vertices) and np.array_equal(got.faces, tris)
    exporters.export_glb(tmp_path / "m.glb", mesh)
    got = exporters.import_glb(tmp_path / "m.glb")
    assert np.array_equal(got.vertices, mesh.vertices.astype(np.float32)) and np.array_equal(got.faces, tris)


def test_glb_reader_applies_node_transforms(tmp_path):
    import trimesh  # the test extra installs it: no skip
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    scene = trimesh.Scene()
    T = trimesh.transformations.rotation_matrix(0.7, [1, 2, 3])
    T[:3, 3] = [5.0, -1.0, 2.0]
    scene.add_geometry(box, transform=T)
    scene.export(str(tmp_path / "s.glb"))
    got = exporters.import_glb(tmp_path / "s.glb")
    want = trimesh.load(str(tmp_path / "s.glb"), force="mesh")
    assert np.allclose(np.sort(got.vertices, axis=0), np.sort(want.vertices, axis=0), atol=1e-6)
    assert np.allclose(got.vertices.mean(axis=0), [5.0, -1.0, 2.0], atol=1e-6)


# -- files written by hand ------------------------------------------------------------------------
def test_binary_stl_with_solid_header_is_read_as_binary(tmp_path):
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    T = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    rec = np.zeros(4, dtype=[("n", "<f4", 3), ("p", "<f4", (3, 3)), ("a", "<u2")])
    rec["p"] = V[T]
    header = b"solid looks like ascii but is not".ljust(80, b" ")
    (tmp_path / "s.stl").write_bytes(header + struct.pack("<I", 4) + rec.tobytes())
    got = exporters.import_stl(tmp_path / "s.stl")
    assert_same_polygons(got, V.astype(np.float64), T.ravel(), np.arange(5) * 3)
    assert got.is_closed and got.volume == pytest.approx(1 / 6)


def test_stl_reader_drops_degenerate_triangles(tmp_path):
    text = (
        "solid t\n"
        "facet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n vertex 0 1 0\n endloop\nendfacet\n"
        "FACET NORMAL 0 0 0\n OUTER LOOP\n VERTEX 1 0 0\n VERTEX 1 0 0\n VERTEX 5 5 5\n ENDLOOP\nENDFACET\n"
        "endsolid t\n"
    )
    (tmp_path / "d.stl").write_text(text)
    got = exporters.import_stl(tmp_path / "d.stl")
    assert got.n_faces == 1 and got.n_vertices == 3
    assert np.array_equal(got.vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


def test_ascii_stl_layouts(tmp_path):
    """Several solids, upper case, everything on one line: the same two triangles."""
    a = "facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 endloop endfacet"
    b = "facet normal 0 0 1 outer loop vertex 1 0 0 vertex 1 1 0 vertex 0 1 0 endloop endfacet"
    texts = [
        f"solid one\n{a}\nendsolid one\nsolid two\n{b}\nendsolid two\n",
        f"SOLID\r\n{a.upper()}\r\n{b.upper()}\r\nENDSOLID\r\n",
        f"solid x {a} {b} endsolid x",
    ]
    for text in texts:
        (tmp_path / "s.stl").write_text(text)
        got = exporters.import_stl(tmp_path / "s.stl")
        V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=np.float64)
        assert_same_polygons(got, V, [0, 1, 2, 1, 3, 2], [0, 3, 6])


def test_vertex_merging_survives_hash_collisions(monkeypatch):
    rng = np.random.default_rng(4)
    V = rng.integers(-3, 3, (40, 3)).astype(np.float64)
    V[0] = (-0.0, 0.0, -0.0)
    P = V[rng.integers(0, 40, 500)]
    expected = None
    for collide in (False, True):
        if collide:  # every row gets the same hash: the exact fallback must take over
            monkeypatch.setattr(_meshio, "row_hash", lambda U: np.zeros(len(U), dtype=np.uint64))
        W, index = _meshio.merge_vertices(P)
        assert np.array_equal(W[index], P)
        assert len({tuple(r) for r in (P + 0.0).tolist()}) == len(W)
        # vertices in order of first appearance
        first = [int(np.flatnonzero((P == w).all(axis=1))[0]) for w in W]
        assert first == sorted(first)
        if expected is None:
            expected = (W, index)
        else:
            assert np.array_equal(W, expected[0]) and np.array_equal(index, expected[1])


def test_obj_reader_index_forms(tmp_path):
    text = (
        "# a quad and a triangle\no thing\ng part\nmtllib none.mtl\n"
        "v 0 0 0\nv 1 0 0 1.0\nv 1 1 0 0.5 0.5 0.5\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
        "usemtl red\ns off\n"
        "f 1/1/1 2/2/1 3/3/1  # first\n"
        "v 0 1 0\n"
        "f -4/-3 -2/-1 \\\n -1/-1\n"  # relative indices, continued line: (0, 2, 3)
        "l 1 2\n"
    )
    (tmp_path / "f.obj").write_text(text)
    got = exporters.import_obj(tmp_path / "f.obj")
    assert np.array_equal(got.vertices, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    assert [f.tolist() for f in got.faces] == [[0, 1, 2], [0, 2, 3]]
    (tmp_path / "p.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 2//1 5//1 3//1\nvn 0 0 1\n")
    got = exporters.import_obj(tmp_path / "p.obj")
    assert got.faces[0].tolist() == [0, 1, 2, 3] and got.faces[1].tolist() == [1, 4, 2]


def test_ply_reader_big_endian_extra_properties_and_elements(tmp_path):
    header = (
        b"ply\nformat binary_big_endian 1.0\ncomment hand made\n"
        b"element vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
        b"element face 2\nproperty uchar flags\nproperty list uchar uint vertex_indices\nproperty float quality\n"
        b"element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
    )
    verts = np.zeros(4, dtype=[("x", ">f4"), ("y", ">f4"), ("z", ">f4"), ("r", "u1")])
    verts["x"], verts["y"] = [0, 1, 1, 0], [0, 0, 1, 1]
    faces = struct.pack(">BB4If", 7, 4, 0, 1, 2, 3, 0.5) + struct.pack(">BB3If", 7, 3, 0, 2, 1, 0.25)
    edge = struct.pack(">ii", 0, 1)
    (tmp_path / "h.ply").write_bytes(header + verts.tobytes() + faces + edge)
    got = exporters.import_ply(tmp_path / "h.ply")
    assert np.array_equal(got.vertices, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    assert [f.tolist() for f in got.faces] == [[0, 1, 2, 3], [0, 2, 1]]


def test_ply_reader_many_alternating_face_sizes(tmp_path):
    """Faces of sizes 3, 4, 5, 3, 4, 5, ... in binary and ASCII (no common record layout)."""
    n = 60
    k = np.arange(3, 3 + n) % 3 + 3
    offsets = np.concatenate([[0], np.cumsum(k)])
    V = np.random.default_rng(2).random((offsets[-1], 3))
    faces = [np.arange(offsets[f], offsets[f + 1]) for f in range(n)]
    mesh = PolyMesh(V, faces)  # disjoint polygons
    for binary in (True, False):
        exporters.export_ply(tmp_path / "a.ply", mesh, binary=binary)
        assert exporters.import_ply(tmp_path / "a.ply") == mesh


def test_ply_ascii_with_extra_properties(tmp_path):
    text = (
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
        "property float nx\nelement face 1\nproperty list uchar int vertex_index\nproperty uchar c\nend_header\n"
        "0 0 0 9\n1 0 0 9\n0 1 0 9\n3 0 1 2 255\n"
    )
    (tmp_path / "x.ply").write_text(text)
    got = exporters.import_ply(tmp_path / "x.ply")
    assert np.array_equal(got.vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert got.faces.tolist() == [[0, 1, 2]]


# -- atomic writing -------------------------------------------------------------------------------
def _failing_write_part(real):
    calls = {"n": 0}

    def write_part(fh, data):
        calls["n"] += 1
        raw = data.encode("ascii") if isinstance(data, str) else (data.tobytes() if isinstance(data, np.ndarray) else data)
        if calls["n"] >= 2 or len(raw) > 64:
            real(fh, raw[: len(raw) // 2])  # part of the data reaches the file, then the disk fills up
            raise OSError(28, "No space left on device")
        real(fh, raw)

    return write_part


@pytest.mark.parametrize("suffix", FORMATS)
def test_failed_write_keeps_existing_file(tmp_path, monkeypatch, suffix):
    target = tmp_path / f"keep{suffix}"
    original = os.urandom(300)
    target.write_bytes(original)
    monkeypatch.setattr(_meshio, "write_part", _failing_write_part(_meshio.write_part))
    with pytest.raises(ExportError, match="No space left"):
        exporters.export_mesh(target, primitives.torus(8, 5))
    assert target.read_bytes() == original
    assert os.listdir(tmp_path) == [target.name]


def test_interrupted_write_leaves_no_temporary_file(tmp_path, monkeypatch):
    def interrupted(fh, data):
        fh.write(b"partial")
        raise KeyboardInterrupt

    monkeypatch.setattr(_meshio, "write_part", interrupted)
    with pytest.raises(KeyboardInterrupt):
        exporters.export_stl(tmp_path / "x.stl", primitives.box())
    assert os.listdir(tmp_path) == []


def test_successful_write_replaces_target_and_leaves_nothing_else(tmp_path):
    target = tmp_path / "m.ply"
    target.write_bytes(b"old")
    assert exporters.export_mesh(target, primitives.box()) == str(target)
    assert target.read_bytes().startswith(b"ply\n")
    assert os.listdir(tmp_path) == ["m.ply"]


def test_unwritable_targets(tmp_path):
    mesh = primitives.box()
    missing = tmp_path / "no" / "such" / "folder" / "m.stl"
    with pytest.raises(ExportError, match="does not exist"):
        exporters.export_stl(missing, mesh)
    assert not (tmp_path / "no").exists()
    (tmp_path / "dir.obj").mkdir()
    with pytest.raises(ExportError, match="is a folder"):
        exporters.export_obj(tmp_path / "dir.obj", mesh)
    if hasattr(os, "geteuid") and os.geteuid() != 0:  # root ignores folder permissions
        locked = tmp_path / "locked"
        locked.mkdir()
        locked.chmod(0o500)
        try:
            with pytest.raises(ExportError):
                exporters.export_ply(locked / "m.ply", mesh)
            assert os.listdir(locked) == []
        finally:
            locked.chmod(0o700)
    assert issubclass(ExportError, OSError) and issubclass(ExportError, SplineKitError)


# -- formats and arguments ------------------------------------------------------------------------
def test_unsupported_suffix(tmp_path):
    with pytest.raises(FileFormatError, match=r"'\.xyz'.*\.stl, \.obj, \.ply, \.3mf, \.glb"):
        exporters.export_mesh(tmp_path / "m.xyz", primitives.box())
    with pytest.raises(FileFormatError, match="no suffix"):
        exporters.import_mesh(tmp_path / "m")
    with pytest.raises(FileFormatError, match="'step'"):
        exporters.export_mesh(tmp_path / "m.stl", primitives.box(), format="step")
    assert os.listdir(tmp_path) == []
    # format= overrides the suffix, any case, with or without the dot
    exporters.export_mesh(tmp_path / "m.dat", primitives.box(), format=".PLY")
    assert exporters.import_mesh(tmp_path / "m.dat", format="ply") == primitives.box()


def test_writer_arguments():
    box = primitives.box()
    flat = PolyMesh(np.array([[0.0, 0], [1, 0], [0, 1]]), [[0, 1, 2]])
    with tempfile.TemporaryDirectory() as folder:
        p = os.path.join(folder, "m")
        with pytest.raises(ParameterError, match="PolyMesh"):
            exporters.export_stl(p + ".stl", np.zeros((3, 3)))
        with pytest.raises(ParameterError, match=r"3-D vertices.*\(3, 2\)"):
            exporters.export_obj(p + ".obj", flat)
        with pytest.raises(ParameterError, match="binary"):
            exporters.export_stl(p + ".stl", box, binary="yes")
        with pytest.raises(ParameterError, match="unit"):
            exporters.export_3mf(p + ".3mf", box, unit="parsec")
        for bad, code in (("a\x01b", "0001"), ("nul\x00", "0000"), ("\ud800", "D800")):
            with pytest.raises(ParameterError, match=f"U\\+{code}"):
                exporters.export_3mf(p + ".3mf", box, name=bad)
        with pytest.raises(ParameterError, match="name"):
            exporters.export_stl(p + ".stl", box, name="two\nlines")
        empty = PolyMesh(np.zeros((0, 3)), [])
        for writer in (exporters.export_3mf, exporters.export_glb):
            with pytest.raises(ParameterError, match="at least one face"):
                writer(p, empty)
        with pytest.raises(ExportError, match="float32"):
            exporters.export_stl(p + ".stl", box.with_vertices(box.vertices * 1e39))
        with pytest.raises(ParameterError, match="path"):
            exporters.export_stl(None, box)
        assert os.listdir(folder) == []


# -- malformed files ------------------------------------------------------------------------------
def _bad(tmp_path, name, content, match, error=FileFormatError):
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(error, match=match):
        exporters.import_mesh(path)


def test_malformed_stl(tmp_path):
    exporters.export_stl(tmp_path / "ok.stl", primitives.box())
    good = (tmp_path / "ok.stl").read_bytes()
    _bad(tmp_path, "a.stl", good[:-7], r"declares 12 triangles \(684 bytes\) but the file has 677 bytes \(truncated")
    _bad(tmp_path, "b.stl", good[:50], "shorter than the 84-byte header")
    _bad(tmp_path, "c.stl", b"solid x\n" + good[8:-7], "truncated")  # binary with a solid header, cut short
    facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
    _bad(tmp_path, "d.stl", "solid x\n" + facet + facet.replace("vertex 0 1 0\n", ""), "facet 1 .*malformed")
    _bad(tmp_path, "e.stl", "solid x\n" + facet, "endsolid")
    _bad(tmp_path, "f.stl", "solid x\n" + facet.replace("vertex 1 0 0", "vertex 1 0 nan") + "endsolid\n", "non-finite")
    _bad(tmp_path, "g.stl", "solid x\n" + facet.replace("vertex 1 0 0", "vertex 1 0 zz") + "endsolid\n", "non-numeric")
    # three triangles on one edge: a valid file, but not a manifold PolyMesh
    fan = "".join(facet.replace("vertex 0 1 0", f"vertex 0 {y} {z}") for y, z in ((1, 0), (0, 1), (-1, 0)))
    _bad(tmp_path, "h.stl", "solid x\n" + fan + "endsolid\n", r"h\.stl.*edge", MeshTopologyError)
    _bad(tmp_path, "empty.stl", b"", "shorter than the 84-byte header")
    with pytest.raises(FileFormatError, match="cannot read"):
        exporters.import_stl(tmp_path / "nope.stl")


def test_malformed_obj(tmp_path):
    tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
    _bad(tmp_path, "a.obj", tri + "f 1 2 4\n", r"face 0 \(line 4\) refers to vertex 4; 3 vertices")
    _bad(tmp_path, "b.obj", tri + "f 1 2 0\n", "refers to vertex 0")
    _bad(tmp_path, "c.obj", tri + "f -1 -2 -4\n", "vertex -4; 3 vertices are defined above it")
    _bad(tmp_path, "d.obj", tri + "f 1 2\n", "face 0 .* 2 corners")
    _bad(tmp_path, "e.obj", tri + "f 1 2 x\n", "non-integer vertex index 'x'")
    _bad(tmp_path, "e2.obj", tri + "f 1 2 3\nf 1 2 -99999999999999999999\n",
         r"face 1 \(line 5\) has an out-of-range vertex index '-99999999999999999999'")
    _bad(tmp_path, "e3.obj", tri + "vn 0 0 1\nf 1//1 2//1 3//99999999999999999999\n", "out-of-range normal index")
    _bad(tmp_path, "f.obj", "v 0 0\n", r"vertex 0 \(line 1\) has fewer than 3")
    _bad(tmp_path, "g.obj", "v 0 0 inf\n", "not finite")
    _bad(tmp_path, "h.obj", "v 0 0 a\n", "non-numeric")
    _bad(tmp_path, "i.obj", tri + "f 1/1 2/1 3/1\n", "texture coordinate 1; 0 texture coordinates")
    _bad(tmp_path, "j.obj", tri + "vn 0 0 1\nf 1//1 2//2 3//1\n", "normal 2")


def test_malformed_ply(tmp_path):
    exporters.export_ply(tmp_path / "ok.ply", primitives.box())
    good = (tmp_path / "ok.ply").read_bytes()
    _bad(tmp_path, "a.ply", good[:-3], "face 5 is truncated")
    _bad(tmp_path, "b.ply", b"plx\n" + good[4:], "not a PLY file")
    _bad(tmp_path, "c.ply", good.replace(b"end_header", b"end_heada"), "end_header")
    _bad(tmp_path, "d.ply", good.replace(b"double x", b"quad x"), "malformed PLY header line 5")
    head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n" \
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
    _bad(tmp_path, "e.ply", head + "3 0 1 3\n", "face 0 refers to vertex 3, outside 0..2")
    _bad(tmp_path, "f.ply", head + "2 0 1\n", "face 0 has 2 corners")
    _bad(tmp_path, "g.ply", head + "3 0 1\n", "truncated")
    _bad(tmp_path, "h.ply", head.replace("1 0 0\n", "1 0 nan\n") + "3 0 1 2\n", "vertex 1 has non-finite")
    _bad(tmp_path, "i.ply", head.replace("property float x\n", "") + "3 0 1 2\n", "no scalar x")
    _bad(tmp_path, "j.ply", head + "3 0 1 two\n", "not a number")
    # beyond int64 in ASCII: named (as parsed) instead of wrapped around by a cast
    _bad(tmp_path, "k.ply", head + "3 0 1 99999999999999999999\n", r"refers to vertex 1(0{20}), outside 0\.\.2")  # as read: a float64
    _bad(tmp_path, "l.ply", head + "3 0 1 inf\n", "refers to vertex inf, outside 0..2")
    _bad(tmp_path, "m.ply", head + "3 0 1 2.5\n", "non-integer vertex index 2.5")


def test_malformed_glb_and_3mf(tmp_path):
    exporters.export_glb(tmp_path / "ok.glb", primitives.box())
    good = (tmp_path / "ok.glb").read_bytes()
    _bad(tmp_path, "a.glb", good[:-4], "truncated")
    _bad(tmp_path, "b.glb", b"gltf" + good[4:], "not a GLB file")
    _bad(tmp_path, "c.glb", good[:10], "too short")
    doc_len = struct.unpack_from("<I", good, 12)[0]
    doc = json.loads(good[20:20 + doc_len])
    doc["accessors"][0]["count"] = 10_000
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    rest = good[20 + doc_len:]
    bad = struct.pack("<III", 0x46546C67, 2, 20 + len(text) + len(rest)) + struct.pack("<I4s", len(text), b"JSON") + text + rest
    _bad(tmp_path, "d.glb", bad, "accessor 0 reaches past the end")
    for rotation in ([0, 0, 0, 0], [0, 0, 1], [0, 0, float("nan"), 1]):
        doc = json.loads(good[20:20 + doc_len])
        doc["nodes"][0]["rotation"] = rotation
        text = json.dumps(doc).encode()
        text += b" " * (-len(text) % 4)
        bad = struct.pack("<III", 0x46546C67, 2, 20 + len(text) + len(rest)) + struct.pack("<I4s", len(text), b"JSON") + text + rest
        _bad(tmp_path, "q.glb", bad, "unit quaternion")
    _bad(tmp_path, "a.3mf", b"PK not really a zip", "not a readable 3MF")
    with zipfile.ZipFile(tmp_path / "b.3mf", "w") as z:
        z.writestr("3D/other.model", "<model/>")
    with pytest.raises(FileFormatError, match="no model part"):
        exporters.import_3mf(tmp_path / "b.3mf")


def test_first_stl_export_loads_the_kernel_only_where_it_pays():
    """A first binary STL export of LOAD_WORK triangles (2M: the numpy fill takes a few tenths of
    a second) stays on the numpy path in a fresh process with the default rule: loading numba
    would cost more than the fill. 1 / RECORD_WORK times as many records load it."""
    code = (
        "import os, sys\n"
        "os.environ.pop('SPLINEKIT_NUMBA', None)\n"
        "from splinekit import _kernels\n"
        "from exporters import _meshio\n"
        "n = int(_kernels.LOAD_WORK)\n"
        "small = _meshio.stl_fill_kernel(n) is None and 'numba' not in sys.modules\n"
        "print(small, _meshio.stl_fill_kernel(int(n / _meshio.RECORD_WORK)) is not None)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "True True"
