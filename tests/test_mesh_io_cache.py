"""Normals cached on the immutable PolyMesh and reused by the STL writer; space reserved before an
atomic write.

The reference normals are computed here with ``np.cross`` from the float64 triangles, independently
of ``splinekit.mesh.geometry`` and ``exporters``.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

import exporters
from exporters import _meshio
from splinekit.mesh import PolyMesh, primitives

RECORD = np.dtype([("n", "<f4", 3), ("p", "<f4", (3, 3)), ("a", "<u2")])


def stl_records(path):
    return np.frombuffer(open(path, "rb").read(), dtype=RECORD, offset=84)


def cross_normals(V, tris):
    P = V[tris]
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def fan(mesh):
    """Fan triangles from each face's first corner, by a loop over faces (the reference)."""
    out = []
    for f in range(mesh.n_faces):
        face = mesh.face_indices[mesh.face_offsets[f]:mesh.face_offsets[f + 1]]
        out += [(face[0], face[j], face[j + 1]) for j in range(1, len(face) - 1)]
    return np.array(out, dtype=np.int64)


@pytest.mark.parametrize("numba", ["0", "1"])
def test_stl_normals_are_the_cached_face_normals_and_equal_a_fresh_computation(tmp_path, monkeypatch, numba):
    monkeypatch.setenv("SPLINEKIT_NUMBA", numba)
    mesh = primitives.icosphere(5, radius=3.0)  # above the compiled kernel's threshold
    assert "face_normals" not in mesh.__dict__
    exporters.export_stl(tmp_path / "a.stl", mesh)
    cached = mesh.__dict__["face_normals"]  # computed once, kept with the mesh
    assert not cached.flags.writeable
    rec = stl_records(tmp_path / "a.stl")
    np.testing.assert_array_equal(rec["n"], cached.astype(np.float32))
    assert np.abs(rec["n"] - cross_normals(mesh.vertices, mesh.faces)).max() <= 6e-8
    # a second export reuses the cache and writes the same bytes
    exporters.export_stl(tmp_path / "b.stl", mesh)
    assert mesh.__dict__["face_normals"] is cached
    assert (tmp_path / "a.stl").read_bytes() == (tmp_path / "b.stl").read_bytes()


def test_output_does_not_depend_on_the_cache_state(tmp_path):
    """A mesh whose normals were asked for first and a fresh one write the same bytes."""
    mesh = primitives.torus(24, 16)
    warm = PolyMesh(mesh.vertices, mesh.faces)
    _ = warm.face_normals
    fresh = PolyMesh(mesh.vertices, mesh.faces)
    for binary in (True, False):
        exporters.export_stl(tmp_path / "w.stl", warm, binary=binary)
        exporters.export_stl(tmp_path / "f.stl", fresh, binary=binary)
        assert (tmp_path / "w.stl").read_bytes() == (tmp_path / "f.stl").read_bytes()


def test_a_new_mesh_does_not_share_a_stale_cache(tmp_path):
    mesh = primitives.icosphere(2)
    exporters.export_stl(tmp_path / "a.stl", mesh)
    moved = mesh.with_vertices(mesh.vertices * np.array([1.0, 2.0, 0.5]))  # same topology, new shape
    exporters.export_stl(tmp_path / "b.stl", moved)
    rec = stl_records(tmp_path / "b.stl")
    assert np.abs(rec["n"] - cross_normals(moved.vertices, moved.faces)).max() <= 6e-8
    assert np.abs(rec["n"] - stl_records(tmp_path / "a.stl")["n"]).max() > 0.1


def test_cached_arrays_are_read_only():
    mesh = primitives.icosphere(1)
    with pytest.raises(ValueError):
        mesh.face_normals[0, 0] = 1.0
    with pytest.raises(ValueError):
        mesh.vertices[0, 0] = 1.0


@pytest.mark.parametrize("binary", [True, False])
def test_polygon_meshes_write_their_fan_triangle_normals_cached(tmp_path, binary):
    """Non-planar quads: every fan triangle gets its own normal (not the face's), cached on the mesh."""
    rng = np.random.default_rng(3)
    quads = primitives.torus(10, 6)
    mesh = quads.with_vertices(quads.vertices + rng.normal(scale=0.05, size=quads.vertices.shape))
    exporters.export_stl(tmp_path / "q.stl", mesh, binary=binary)
    want = cross_normals(mesh.vertices, fan(mesh))
    if binary:
        got = stl_records(tmp_path / "q.stl")["n"]
        assert np.abs(got - want).max() <= 6e-8
    else:
        text = (tmp_path / "q.stl").read_text().split()
        at = [i for i, t in enumerate(text) if t == "normal"]
        got = np.array([[float(text[i + k]) for k in (1, 2, 3)] for i in at])
        assert np.abs(got - want).max() <= 1e-15
    cached = mesh.derived("stl.fan_triangle_normals", lambda m: pytest.fail("not cached"))
    assert not cached.flags.writeable and cached.shape == want.shape


@pytest.mark.parametrize("size", [1, 84, 10**6])
def test_a_wrong_reserved_size_does_not_change_the_file(tmp_path, size):
    path = tmp_path / "r.bin"
    payload = bytes(range(256)) * 4
    _meshio.save(path, lambda fh: _meshio.write_part(fh, payload), "test file", size=size)
    assert path.read_bytes() == payload


def test_without_fallocate_the_write_still_happens(tmp_path, monkeypatch):
    def refuse(fd, offset, length):
        raise OSError(95, "Operation not supported")

    monkeypatch.setattr(os, "posix_fallocate", refuse, raising=False)
    mesh = primitives.box()
    exporters.export_stl(tmp_path / "a.stl", mesh)
    assert len(stl_records(tmp_path / "a.stl")) == 12
    monkeypatch.delattr(os, "posix_fallocate", raising=False)
    exporters.export_ply(tmp_path / "a.ply", mesh)
    assert exporters.import_ply(tmp_path / "a.ply") == mesh


def test_row_hash_separates_mirrored_points():
    """Points mirrored through the coordinate planes differ only in sign bits: the STL reader's row
    hash must still tell them apart (else every read falls back to the exact row sort)."""
    rng = np.random.default_rng(5)
    P = rng.uniform(0.1, 1.0, (500, 3)).astype(np.float32).astype(np.float64)
    signs = np.array([[sx, sy, sz] for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)], dtype=np.float64)
    Q = (P[:, None, :] * signs[None]).reshape(-1, 3)
    U = np.ascontiguousarray(Q).view(np.uint64)
    assert len(np.unique(_meshio.row_hash(U))) == len(np.unique(U, axis=0)) == 4000
