"""Edge uses read from OpenCascade made SameParameter: each pcurve, seen through its surface,
follows the edge's 3-D curve at the same parameter, within a tolerance that covers what is left.

STEP files from other systems often give an edge pcurves that trace the 3-D curve's points but
not at its parameter (a CATIA ventilator edge: the surface at the pcurve runs 6.5e-4 mm off the
3-D curve at the same parameter while staying 1.5e-5 mm from it; an Alias edge 1.3e-3 mm), beyond
the tolerance OCC gives the edge (its check looks at a few samples only). Such a use must keep its
3-D curve: a use without one leaves the edge, once written, to the curve OCC builds from another
face's pcurve, which need not share this one's parameter (the re-read ventilator was refused so:
an InvalidCurveOnSurface that OCC reports as an "unorientable" face).

:func:`same_parameter` therefore puts such a pcurve on the 3-D curve's parameter without changing
its trace: the new pcurve is the old one composed with a piecewise-linear parameter map
(:func:`compose_piecewise_linear`: knots moved, control points kept), so the face's trimming
loop, area and volume stay the same to rounding; the tolerance covers the deviation left. The
map's breakpoints come from projecting the 3-D curve's points onto the surface at the pcurve.
"""

from __future__ import annotations

import numpy as np

from ..brep import Edge
from ..closest import project
from ..curves import BSplineCurve, NurbsCurve
from ..tolerances import DEFAULT

__all__ = ["same_parameter", "compose_piecewise_linear"]

MARGIN = 1.1
"""Tolerances cover a measured deviation times this (the check samples the same parameters; the
margin covers rounding only)."""


def compose_piecewise_linear(curve, t_breaks, s_breaks):
    """``curve(phi(t))`` as a spline curve on ``[t_breaks[0], t_breaks[-1]]``, where ``phi`` maps
    each ``t_breaks[i]`` to ``s_breaks[i]`` (both strictly increasing, ``s_breaks`` spanning the
    curve's domain) and is linear in between.

    Exact to rounding: the curve is split at the interior ``s_breaks`` (knots raised to multiplicity
    ``degree``, so each piece depends only on the knots at and inside its own ends) and every knot is
    mapped by ``phi``'s inverse, which is affine on each piece; the control points (and weights) do
    not change. The pieces meet with C0 continuity in the new parameter (the trace stays as smooth
    as it was)."""
    t_breaks = np.asarray(t_breaks, dtype=np.float64)
    s_breaks = np.asarray(s_breaks, dtype=np.float64)
    p = curve.degree
    knots = np.asarray(curve.knots)
    a, b = curve.domain
    # a breakpoint within the knot tolerance of a knot is that knot (refinement would snap it there)
    distinct = np.unique(knots)
    nearest = distinct[np.abs(distinct[None, :] - s_breaks[:, None]).argmin(axis=1)]
    s_breaks = np.where(np.abs(nearest - s_breaks) <= DEFAULT.knot * (b - a), nearest, s_breaks)
    inner = s_breaks[1:-1]
    keep = np.concatenate([[True], (inner > s_breaks[:-2]) & (inner > a) & (inner < b), [True]])
    t_breaks, s_breaks = t_breaks[keep], s_breaks[keep]
    extra = []
    for s in s_breaks[1:-1]:
        extra += [s] * max(0, p - int(np.count_nonzero(knots == s)))
    refined = curve.refine(extra) if extra else curve
    new_knots = np.interp(np.asarray(refined.knots), s_breaks, t_breaks)
    if refined.weights is None:
        return BSplineCurve(p, new_knots, refined.control_points)
    return NurbsCurve(p, new_knots, refined.control_points, refined.weights)


class _CurveOnSurface:
    """``Q(s) = surface(pcurve(s))``: the 3-D trace of a pcurve, with the evaluate / derivatives /
    domain that :func:`splinekit.project` needs (derivatives up to order 2, by the chain rule)."""

    def __init__(self, surface, pcurve):
        self.surface, self.pcurve = surface, pcurve
        self.domain = pcurve.domain
        (self._u0, self._u1), (self._v0, self._v1) = surface.domain

    def _uv(self, uv):
        # a file's pcurve may overshoot the surface's domain by a rounding
        return np.clip(uv[..., 0], self._u0, self._u1), np.clip(uv[..., 1], self._v0, self._v1)

    def evaluate(self, s):
        return self.surface.evaluate(*self._uv(np.atleast_2d(self.pcurve.evaluate(np.atleast_1d(s)))))

    def derivatives(self, s, order):
        s = np.atleast_1d(np.asarray(s, dtype=np.float64))
        c = self.pcurve.derivatives(s, 2)  # (3, n, 2): pcurve, its first and second derivatives
        S = self.surface.derivatives(*self._uv(c[0]), 2)  # (3, 3, n, 3)
        du, dv, ddu, ddv = c[1][:, :1], c[1][:, 1:], c[2][:, :1], c[2][:, 1:]
        out = [S[0, 0], S[1, 0] * du + S[0, 1] * dv,
               S[2, 0] * du ** 2 + 2.0 * S[1, 1] * du * dv + S[0, 2] * dv ** 2 + S[1, 0] * ddu + S[0, 1] * ddv]
        return np.stack(out[:order + 1])


