"""STEP round trip of parts with loose edges, as parts read from other CAD systems have them
(curve ends and pcurves up to a tolerance apart): export_step -> import_step keeps counts, area
and volume to 1e-9.

A STEP file carries neither edge ranges nor per-edge tolerances, only vertices and one
uncertainty for the whole file. OCC's reader rebuilds an edge's range by projecting its vertices
onto its 3-D curve (and its pcurves' ranges by projecting the curve's ends onto their traces), and
re-fits a pcurve by projection where it lies further than twice the file's uncertainty from its
curve. Two writer settings keep a loose part as it is (see ``splinekit.interop.occ_brep_write``
and ``exporters.step``):

* each vertex lies in the normal plane of every incident curve end, so it projects onto the ends;
* the file's uncertainty is the part's greatest tolerance (OCC's ``write.precision.mode`` = 1).

Each test builds a build123d box with a hole, loosens it by a known amount by hand, checks the round
trip keeps it, and then switches the setting off (monkeypatch) to check the round trip loses the
part by far more than 1e-9: without the setting the test fails. References: OCC's GProp (at eps
1e-10) on the shape written and on the shape read back, TopExp counts.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

build123d = pytest.importorskip("build123d")

from OCP.BRepGProp import BRepGProp  # noqa: E402
from OCP.GProp import GProp_GProps  # noqa: E402

import exporters  # noqa: E402
import splinekit as sk  # noqa: E402
from exporters import step as step_module  # noqa: E402
from splinekit.brep import Edge, Shell, Solid, TrimmedFace  # noqa: E402
from splinekit.curves import BSplineCurve  # noqa: E402
from splinekit.interop import occ_brep_write  # noqa: E402
from splinekit.interop.occ_brep import brep_to_shape  # noqa: E402
from splinekit.interop.occ_shapes import _sub_shapes  # noqa: E402
from splinekit.surfaces import BSplineSurface  # noqa: E402
from test_same_parameter import with_edge_tolerance  # noqa: E402

LOOSE = 0.05
"""How far the loosened curve ends and pcurves lie from where the exact part has them (mm); NX
and CATIA files carry edge tolerances this large."""


def _box_with_hole():
    (solid,) = sk.occ.from_occ((build123d.Box(30, 20, 10) - build123d.Cylinder(3, 10)).wrapped)
    return solid


def _measure(shape):
    """``(counts of faces, edges, vertices), volume, area`` by OCC (TopExp, GProp at eps 1e-10)."""
    v, a = GProp_GProps(), GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, v, 1e-10)
    BRepGProp.SurfaceProperties_s(shape, a, 1e-10)
    return [len(_sub_shapes(shape, k)) for k in ("FACE", "EDGE", "VERTEX")], v.Mass(), a.Mass()


def _round_trip(solid, path):
    """The change of ``solid`` over export_step -> import_step: ``(counts before, counts after,
    relative volume change, relative area change)``."""
    exporters.export_step(path, [solid])
    (again,) = exporters.import_step(path)
    (c0, v0, a0), (c1, v1, a1) = _measure(brep_to_shape(solid)), _measure(brep_to_shape(again.geometry))
    return c0, c1, abs(v1 - v0) / v0, abs(a1 - a0) / a0


def _enlarged(surface, margin):
    """A bilinear plane patch extended by ``margin`` on every side, with the same (affine) map
    from (u, v) to space, so the pcurves on it stay where they are."""
    (u0, u1), (v0, v1) = surface.domain
    C = np.asarray(surface.control_points)
    du, dv = (C[1, 0] - C[0, 0]) / (u1 - u0), (C[0, 1] - C[0, 0]) / (v1 - v0)
    us, vs = np.array([u0 - margin, u1 + margin]), np.array([v0 - margin, v1 + margin])
    P = C[0, 0] + (us - u0)[:, None, None] * du + (vs - v0)[None, :, None] * dv
    return BSplineSurface(1, 1, [us[0]] * 2 + [us[1]] * 2, [vs[0]] * 2 + [vs[1]] * 2, P)


def _shifted_end(use, corner, shift, tolerance):
    """The straight ``use`` with its end at ``corner`` moved ``shift`` mm along the edge, away
    from the edge (``shift < 0``: beyond the corner), its 3-D line and pcurve alike."""
    P, Q = np.array(use.curve.control_points), np.array(use.pcurve.control_points)
    i = 0 if np.linalg.norm(P[0] - corner) < np.linalg.norm(P[1] - corner) else 1
    f = shift / float(np.linalg.norm(P[1] - P[0]))
    P[i] += f * (P[1 - i] - P[i])
    Q[i] += f * (Q[1 - i] - Q[i])
    curve = BSplineCurve(1, use.curve.knots, P)
    return Edge(BSplineCurve(1, use.pcurve.knots, Q), curve, key=use.key, tolerance=tolerance)


def _loose_corner(solid, eps):
    """``solid`` with one box corner loosened: of its three edges, the one along x runs ``eps``
    past the corner and the other two stop ``eps`` short of it (3-D lines and pcurves alike, edge
    tolerance ``2 eps``), so the three curve ends lie 1.4 ``eps`` apart around the corner. The plane
    faces are enlarged so the pcurve running past the corner stays on its surface."""
    corner = np.array([-15.0, -10.0, 5.0])
    keys = {}
    for f in solid.faces:
        for loop in f.loops:
            for e in loop:
                P = np.asarray(e.curve.control_points) if e.curve is not None else None
                if P is not None and len(P) == 2 and np.min(np.linalg.norm(P - corner, axis=1)) < 1e-9:
                    along_x = abs(P[1, 0] - P[0, 0]) > 1.0
                    keys[e.key] = -eps if along_x else eps
    assert len(keys) == 3
    faces = []
    for f in solid.faces:
        planar = isinstance(f.surface, BSplineSurface) and f.surface.degree_u == f.surface.degree_v == 1
        loops = [[_shifted_end(e, corner, keys[e.key], 2 * eps) if e.key in keys else e for e in loop]
                 for loop in f.loops]
        faces.append(TrimmedFace(_enlarged(f.surface, 1.0) if planar else f.surface, loops,
                                 reversed=f.reversed, tolerance=f.tolerance))
    return Solid([Shell(faces)])


def _bulged_pcurve(solid, bulge):
    """``solid`` with the pcurve of one straight edge on one plane face bent sideways (a quadratic
    whose middle pole lies ``bulge`` mm off the segment): the trace lies up to ``bulge / 2`` off the
    3-D line, the edge's tolerance covers that, every other edge stays at 1e-7."""
    faces = list(solid.faces)
    for i, f in enumerate(faces):
        for j, loop in enumerate(f.loops):
            for k, use in enumerate(loop):
                if use.curve is None or use.pcurve.degree != 1 or len(np.asarray(use.pcurve.control_points)) != 2:
                    continue
                A, B = np.asarray(use.pcurve.control_points)
                normal = np.array([-(B - A)[1], (B - A)[0]]) / np.linalg.norm(B - A)
                mid = (A + B) / 2 + bulge * normal
                a, b = use.domain
                pcurve = BSplineCurve(2, [a] * 3 + [b] * 3, [A, mid, B])
                loops = [list(lp) for lp in f.loops]
                loops[j][k] = Edge(pcurve, use.curve, key=use.key, tolerance=bulge)
                faces[i] = TrimmedFace(f.surface, loops, reversed=f.reversed, tolerance=f.tolerance)
                return Solid([Shell(with_edge_tolerance(faces, use.key, bulge, but=i))])  # the other use too
    raise AssertionError("the part has no straight edge")


