"""A loop corner whose pcurve runs past its edge's curve end: import_step settles it, so that
import -> export -> import keeps area and volume to 1e-9 (NX 9's face 30 had one).

OCC's STEP reader sets a pcurve's range by projecting the curve's end onto the pcurve's trace; a
trace that runs past the curve's end gets a shorter range than the curve, the reader re-fits the
pcurve from the curve and repairs the loop around it (see ``exporters._step_corners``). The part
below has one such corner, made by hand on a build123d box with a rounded vertical edge, where,
as on NX's part, the loose edge is continued tangentially by an edge of other faces (so the
vertex cannot follow a lengthened curve). References: OCC's GProp (eps 1e-10) and TopExp counts
on the shapes before and after; the projection of the curve end onto the trace by dense sampling.
"""

from __future__ import annotations

import numpy as np
import pytest

build123d = pytest.importorskip("build123d")

import exporters  # noqa: E402
import splinekit as sk  # noqa: E402
from exporters import _step_corners, step as step_module  # noqa: E402
from splinekit.brep import Edge, Shell, Solid, TrimmedFace  # noqa: E402
from splinekit.curves import BSplineCurve  # noqa: E402
from splinekit.interop.occ_brep import brep_to_shape  # noqa: E402
from test_same_parameter import with_edge_tolerance  # noqa: E402
from test_step_loose_roundtrip import _box_with_hole, _enlarged, _measure  # noqa: E402

OVER = 0.01
"""How far (mm) the loosened pcurve's trace runs past its curve's end."""


def _filleted_box():
    """A build123d box 30 x 20 x 10 with one vertical edge rounded (radius 3), as a Solid."""
    part = build123d.fillet(build123d.Box(30, 20, 10).edges().filter_by(build123d.Axis.Z)[0], radius=3)
    (solid,) = sk.occ.from_occ(part.wrapped)
    return solid


def _planar(face) -> bool:
    return face.surface.degree_u == face.surface.degree_v == 1


def _overshooting_corner(solid, over):
    """``solid`` (the filleted box) with one corner of a flat side loosened in (u, v) only, as NX's
    face 30 was: at the top end of the edge where the side meets the rounding, the pcurve of the
    side's top edge runs ``over`` mm on, past its curve's end (into the rounding's side, where the
    top edge is continued tangentially by the rounding's arc), and the pcurve of the vertical edge
    ends there too, so the loop stays closed in (u, v). Both 3-D curves and the other faces keep
    the exact corner; both edges get tolerance 2 ``over``; the side is enlarged so the longer
    pcurve stays on it. Returns the loose solid, the side's index, the two uses' positions in its
    loop and the corner."""
    faces = list(solid.faces)
    rounding = next(i for i, f in enumerate(faces) if not _planar(f))
    vertical = {e.key for e in faces[rounding].loops[0] if np.ptp(np.asarray(e.curve.control_points)[:, 2]) > 1}
    side = next(i for i, f in enumerate(faces) if _planar(f) and any(e.key in vertical for e in f.loops[0]))
    f = faces[side]
    loop = list(f.loops[0])
    k_v = next(k for k, e in enumerate(loop) if e.key in vertical)
    up = loop[k_v]
    ends = up.curve.evaluate(np.array(up.domain))
    at_top = int(np.argmax(ends[:, 2]))
    corner = ends[at_top]
    k_t = (k_v + 1) % len(loop) if at_top == 1 else k_v - 1  # the top edge, meeting it at the corner
    top = loop[k_t]
    top_ends = top.curve.evaluate(np.array(top.domain))
    i = -1 if np.linalg.norm(top_ends[1] - corner) < np.linalg.norm(top_ends[0] - corner) else 0
    Q, R = np.array(top.pcurve.control_points), np.array(up.pcurve.control_points)
    mm_per_uv = np.linalg.norm(top_ends[1] - top_ends[0]) / np.linalg.norm(Q[-1] - Q[0])
    Q[i] += (Q[i] - Q[-1 - i]) / np.linalg.norm(Q[i] - Q[-1 - i]) * over / mm_per_uv
    R[-1 if at_top == 1 else 0] = Q[i]
    tol = 2 * over
    loop[k_t] = Edge(BSplineCurve(top.pcurve.degree, top.pcurve.knots, Q), top.curve, key=top.key, tolerance=tol)
    loop[k_v] = Edge(BSplineCurve(up.pcurve.degree, up.pcurve.knots, R), up.curve, key=up.key, tolerance=tol)
    faces[side] = TrimmedFace(_enlarged(f.surface, 1.0), [loop, *f.loops[1:]], reversed=f.reversed,
                              tolerance=f.tolerance)
    for key in (top.key, up.key):
        faces = with_edge_tolerance(faces, key, tol, but=side)
    return Solid([Shell(faces)]), side, (k_t, k_v, i), corner


