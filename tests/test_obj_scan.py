"""The OBJ reader's numpy fast path (exporters._objscan) against its general path.

Every file is read twice, once as it is and once with the fast path switched off: both must give
the same mesh, or the same error. The files are meshes written by exporters and by trimesh, and
hand-built text that mixes what the fast path takes (v/vt/vn/f lines, negative indices, comments,
the four corner forms) with what it must hand over (leading blanks, trailing comments, extra
numbers, mixed corner forms, bad numbers, out-of-range indices, short faces).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import exporters
from exporters import _objscan
from splinekit.errors import SplineKitError
from splinekit.mesh import primitives
from splinekit.mesh.geometry import triangulate


def read_both(path, monkeypatch):
    """(fast result, general result): a PolyMesh or (error type, message) each."""
    def outcome():
        try:
            return exporters.import_obj(path)
        except SplineKitError as exc:
            return type(exc), str(exc)

    fast = outcome()
    with monkeypatch.context() as m:
        m.setattr(_objscan, "scan", lambda text: None)
        general = outcome()
    return fast, general


def test_written_meshes_take_the_fast_path_and_read_back_exactly(tmp_path, monkeypatch):
    rng = np.random.default_rng(0)
    for mesh in (primitives.icosphere(2), primitives.torus(12, 8), primitives.box()):
        mesh = mesh.with_vertices(mesh.vertices * 10.0 ** rng.integers(-8, 8, mesh.vertices.shape))
        for normals in (True, False):
            path = tmp_path / "m.obj"
            exporters.export_obj(path, mesh, normals=normals)
            assert _objscan.scan(path.read_bytes()) is not None
            fast, general = read_both(path, monkeypatch)
            assert fast == mesh and general == mesh


def test_trimesh_files_take_the_fast_path(tmp_path, monkeypatch):
    trimesh = pytest.importorskip("trimesh")
    mesh = primitives.icosphere(2)
    path = tmp_path / "t.obj"
    t = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    for options in ({}, {"include_normals": True}):
        path.write_text(trimesh.exchange.obj.export_obj(t, **options))
        assert _objscan.scan(path.read_bytes()) is not None
        fast, general = read_both(path, monkeypatch)
        assert fast == general
        assert np.abs(fast.vertices - mesh.vertices).max() <= 5e-9  # trimesh writes 8 decimals
        np.testing.assert_array_equal(fast.faces, mesh.faces)


# hand-built files: a tetrahedron's lines in varied spellings
TETRA_V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TETRA_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]

number = st.one_of(
    st.sampled_from(["0", "1", "-1", "0.5", "1e-3", "-2.5E+2", ".5", "1.", "+3"]),
    st.floats(-1e6, 1e6, allow_nan=False).map(repr),
)
oddity = st.sampled_from([
    "", "", "", "", "", "",  # mostly plain
    "lead", "trail#", "extra", "w", "badnum", "nan", "short", "zero", "big", "huge", "mixed", "bare",
    "vt", "vn", "neg", "tab", "crlf", "cont", "fewcorners",
])


def tetra_text(numbers, odd, form):
    vt = "vt 0.5 0.5\n" if form in ("vt", "vtvn") else ""
    vn = "vn 0 0 1\n" if form in ("vn", "vtvn") else ""
    lines = ["# a tetrahedron", "o tetra"]
    for k, p in enumerate(TETRA_V):
        coords = [numbers[(3 * k + j) % len(numbers)] if odd != "" or j else str(p[j]) for j in range(3)]
        coords = [str(p[j]) for j in range(3)] if k == 0 else coords
        if odd == "badnum" and k == 1:
            coords[1] = "1.2.3"
        if odd == "nan" and k == 2:
            coords[0] = "nan"
        if odd == "w" and k == 3:
            coords.append("1")
        if odd == "short" and k == 3:
            coords = coords[:2]
        sep = "\t" if odd == "tab" else " "
        lines.append("v" + sep + sep.join(coords))
    lines += [s for s in (vt + vn).splitlines()]
    for i, face in enumerate(TETRA_F):
        idx = [str(v + 1) for v in face]
        if odd == "neg" and i == 1:
            idx = [str(v - 4) for v in face]
        if odd == "zero" and i == 2:
            idx[0] = "0"
        if odd == "big" and i == 2:
            idx[0] = "5"
        if odd == "huge" and i == 3:
            idx[2] = "99999999999999999999"
        if odd == "fewcorners" and i == 0:
            idx = idx[:2]
        suffix = {"vt": "/1", "vn": "//1", "vtvn": "/1/1"}.get(form, "")
        corners = [c + suffix for c in idx]
        if odd == "mixed" and i == 3:
            corners[0] = idx[0]
        if odd == "vn" and form in ("vn", "vtvn") and i == 0:
            corners[1] = corners[1][:-1] + "2"  # refers to normal 2 of 1
        if odd == "vt" and form in ("vt", "vtvn"):
            corners[2] = idx[2] + ("/3" if form == "vt" else "/3/1")  # texture coordinate 3 of 1
        lines.append("f " + " ".join(corners))
    if odd == "lead":
        lines[3] = "  " + lines[3]
    if odd == "trail#":
        lines[-1] += " # done"
    if odd == "extra":
        lines.append("l 1 2")
    if odd == "bare":
        lines.append("f")
    text = "\n".join(lines) + "\n"
    if odd == "crlf":
        text = text.replace("\n", "\r\n")
    if odd == "cont":
        text = text.replace("f 1", "f \\\n1", 1)
    return text


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(numbers=st.lists(number, min_size=1, max_size=12), odd=oddity,
       form=st.sampled_from(["", "vt", "vn", "vtvn"]))
def test_hand_built_files_read_the_same_both_ways(tmp_path, monkeypatch, numbers, odd, form):
    path = tmp_path / "h.obj"
    text = tetra_text(numbers, odd, form)
    path.write_text(text)
    if odd in ("", "neg", "zero", "big", "vn", "vt", "tab", "extra"):  # plain: the fast path must take it
        assert _objscan.scan(text.encode()) is not None
    fast, general = read_both(path, monkeypatch)
    assert fast == general


@pytest.mark.parametrize("text", [
    b"", b"\n", b"# nothing\n", b"v 1 2 3\n", b"v 1 2 3",  # no faces, no final newline
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3",
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n",
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n",  # a texture index without vt lines
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\nvn 0 0 1\n",  # the normal defined after the face
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 \n",  # trailing blank
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/ 2/ 3/\n",
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1// 2// 3//\n",
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1e1\n",
    b"v 0x1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    b"v 1e999 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    b"vp 1 2\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv\nf 1 2 3\n",
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn\nf 1 2 3\n",
])
def test_edge_cases_read_the_same_both_ways(tmp_path, monkeypatch, text):
    path = tmp_path / "e.obj"
    path.write_bytes(text)
    fast, general = read_both(path, monkeypatch)
    assert fast == general


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**32 - 1), normals=st.booleans())
def test_random_meshes_written_by_trimesh_read_back(tmp_path, monkeypatch, seed, normals):
    """Random coordinates and vertex labels on a triangulated torus, written by trimesh with or
    without normals: both paths read the same mesh, the one written up to trimesh's 8 decimals."""
    trimesh = pytest.importorskip("trimesh")
    rng = np.random.default_rng(seed)
    base = primitives.torus(int(rng.integers(3, 12)), int(rng.integers(3, 9)))
    label = rng.permutation(base.n_vertices)  # vertex i of the torus is written as vertex label[i]
    V = np.empty((base.n_vertices, 3))
    V[label] = rng.uniform(-1e3, 1e3, (base.n_vertices, 3))
    F = label[triangulate(base)[0]]
    path = tmp_path / "r.obj"
    path.write_text(trimesh.exchange.obj.export_obj(trimesh.Trimesh(V, F, process=False), include_normals=normals))
    assert _objscan.scan(path.read_bytes()) is not None
    fast, general = read_both(path, monkeypatch)
    assert fast == general
    assert np.abs(fast.vertices - V).max() <= 5e-9
    np.testing.assert_array_equal(fast.faces, F)