def test_a_loose_corner_keeps_its_edges_ranges(tmp_path, monkeypatch):
    loose = _loose_corner(_box_with_hole(), LOOSE)
    c0, c1, dv, da = _round_trip(loose, tmp_path / "corner.step")
    assert c0 == c1 == [7, 15, 10]
    assert dv <= 1e-9 and da <= 1e-9
    # mutation: vertices at the centroid of their curve ends; the reader then shortens the edge
    # running past the corner (its range starts where the centroid projects) and cuts its
    # pcurves with it, a corner of each face it bounds (measured: area 9.0e-5, volume 8.1e-5)
    monkeypatch.setattr(occ_brep_write, "_vertex_points", lambda centers, *_: centers)
    c0, c1, dv, da = _round_trip(loose, tmp_path / "centroid.step")
    assert c0 == c1
    assert da > 1e-6 and dv > 1e-6


def test_a_loose_pcurve_is_not_refitted(tmp_path, monkeypatch):
    bulged = _bulged_pcurve(_box_with_hole(), 10 * LOOSE)
    c0, c1, dv, da = _round_trip(bulged, tmp_path / "bulge.step")
    assert c0 == c1 == [7, 15, 10]
    assert dv <= 1e-9 and da <= 1e-9
    # mutation: OCC's default uncertainty (the mean tolerance): the reader re-fits the bent pcurve
    # onto the 3-D line, which takes the bulge off the face (measured: area 7.2e-4, volume 1.5e-3)
    monkeypatch.setattr(step_module, "_WRITE_PRECISION_GREATEST", 0)
    c0, c1, dv, da = _round_trip(bulged, tmp_path / "average.step")
    assert c0 == c1
    assert da > 1e-5 and dv > 1e-5


