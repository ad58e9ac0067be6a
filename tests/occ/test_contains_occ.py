"""Solid.contains against OpenCascade's BRepClass3d_SolidClassifier, point by point, on the same
solids (build123d shapes and STEP files written by other CAD systems, converted with from_occ).

The points: random ones in the solid's box; points on every face (ON), and 1e-3 and 1e-6 off it
along the exact outward normal on both sides; points on every edge (ON). OCC classifies with the
tolerance splinekit uses (the faces' tolerance). Both of splinekit's paths are checked: the
tessellation's signed distance (compiled search, ``SPLINEKIT_NUMBA=1``) and the winding numbers of
the faces' coarse meshes (``SPLINEKIT_NUMBA=0``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

bd = pytest.importorskip("build123d")

from splinekit.brep.classify import INSIDE, ON, OUTSIDE  # noqa: E402
from splinekit.occ import from_occ  # noqa: E402

STEP_DIR = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "step"


def _occ_codes(shape, points, tol):
    from OCP.BRepClass3d import BRepClass3d_SolidClassifier
    from OCP.gp import gp_Pnt
    from OCP.TopAbs import TopAbs_IN, TopAbs_ON, TopAbs_OUT

    code = {TopAbs_IN: INSIDE, TopAbs_OUT: OUTSIDE, TopAbs_ON: ON}
    return np.array([code[BRepClass3d_SolidClassifier(shape, gp_Pnt(*map(float, p)), tol).State()]
                     for p in points], dtype=np.int8)


def _face_points(solid, rng, per_face):
    """``(points (m, 3), outward normals (m, 3))`` at random ``(u, v)`` inside each face's trims."""
    pts, nrm = [], []
    for f in solid.faces:
        (u0, u1), (v0, v1) = f.domain
        uv = rng.uniform((u0, v0), (u1, v1), (8 * per_face, 2))
        uv = uv[f.contains_uv(uv) == INSIDE][:per_face]
        if len(uv):
            pts.append(f.surface.evaluate(uv[:, 0], uv[:, 1]))
            nrm.append(f.normals(uv[:, 0], uv[:, 1]))
    return np.concatenate(pts), np.concatenate(nrm)


def _edge_points(solid, rng, per_edge):
    """Points on every non-degenerate edge, from a use's pcurve on its face ``(m, 3)``."""
    out = []
    for shell in solid.shells:
        for g in shell.topology.edges:
            if g.degenerate:
                continue
            fi, li, ei = g.uses[0]
            face = shell.faces[fi]
            e = face.boundary_loops()[li][ei]
            a, b = e.domain
            uv = e.pcurve.evaluate(rng.uniform(a, b, per_edge))
            out.append(face.surface.evaluate(uv[:, 0], uv[:, 1]))
    return np.concatenate(out)


def _probe_points(solid, shape, rng, n_random=300, per_face=None, per_edge=2):
    """Random points in the box (5% margin), points on and 1e-3 / 1e-6 off the faces (``per_face``
    each, default about 120 in all), on the edges."""
    per_face = max(4, 120 // len(solid.faces)) if per_face is None else per_face
    bb = shape.bounding_box()
    lo, hi = np.array([bb.min.X, bb.min.Y, bb.min.Z]), np.array([bb.max.X, bb.max.Y, bb.max.Z])
    pad = 0.05 * (hi - lo)
    P, N = _face_points(solid, rng, per_face)
    groups = [rng.uniform(lo - pad, hi + pad, (n_random, 3)), P, _edge_points(solid, rng, per_edge)]
    groups += [P + s * N for s in (1e-3, -1e-3, 1e-6, -1e-6)]
    return np.concatenate(groups), len(P)


def _agree(solid, wrapped, points, monkeypatch, path):
    tol = max(f.tolerance for f in solid.faces)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1" if path == "mesh" else "0")
    ours = solid.contains(points)
    if path == "mesh":
        assert solid._cache.get("inside_mesh") is not None  # the tessellation path answered
    theirs = _occ_codes(wrapped, points, tol)
    bad = np.flatnonzero(ours != theirs)
    assert bad.size == 0, f"{bad.size} of {len(points)} differ, e.g. {points[bad[:3]].tolist()}: ours {ours[bad[:3]]}, OCC {theirs[bad[:3]]}"
    return ours


def _filleted_box():
    b = bd.Box(10, 10, 10)
    return b.fillet(2, b.edges())


PARTS = {
    "box_with_hole": lambda: bd.Box(20, 20, 20) - bd.Cylinder(4, 20),
    "filleted_box": _filleted_box,
    "sphere": lambda: bd.Sphere(3),
    "torus": lambda: bd.Torus(5, 1.5),
}


@pytest.mark.parametrize("path", ["mesh", "winding"])
@pytest.mark.parametrize("name", list(PARTS))
def test_contains_agrees_with_occ_classifier(name, path, monkeypatch):
    (shape,) = PARTS[name]().solids()
    solid = from_occ(shape.wrapped)
    rng = np.random.default_rng(12)
    points, n_face = _probe_points(solid, shape, rng)
    ours = _agree(solid, shape.wrapped, points, monkeypatch, path)
    # the probes reach every class: on faces and edges ON, 1e-6 off them not
    n_random = 300
    on_faces = ours[n_random:n_random + n_face]
    assert np.all(on_faces == ON)
    off = ours[-4 * n_face:].reshape(4, n_face)  # +1e-3, -1e-3, +1e-6, -1e-6 along the outward normal
    assert np.all(off[[0, 2]] == OUTSIDE) and np.all(off[[1, 3]] == INSIDE)
    assert (ours[:n_random] == INSIDE).sum() > 10 and (ours[:n_random] == OUTSIDE).sum() > 10


def _step_solids(name):
    path = STEP_DIR / name
    if not path.exists():
        pytest.skip(f"the foreign STEP files are not here ({STEP_DIR})")
    return [s for s in bd.import_step(str(path)).solids()]


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ug19_io1_analytic.stp", "euclid_screw.step"])
def test_contains_agrees_with_occ_on_foreign_step_files(name, monkeypatch):
    for k, shape in enumerate(_step_solids(name)):
        solid = from_occ(shape.wrapped)
        rng = np.random.default_rng(13 + k)
        points, n_face = _probe_points(solid, shape, rng, n_random=400, per_face=4, per_edge=1)
        _agree(solid, shape.wrapped, points, monkeypatch, "mesh")
