"""The batched searches of the reader's SameParameter step (splinekit.interop.occ_same_parameter)
against the one-use route through ``splinekit.project`` they replace, and against closed forms.

* ``_onto_curve_parameters`` (all uses of a face at once) gives the same composed pcurves as
  ``_onto_curve_parameter`` (one use through ``project``) to 1e-12 in parameter;
* ``_aparts`` (all uses at once) gives the same largest trace-to-curve distances as
  ``project(...).distances.max()`` (one use at a time);
* on a plane, a unit-circle pcurve and a 3-D circle of radius 1 + d about the same centre: every
  breakpoint lands on the foot point ``P / |P|`` and the distance is ``d`` (closed forms).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import splinekit as sk
from splinekit.basis.knots import clamped_uniform
from splinekit.brep import Edge
from splinekit.curves import BSplineCurve, NurbsCurve
from splinekit.interop.occ_same_parameter import (
    _aparts,
    _deviations,
    _onto_curve_parameter,
    _onto_curve_parameters,
    compose_piecewise_linear,
)


def _face(rng, count):
    """A wavy bicubic surface on [0, 1]^2 and ``count`` uses: random cubic pcurves inside the
    domain, each with a 3-D curve through the surface at its poles (near the trace, at another
    parameter: the pcurve is composed with a random increasing piecewise-linear map)."""
    U = clamped_uniform(3, 6)
    g = np.linspace(0.0, 10.0, 6)
    P = np.empty((6, 6, 3))
    P[..., 0], P[..., 1] = g[:, None], g[None, :]
    P[..., 2] = rng.uniform(-2.0, 2.0, (6, 6))
    surface = sk.BSplineSurface(3, 3, U, U, P)
    uses = []
    for _ in range(count):
        a = float(rng.uniform(-1.0, 1.0))
        b = a + float(rng.uniform(0.5, 3.0))
        knots = np.concatenate([[a] * 4, np.sort(rng.uniform(a, b, 2)), [b] * 4])
        pc = BSplineCurve(3, knots, rng.uniform(0.1, 0.9, (6, 2)))
        tb = np.linspace(a, b, 4)
        sb = np.concatenate([[a], np.sort(rng.uniform(a + 0.05 * (b - a), b - 0.05 * (b - a), 2)), [b]])
        lag = compose_piecewise_linear(pc, tb, sb)
        poles = surface.evaluate(lag.control_points[:, 0], lag.control_points[:, 1])
        uses.append(Edge(pc, BSplineCurve(3, lag.knots, poles), key=len(uses)))
    return surface, uses


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), pieces=st.sampled_from([16, 64]))
def test_batched_search_matches_one_use_at_a_time(seed, pieces):
    rng = np.random.default_rng(seed)
    surface, uses = _face(rng, int(rng.integers(1, 5)))
    _, on = _deviations(surface, [u.pcurve for u in uses], [u.curve for u in uses])
    extents = [float(np.abs(x).max()) for x in on]
    got = _onto_curve_parameters(surface, uses, extents, pieces)
    for use, new in zip(uses, got):
        old = _onto_curve_parameter(surface, use, pieces)
        assert (new is None) == (old is None)
        if old is not None:
            assert np.asarray(new.knots).shape == np.asarray(old.knots).shape
            np.testing.assert_allclose(new.knots, old.knots, rtol=0, atol=1e-12)
            np.testing.assert_allclose(new.control_points, old.control_points, rtol=0, atol=1e-12)
    aparts = _aparts(uses, on)
    for use, pts, apart in zip(uses, on, aparts):
        assert apart == pytest.approx(float(sk.project(use.curve, pts).distances.max()), rel=1e-10, abs=1e-13)


def _plane_and_circles(d):
    """The plane ``(u, v, 0)`` over [-2, 2]^2, the unit circle as a pcurve and, as the 3-D curve,
    the circle of radius ``1 + d`` about the same centre on another parameter (its knots moved)."""
    plane = sk.BSplineSurface(1, 1, [-2, -2, 2, 2], [-2, -2, 2, 2],
                              [[[-2.0, -2.0, 0.0], [-2.0, 2.0, 0.0]], [[2.0, -2.0, 0.0], [2.0, 2.0, 0.0]]])
    unit = sk.circle([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0)
    pc = NurbsCurve(2, unit.knots, np.asarray(unit.control_points)[:, :2], unit.weights)
    a, b = pc.domain
    big = sk.circle([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0 + d)
    curve = compose_piecewise_linear(big, np.linspace(a, b, 4), a + (b - a) * np.array([0.0, 0.2, 0.45, 1.0]))
    return plane, Edge(pc, curve, key=0)


@pytest.mark.parametrize("d", [0.0, 1e-4, 0.01])
def test_circle_closed_forms(d):
    plane, use = _plane_and_circles(d)
    [pc] = _onto_curve_parameters(plane, [use], [1.0], 16)
    a, b = use.domain
    t = np.linspace(a, b, 17)
    P = use.curve.evaluate(t)
    foot = P / np.linalg.norm(P, axis=1)[:, None]  # the unit circle's point nearest to P
    np.testing.assert_allclose(pc.evaluate(t), foot[:, :2], rtol=0, atol=1e-12)
    _, on = _deviations(plane, [use.pcurve], [use.curve])
    [apart] = _aparts([use], on)
    assert apart == pytest.approx(d, rel=1e-9, abs=1e-14)