def test_the_first_export_of_a_process_applies_its_settings(tmp_path):
    """OCC's STEP statics (unit, uncertainty mode) exist only once its STEP controller is set up;
    the first export of a fresh process used to set them before that, silently in vain (a file
    asked for in inches came out in millimetres)."""
    path = tmp_path / "inch.step"
    code = ("import numpy as np, exporters, splinekit as sk; "
            "exporters.export_step(%r, sk.BSplineCurve(1, [0, 0, 1, 1], np.eye(3)[:2]), unit='inch')" % str(path))
    subprocess.run([sys.executable, "-c", code], check=True, timeout=300)
    assert "INCH" in path.read_text()


def test_a_vertex_goes_past_every_curve_end_where_their_planes_do_not_meet():
    """Four curve ends whose normal planes meet nowhere (CATIA's ventilator has such vertices: two
    edges continuing each other, a third parallel to them ending 1e-5 mm on). The least-squares
    point lies inside one of them, where the STEP reader would cut that edge; the vertex goes to
    the nearest point past every end instead. Closed form: ends at the origin pointing out along
    +x, -x and +y, and one at x = 1e-5 pointing out along -x: the least-squares point is
    (1e-5 / 3, 0, z), the nearest point with 0 <= x <= 0 (and x <= 1e-5, y >= 0) is (0, 0, z)."""
    P = np.array([[0.0, 0, 0], [0, 0, 0], [1e-5, 0, 0], [0, 0, 0]])
    T = np.array([[1.0, 0, 0], [-1, 0, 0], [-1, 0, 0], [0, 1, 0]])
    center = np.array([[1e-6, -2e-6, 3e-6]])
    V = occ_brep_write._vertex_points(center, np.zeros(4, dtype=int), P, T)
    assert np.allclose(V, [[0.0, 0.0, 3e-6]], rtol=0, atol=1e-15)
    # planes that meet in one point keep it: three ends along the axes, at a common corner
    corner = np.array([1.0, 2.0, 3.0])
    V = occ_brep_write._vertex_points(center + corner, np.zeros(3, dtype=int), np.tile(corner, (3, 1)), np.eye(3))
    assert np.allclose(V, [corner], rtol=0, atol=1e-15)