def _round_trip(solid, path):
    """``(counts before, counts after, relative volume change, relative area change)`` of
    ``solid`` over export_step -> import_step."""
    exporters.export_step(path, [solid])
    (again,) = exporters.import_step(path)
    (c0, v0, a0), (c1, v1, a1) = _measure(brep_to_shape(solid)), _measure(brep_to_shape(again.geometry))
    return c0, c1, abs(v1 - v0) / v0, abs(a1 - a0) / a0


def test_an_overshooting_pcurve_is_settled_where_the_curve_end_projects():
    loose, side, (k_t, k_v, i), corner = _overshooting_corner(_filleted_box(), OVER)
    settled = _step_corners.settle_corners(loose)
    face = settled.faces[side]
    top, up = face.loops[0][k_t], face.loops[0][k_v]
    # independent: the point of the loosened trace nearest the curve's end, by dense sampling
    old = loose.faces[side].loops[0][k_t]
    t = np.linspace(*old.domain, 400001)
    uv = old.pcurve.evaluate(t)
    nearest = uv[np.argmin(np.linalg.norm(loose.faces[side].surface.evaluate(uv[:, 0], uv[:, 1]) - corner, axis=1))]
    end_uv = top.pcurve.evaluate(np.array([top.domain[i]]))[0]
    assert np.linalg.norm(end_uv - nearest) <= np.linalg.norm(uv[1] - uv[0])
    # the vertical edge's pcurve follows, so the loop stays closed in (u, v)
    up_uv = up.pcurve.evaluate(np.array(up.domain))
    assert np.min(np.linalg.norm(up_uv - end_uv, axis=1)) <= 1e-15
    # the trace is straight along the edge, so the corner is back on the exact corner
    assert np.allclose(face.surface.evaluate(end_uv[:1], end_uv[1:])[0], corner, rtol=0, atol=1e-9)
    # the other faces are the same objects, and a part without such corners comes back as it is
    assert all(a is b for j, (a, b) in enumerate(zip(loose.faces, settled.faces)) if j != side)
    exact = _filleted_box()
    assert _step_corners.settle_corners(exact) is exact


def test_a_settled_corner_survives_the_round_trip(tmp_path):
    loose, *_ = _overshooting_corner(_filleted_box(), OVER)
    c0, c1, dv, da = _round_trip(_step_corners.settle_corners(loose), tmp_path / "settled.step")
    assert c0 == c1 == [7, 15, 10]
    assert dv <= 1e-9 and da <= 1e-9
    # mutation: the part as it is. OCC's reader re-fits the overshooting pcurve from its curve and
    # repairs the loop around it, which ends back on the exact corner (measured: volume 7.0e-5,
    # area 4.6e-5)
    c0, c1, dv, da = _round_trip(loose, tmp_path / "loose.step")
    assert c0 == c1
    assert dv > 1e-6 and da > 1e-6


def test_import_step_settles_every_object(tmp_path, monkeypatch):
    """import_step hands every object it reads to settle_corners before checking it."""
    seen = []
    monkeypatch.setattr(step_module, "settle_corners", lambda obj: seen.append(obj) or obj)
    exact = _box_with_hole()
    exporters.export_step(tmp_path / "two.step", [exact, exact])
    items = exporters.import_step(tmp_path / "two.step")
    assert [it.geometry for it in items] == seen and len(seen) == 2
