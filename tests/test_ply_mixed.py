"""PLY files whose faces have mixed sizes, read and written against plyfile (an independent PLY
library) and trimesh.

The meshes are disjoint polygons, each on vertices of its own, numbered through a random
permutation: any sequence of face sizes then makes a valid mesh, in any order. plyfile writes
them in both byte orders with ``uchar`` or ``int`` list counts (and extra face properties around
the list) for splinekit to read; splinekit writes them for plyfile to read.
"""

from __future__ import annotations

import numpy as np
import plyfile
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

import exporters
from splinekit.errors import FileFormatError
from splinekit.mesh import PolyMesh


def polygons(sizes, seed):
    """``(V, faces)``: one polygon per entry of ``sizes`` on fresh vertices, renumbered at random."""
    rng = np.random.default_rng(seed)
    sizes = np.asarray(sizes, dtype=np.int64)
    perm = rng.permutation(int(sizes.sum()))
    V = rng.normal(size=(perm.size, 3))
    faces = np.split(perm, np.cumsum(sizes)[:-1])
    return V, faces


def plyfile_write(path, V, faces, byte_order, count, extra=False):
    """The mesh as plyfile writes it; ``extra`` adds a scalar before the list and after it, and a
    second list."""
    vert = np.empty(len(V), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    vert["x"], vert["y"], vert["z"] = V.T
    fields = [("vertex_indices", object)]
    if extra:
        fields = [("flag", "u1")] + fields + [("uv", object), ("quality", "f4")]
    face = np.empty(len(faces), dtype=fields)
    face["vertex_indices"] = [f.astype(np.int32) for f in faces]
    if extra:
        face["flag"] = np.arange(len(faces)) % 7
        face["uv"] = [np.full(2 * (i % 4), 0.5, dtype="f4") for i in range(len(faces))]
        face["quality"] = 1.5
    lengths = {"vertex_indices": count, "uv": "u1"}
    elements = [plyfile.PlyElement.describe(vert, "vertex"),
                plyfile.PlyElement.describe(face, "face", len_types=lengths)]
    text = byte_order == "ascii"
    plyfile.PlyData(elements, text=text, byte_order="<" if text else byte_order).write(str(path))


def assert_same_mesh(mesh, V, faces):
    np.testing.assert_array_equal(mesh.vertices, V)
    assert len(mesh.faces) == len(faces)
    np.testing.assert_array_equal(mesh.face_offsets, np.concatenate([[0], np.cumsum([len(f) for f in faces])]))
    np.testing.assert_array_equal(mesh.face_indices, np.concatenate(faces))


sizes_strategy = st.lists(st.integers(3, 9), min_size=1, max_size=60)


@settings(max_examples=25, deadline=None)
@given(sizes=sizes_strategy, seed=st.integers(0, 2**32 - 1),
       byte_order=st.sampled_from(["<", ">", "ascii"]), count=st.sampled_from(["u1", "i4"]),
       extra=st.booleans())
def test_mixed_faces_written_by_plyfile_are_read(tmp_path_factory, sizes, seed, byte_order, count, extra):
    V, faces = polygons(sizes, seed)
    path = tmp_path_factory.mktemp("ply") / "m.ply"
    plyfile_write(path, V, faces, byte_order, count, extra)
    assert_same_mesh(exporters.import_ply(path), V, faces)


@pytest.mark.parametrize("binary", [True, False])
def test_mixed_faces_written_by_splinekit_are_read_by_plyfile(tmp_path, binary):
    sizes = [3, 4, 5, 3, 3, 4, 5, 5, 7, 3] * 40 + [300]  # a 300-gon: the counts become int
    V, faces = polygons(sizes, 1)
    exporters.export_ply(tmp_path / "m.ply", PolyMesh(V, faces), binary=binary)
    data = plyfile.PlyData.read(str(tmp_path / "m.ply"))
    np.testing.assert_array_equal(np.column_stack([data["vertex"][c] for c in "xyz"]), V)
    got = data["face"]["vertex_indices"]
    assert len(got) == len(faces) and all(np.array_equal(a, b) for a, b in zip(got, faces))
    assert exporters.import_ply(tmp_path / "m.ply") == PolyMesh(V, faces)


@pytest.mark.parametrize("byte_order", ["<", ">"])
def test_long_mixed_file_from_plyfile(tmp_path, byte_order):
    """Beyond 4096 faces the reader chains records in giant and baby steps (see ply._record_starts)."""
    rng = np.random.default_rng(7)
    V, faces = polygons(rng.integers(3, 7, size=20_011), 3)
    plyfile_write(tmp_path / "m.ply", V, faces, byte_order, "u1")
    assert_same_mesh(exporters.import_ply(tmp_path / "m.ply"), V, faces)


def test_triangles_against_trimesh(tmp_path):
    """trimesh's binary reader takes one face size: the all-triangle path, against it."""
    V, faces = polygons([3] * 500, 5)
    exporters.export_ply(tmp_path / "t.ply", PolyMesh(V, faces))
    tm = trimesh.load(tmp_path / "t.ply", process=False)
    mesh = exporters.import_ply(tmp_path / "t.ply")
    np.testing.assert_array_equal(tm.vertices, mesh.vertices)
    np.testing.assert_array_equal(tm.faces, mesh.faces)


def test_bad_mixed_files_are_refused(tmp_path):
    V, faces = polygons([3, 4, 5] * 2000, 2)
    plyfile_write(tmp_path / "ok.ply", V, faces, "<", "u1")
    good = (tmp_path / "ok.ply").read_bytes()
    (tmp_path / "a.ply").write_bytes(good[:-3])
    with pytest.raises(FileFormatError, match="face 5999 is truncated"):
        exporters.import_ply(tmp_path / "a.ply")
    # a count of 200 in face 3000 misaligns the records after it, until one runs past the end
    body = good.index(b"end_header\n") + len(b"end_header\n") + 24 * len(V)
    at = body + sum(1 + 4 * len(f) for f in faces[:3000])
    assert good[at] == len(faces[3000])
    (tmp_path / "b.ply").write_bytes(good[:at] + bytes([200]) + good[at + 1:])
    with pytest.raises(FileFormatError, match=r"face [0-9]+ is truncated"):
        exporters.import_ply(tmp_path / "b.ply")
    # a count of 2: a face of fewer than 3 corners, or misaligned records after it
    (tmp_path / "c.ply").write_bytes(good[:at] + bytes([2]) + good[at + 1:])
    with pytest.raises(FileFormatError):
        exporters.import_ply(tmp_path / "c.ply")


@pytest.mark.parametrize("claimed", [10**12, 2**31 + 5])
def test_a_header_claiming_more_faces_than_the_file_holds_is_refused_quickly(tmp_path, claimed):
    V, faces = polygons([3, 4, 5] * 20, 4)
    plyfile_write(tmp_path / "ok.ply", V, faces, "<", "u1")
    good = (tmp_path / "ok.ply").read_bytes()
    bad = good.replace(f"element face {len(faces)}\n".encode(), f"element face {claimed}\n".encode())
    (tmp_path / "c.ply").write_bytes(bad)
    with pytest.raises(FileFormatError, match="truncated"):
        exporters.import_ply(tmp_path / "c.ply")