def _onto_curve_parameter(surface, use, pieces: int):
    """The use's pcurve composed with the piecewise-linear map (``pieces`` pieces, breakpoints at
    equal steps of the 3-D curve's parameter) that sends each breakpoint to the parameter of the
    trace's point closest to the 3-D curve's point there, or None if that map is not increasing."""
    a, b = use.domain
    t = np.linspace(a, b, pieces + 1)
    trace = _CurveOnSurface(surface, use.pcurve)
    s = np.array(project(trace, use.curve.evaluate(t[1:-1]), seeds=t[1:-1]).parameters, dtype=np.float64).ravel()
    s = np.concatenate([[a], s, [b]])
    if not (np.diff(s) > 1e-12 * (b - a)).all():
        return None
    return compose_piecewise_linear(use.pcurve, t, s)


def _deviation(surface, pcurve, curve, t) -> float:
    """Largest distance between ``surface(pcurve(t))`` and ``curve(t)`` over the parameters ``t``."""
    return float(np.linalg.norm(_CurveOnSurface(surface, pcurve).evaluate(t) - curve.evaluate(t), axis=1).max())


def _samples(use, per_span: int = 17) -> np.ndarray:
    """Parameters of ``use``: ``per_span`` in each Bézier span of its pcurve and of its 3-D curve."""
    a, b = use.domain
    br = np.union1d(use.pcurve.bezier_breakpoints(), use.curve.bezier_breakpoints())
    br = np.union1d(br[(br > a) & (br < b)], [a, b])
    return (br[:-1, None] + (br[1:] - br[:-1])[:, None] * np.linspace(0.0, 1.0, per_span)[None]).ravel()


def _reparametrized(surface, use, dev: float, apart: float):
    """``(pcurve, deviation left)``: the use's pcurve on its 3-D curve's parameter, with 16 to 256
    pieces (four times more while that halves the deviation left and it exceeds twice ``apart``,
    the distance between the two point sets, which no parameter can undo); None when no
    increasing map is found or the best one does not halve ``dev``."""
    best = None
    for pieces in (16, 64, 256):
        pc = _onto_curve_parameter(surface, use, pieces)
        if pc is None:
            break
        got = _deviation(surface, pc, use.curve, _samples(Edge(pc, use.curve)))
        if best is not None and got > 0.5 * best[1]:  # no longer the map's resolution that limits it
            break
        best = (pc, got)
        if got <= 2.0 * apart:
            break
    return best if best is not None and best[1] < 0.5 * dev else None


def same_parameter(surface, loops) -> list:
    """``loops`` (lists of Edges on ``surface``) with each use SameParameter: its tolerance covers
    how far its 3-D curve is from the surface at its pcurve at the same parameter.

    OCC measures that deviation on its own samples and the NURBS conversion re-approximates
    curves, so the figure read from OCC can fall short of the one the curves really have; it is
    measured again here (17 samples per Bézier span; the surface evaluated once for all the uses).
    Where the two are the same point set within much less than the deviation (only their
    parameters disagree), the pcurve is put onto the 3-D curve's parameter without changing its
    trace (:func:`compose_piecewise_linear`) and the tolerance covers what is left; should that
    fail, the tolerance covers the whole deviation. The 3-D curve is never dropped: a use without
    one would leave the edge to another face's pcurve, which need not share this one's parameter."""
    uses = [use for lp in loops for use in lp if use.curve is not None and not use.degenerate]
    if not uses:
        return loops
    samples = [_samples(use) for use in uses]
    uv = np.concatenate([use.pcurve.evaluate(t) for use, t in zip(uses, samples)])
    (u0, u1), (v0, v1) = surface.domain
    on_surface = np.split(surface.evaluate(np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1)),
                          np.cumsum([len(t) for t in samples])[:-1])
    fixed = {}
    for use, t, on in zip(uses, samples, on_surface):
        dev = float(np.linalg.norm(on - use.curve.evaluate(t), axis=1).max())
        if dev <= use.tolerance:
            continue
        apart = float(project(use.curve, on).distances.max())
        if apart >= 0.5 * dev:  # the curves differ in shape, not only in parameter
            fixed[id(use)] = Edge(use.pcurve, use.curve, key=use.key, tolerance=MARGIN * dev)
            continue
        moved = _reparametrized(surface, use, dev, apart)
        if moved is not None:
            pc, left = moved
            fixed[id(use)] = Edge(pc, use.curve, key=use.key, tolerance=max(use.tolerance, MARGIN * left))
        else:  # the curve is kept (a use without one leaves the edge to the other face's pcurve)
            fixed[id(use)] = Edge(use.pcurve, use.curve, key=use.key, tolerance=MARGIN * dev)
    return [[fixed.get(id(use), use) for use in lp] for lp in loops]
