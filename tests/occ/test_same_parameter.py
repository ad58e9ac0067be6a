"""Edge uses whose pcurve traces the 3-D curve at another parameter (as in STEP files from CATIA,
Alias, Onshape): the reader moves the pcurve onto the curve's parameter without changing its
trace, and the writer's tolerance covers what is left, so OCC accepts the rebuilt solid and a STEP
round trip keeps counts, area and volume.

Before: the reader dropped such a use's 3-D curve; the writer then built the edge's curve from the
other face's pcurve with a tolerance that did not cover this one, and OCC refused the re-read
ventilator ("BRepCheck_UnorientableShape" on the face, from an InvalidCurveOnSurface on its edge).

References, independent of the code under test: the lagging pcurve is built by hand (a quadratic
with an off-centre middle pole on the straight edge: same segment, parameter ``g(s) = s (1 + s)
/ 2``); the trace is checked against that segment in closed form, the lag against the 3-D curve
at sampled parameters, validity with OCC's BRepCheck (exact edge check), area and volume with
OCC's GProp and the box's closed form.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

build123d = pytest.importorskip("build123d")

from OCP.BRepCheck import BRepCheck_Analyzer  # noqa: E402
from OCP.BRepGProp import BRepGProp  # noqa: E402
from OCP.GProp import GProp_GProps  # noqa: E402

import exporters  # noqa: E402
import splinekit as sk  # noqa: E402
from splinekit.brep import Edge, Shell, Solid, TrimmedFace  # noqa: E402
from splinekit.curves import BSplineCurve, NurbsCurve  # noqa: E402
from splinekit.interop.occ_brep import brep_to_shape  # noqa: E402
from splinekit.interop.occ_same_parameter import compose_piecewise_linear, same_parameter  # noqa: E402
from splinekit.interop.occ_shapes import _sub_shapes  # noqa: E402


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2 ** 32 - 1), st.integers(1, 6), st.booleans())
def test_composition_with_a_piecewise_linear_map_is_exact(seed, pieces, rational):
    """``compose_piecewise_linear(c, tb, sb)(t) == c(phi(t))`` with ``phi`` the map np.interp
    draws through the breakpoints, for random curves and maps."""
    rng = np.random.default_rng(seed)
    knots = np.concatenate([[0.0] * 4, np.sort(rng.random(3)), [1.0] * 4])
    P = rng.normal(size=(7, 2))
    curve = NurbsCurve(3, knots, P, rng.uniform(0.5, 2.0, 7)) if rational else BSplineCurve(3, knots, P)
    sb = np.concatenate([[0.0], np.sort(rng.uniform(0.02, 0.98, pieces)), [1.0]])
    sb = np.maximum.accumulate(sb + 1e-3 * np.arange(len(sb))) / (1.0 + 1e-3 * (len(sb) - 1))  # strictly increasing
    tb = np.concatenate([[2.0], 2.0 + np.sort(rng.uniform(0.0, 3.0, pieces)), [5.0]])
    tb = tb + 1e-3 * np.arange(len(tb))
    out = compose_piecewise_linear(curve, tb, sb)
    t = np.linspace(tb[0], tb[-1], 301)
    assert out.domain == pytest.approx((tb[0], tb[-1]), abs=1e-15)
    np.testing.assert_allclose(out.evaluate(t), curve.evaluate(np.interp(t, tb, sb)), rtol=0, atol=1e-12)


def _occ(shape):
    v, a = GProp_GProps(), GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, v, 1e-10)
    BRepGProp.SurfaceProperties_s(shape, a, 1e-10)
    return v.Mass(), a.Mass()


def _exactly_valid(shape) -> bool:
    # exact edge check (every pcurve against its 3-D curve, not OCC's sparse samples)
    return bool(BRepCheck_Analyzer(shape, True, False, True).IsValid())


def _lagging(solid):
    """``solid`` with the first straight use on a plane face replaced by a pcurve that runs along
    the same segment at the parameter ``g(s) = s (1 + s) / 2`` (and no tighter tolerance than
    OCC's), like a foreign file's; returns the new solid, that face's index and the segment."""
    faces = list(solid.faces)
    for i, f in enumerate(faces):
        for j, loop in enumerate(f.loops):
            for k, use in enumerate(loop):
                pc = use.pcurve
                if use.curve is None or pc.degree != 1 or len(pc.control_points) != 2:
                    continue
                A, B = np.asarray(pc.control_points)
                lag = BSplineCurve(2, [use.domain[0]] * 3 + [use.domain[1]] * 3, [A, A + 0.25 * (B - A), B])
                moved = Edge(lag, use.curve, key=use.key, tolerance=use.tolerance)
                loops = [list(lp) for lp in f.loops]
                loops[j][k] = moved
                faces[i] = TrimmedFace(f.surface, loops, reversed=f.reversed, tolerance=f.tolerance)
                return Solid([Shell(faces)]), i, (A, B), use
    raise AssertionError("the part has no straight edge")


def test_a_lagging_pcurve_moves_onto_the_curve_parameter_and_the_round_trip_keeps_the_part(tmp_path):
    part = build123d.Box(30, 20, 10) - build123d.Cylinder(3, 10)
    (solid,) = sk.occ.from_occ(part.wrapped)
    lagging, i, (A, B), before = _lagging(solid)
    face = lagging.faces[i]
    use = next(e for lp in face.loops for e in lp if e.key == before.key)
    t = np.linspace(*use.domain, 201)
    on = face.surface.evaluate(*use.pcurve.evaluate(t).T)
    lag = float(np.linalg.norm(on - use.curve.evaluate(t), axis=1).max())
    assert lag > 1.0  # a quarter of a 20 or 30 mm edge off at the same parameter

    fixed = same_parameter(face.surface, face.loops)
    got = next(e for lp in fixed for e in lp if e.key == before.key)
    assert got.curve is not None  # kept, not dropped
    uv = got.pcurve.evaluate(t)
    # the trace is still the segment A-B (closed form), from A to B
    d = B - A
    cross = (uv[:, 0] - A[0]) * d[1] - (uv[:, 1] - A[1]) * d[0]
    assert np.abs(cross).max() <= 1e-9 * float(np.linalg.norm(d)) ** 2
    np.testing.assert_allclose(uv[[0, -1]], [A, B], rtol=0, atol=1e-12)
    # on the 3-D curve's parameter now, within the tolerance it carries
    dev = float(np.linalg.norm(face.surface.evaluate(*uv.T) - got.curve.evaluate(t), axis=1).max())
    assert dev <= got.tolerance
    assert dev <= 1e-3 * lag

    # the whole chain from the fixed part: OCC shape (valid under the exact check), written to
    # STEP and read again
    loops = [list(lp) for lp in fixed]
    part_faces = list(lagging.faces)
    part_faces[i] = TrimmedFace(face.surface, loops, reversed=face.reversed, tolerance=face.tolerance)
    shape = brep_to_shape(Solid([Shell(part_faces)]))
    assert _exactly_valid(shape)
    exporters.export_step(tmp_path / "lag.step", [Solid([Shell(part_faces)])])
    again = exporters.import_step(tmp_path / "lag.step")
    assert len(again) == 1
    final = brep_to_shape(again[0].geometry)
    assert _exactly_valid(final)
    counts = [[len(_sub_shapes(s, k)) for k in ("FACE", "EDGE", "VERTEX")] for s in (shape, final)]
    assert counts[0] == counts[1] == [7, 15, 10]
    (v0, a0), (v1, a1) = _occ(shape), _occ(final)
    assert v0 == pytest.approx(30 * 20 * 10 - np.pi * 9 * 10, rel=1e-9)
    assert v1 == pytest.approx(v0, rel=1e-9) and a1 == pytest.approx(a0, rel=1e-9)


def test_the_writer_covers_a_use_without_a_3d_curve_within_the_uses_tolerances():
    """A use with no 3-D curve whose trace lags the other use's by up to twice the edge tolerance
    (what the reader used to leave): the written edge's tolerance covers the lag, so OCC's exact
    check passes. Further apart, the solid is bad and is left for OCC to refuse."""
    part = build123d.Box(30, 20, 10) - build123d.Cylinder(3, 10)
    (solid,) = sk.occ.from_occ(part.wrapped)
    lagging, i, _, before = _lagging(solid)
    face = lagging.faces[i]
    use = next(e for lp in face.loops for e in lp if e.key == before.key)
    t = np.linspace(*use.domain, 201)
    lag = float(np.linalg.norm(face.surface.evaluate(*use.pcurve.evaluate(t).T) - use.curve.evaluate(t), axis=1).max())
    for tolerance, valid in ((0.6 * lag, True), (0.3 * lag, False)):
        loops = [[Edge(e.pcurve, None, key=e.key, tolerance=tolerance) if e.key == before.key else e for e in lp]
                 for lp in face.loops]
        faces = list(lagging.faces)
        faces[i] = TrimmedFace(face.surface, loops, reversed=face.reversed, tolerance=face.tolerance)
        faces = with_edge_tolerance(faces, before.key, tolerance, but=i)  # the edge's other use too
        assert _exactly_valid(brep_to_shape(Solid([Shell(faces)]))) == valid


def with_edge_tolerance(faces, key, tolerance, but):
    """``faces`` (a list of TrimmedFace) with every use of the edge ``key`` on a face other than
    ``faces[but]`` given ``tolerance``: both uses of a loosened edge carry one tolerance."""
    out = list(faces)
    for j, g in enumerate(faces):
        if j != but and any(e.key == key for lp in g.loops for e in lp):
            out[j] = TrimmedFace(g.surface, [[Edge(e.pcurve, e.curve, key=e.key, tolerance=tolerance)
                                              if e.key == key else e for e in lp] for lp in g.loops],
                                 reversed=g.reversed, tolerance=g.tolerance)
    return out
