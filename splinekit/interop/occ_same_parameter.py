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
from ..closest import curve_distances, project
from ..closest.newton import newton_search
from ..curves import BSplineCurve, NurbsCurve
from ..curves.batch import CurveBatch
from ..tolerances import DEFAULT, GEOMETRIC_CONFUSION

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


def _uv_clipped(surface, uv):
    """The ``(n, 2)`` parameters ``uv`` clamped onto the surface's domain, as ``(u, v)``: a file's
    pcurve may overshoot the domain by a rounding."""
    (u0, u1), (v0, v1) = surface.domain
    return np.clip(uv[..., 0], u0, u1), np.clip(uv[..., 1], v0, v1)


def _chain(S, c):
    """``Q, Q', Q''`` ``(3, n, 3)`` of ``Q(s) = S(c(s))`` from the surface's derivatives ``S``
    ``(3, 3, n, 3)`` at ``c(s)`` and the pcurve's ``c`` ``(3, n, 2)`` (the chain rule)."""
    du, dv, ddu, ddv = c[1][:, :1], c[1][:, 1:], c[2][:, :1], c[2][:, 1:]
    return np.stack([S[0, 0], S[1, 0] * du + S[0, 1] * dv,
                     S[2, 0] * du ** 2 + 2.0 * S[1, 1] * du * dv + S[0, 2] * dv ** 2 + S[1, 0] * ddu + S[0, 1] * ddv])


class _CurveOnSurface:
    """``Q(s) = surface(pcurve(s))``: the 3-D trace of a pcurve, with the evaluate / derivatives /
    domain that :func:`splinekit.project` needs (derivatives up to order 2, by the chain rule)."""

    def __init__(self, surface, pcurve):
        self.surface, self.pcurve = surface, pcurve
        self.domain = pcurve.domain

    def evaluate(self, s):
        return self.surface.evaluate(*_uv_clipped(self.surface, np.atleast_2d(self.pcurve.evaluate(np.atleast_1d(s)))))

    def derivatives(self, s, order):
        s = np.atleast_1d(np.asarray(s, dtype=np.float64))
        c = self.pcurve.derivatives(s, 2)  # (3, n, 2): pcurve, its first and second derivatives
        return _chain(self.surface.derivatives(*_uv_clipped(self.surface, c[0]), 2), c)[:order + 1]


class _TracesOnSurface:
    """The traces ``surface(pcurve_i(s))`` of many pcurves on one surface, as the batched Newton
    search of :func:`splinekit.closest.newton.newton_search` sees them with ``rows`` (row ``i``: use
    ``i``): ``derivs(x, rows)`` and ``evaluate(x, rows)`` for ``x`` ``(m, 1)``, ``hi`` per row
    ``(n, 1)``, ``size`` per seed (what :func:`splinekit.project` takes for one trace)."""

    def __init__(self, surface, pcurves: CurveBatch, size):
        self.surface, self.pcurves, self.size = surface, pcurves, size
        self.hi = pcurves.domains[:, 1:]

    def derivs(self, x, rows):
        c = self.pcurves.derivatives(rows, x[:, 0], 2)
        d = _chain(self.surface.derivatives(*_uv_clipped(self.surface, c[0]), 2), c)
        return d[0], d[1][..., None], d[2][..., None, None]

    def evaluate(self, x, rows):
        return self.surface.evaluate(*_uv_clipped(self.surface, self.pcurves.evaluate(rows, x[:, 0])))


def _onto_curve_parameter(surface, use, pieces: int):
    """The use's pcurve composed with the piecewise-linear map (``pieces`` pieces, breakpoints at
    equal steps of the 3-D curve's parameter) that sends each breakpoint to the parameter of the
    trace's point closest to the 3-D curve's point there, or None if that map is not increasing.

    One use at a time through :func:`splinekit.project`: the reference that
    :func:`_onto_curve_parameters` (all uses at once) is tested against, and its fallback."""
    a, b = use.domain
    t = np.linspace(a, b, pieces + 1)
    trace = _CurveOnSurface(surface, use.pcurve)
    s = np.array(project(trace, use.curve.evaluate(t[1:-1]), seeds=t[1:-1]).parameters, dtype=np.float64).ravel()
    return _composed(use.pcurve, t, np.concatenate([[a], s, [b]]))


def _composed(pcurve, t, s):
    """``pcurve`` composed with the map ``t -> s`` (:func:`compose_piecewise_linear`), or None
    when ``s`` is not increasing."""
    a, b = t[0], t[-1]
    if not (np.diff(s) > 1e-12 * (b - a)).all():
        return None
    return compose_piecewise_linear(pcurve, t, s)


def _onto_curve_parameters(surface, uses, extents, pieces: int) -> list:
    """:func:`_onto_curve_parameter` of every use in ``uses`` (their traces' largest absolute
    coordinates in ``extents``) with one batched Newton search: each breakpoint seeded at its
    own parameter, inside its use's domain, stopping at ``GEOMETRIC_CONFUSION`` times its
    trace's size, as :func:`splinekit.project` does for one use. A use whose search fails to
    converge goes through :func:`_onto_curve_parameter` (which raises what ``project`` raises)."""
    domains = np.array([use.domain for use in uses], dtype=np.float64)
    t = np.linspace(domains[:, 0], domains[:, 1], pieces + 1, axis=1)  # (n, pieces + 1)
    rows = np.repeat(np.arange(len(uses)), pieces - 1)
    seeds = t[:, 1:-1].ravel()
    points = CurveBatch([use.curve for use in uses]).evaluate(rows, seeds)
    size = np.maximum(1.0, np.asarray(extents, dtype=np.float64))[rows]
    target = _TracesOnSurface(surface, CurveBatch([use.pcurve for use in uses]), size)
    x, _, dist, _, converged, stationary = newton_search(
        target, points, seeds[:, None], domains[rows, :1], domains[rows, 1:], GEOMETRIC_CONFUSION * size, rows)
    failed = (~(converged | stationary) & (dist > GEOMETRIC_CONFUSION * size)).reshape(len(uses), pieces - 1).any(axis=1)
    s = x[:, 0].reshape(len(uses), pieces - 1)
    out = []
    for i, use in enumerate(uses):
        if failed[i]:
            out.append(_onto_curve_parameter(surface, use, pieces))
        else:
            out.append(_composed(use.pcurve, t[i], np.concatenate([[t[i, 0]], s[i], [t[i, -1]]])))
    return out


def _samples(pcurves, curves, per_span: int = 17):
    """``(rows, t)``: parameters of many edge uses (``pcurves[i]`` with its 3-D ``curves[i]``),
    use ``i``'s ``per_span`` in each Bézier span of either curve, on the pcurve's domain, use by
    use (``rows``: the use of each parameter)."""
    ends = np.array([pc.domain for pc in pcurves], dtype=np.float64)
    knots, owner = [], []
    for i, c in enumerate(pcurves + curves):  # each curve's knots inside its own domain...
        k = np.asarray(c.knots)
        a, b = c.domain
        knots.append(k[(k >= a) & (k <= b)])
        owner.append(np.full(knots[-1].size, i % len(pcurves)))
    value, row = np.concatenate(knots), np.concatenate(owner)
    inside = (value > ends[row, 0]) & (value < ends[row, 1])  # ...and strictly inside the pcurve's
    value = np.concatenate([value[inside], ends.ravel()])
    row = np.concatenate([row[inside], np.repeat(np.arange(len(pcurves)), 2)])
    order = np.lexsort((value, row))
    value, row = value[order], row[order]
    first = np.ones(value.size, dtype=bool)
    first[1:] = (row[1:] != row[:-1]) | (value[1:] != value[:-1])
    br, row = value[first], row[first]
    span = np.flatnonzero(row[1:] == row[:-1])  # consecutive breakpoints of one use
    t = (br[span, None] + (br[span + 1] - br[span])[:, None] * np.linspace(0.0, 1.0, per_span)[None]).ravel()
    return np.repeat(row[span], per_span), t


def _deviations(surface, pcurves, curves):
    """Largest distance between ``surface(pcurve(t))`` and ``curve(t)`` of each pair, over the
    parameters :func:`_samples` gives it; and the traces' points ``(list of (n_i, 3))``."""
    rows, t = _samples(list(pcurves), list(curves))
    on = surface.evaluate(*_uv_clipped(surface, CurveBatch(pcurves).evaluate(rows, t)))
    gap = np.linalg.norm(on - CurveBatch(curves).evaluate(rows, t), axis=1)
    starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]])
    return np.maximum.reduceat(gap, starts), np.split(on, starts[1:])


def _aparts(uses, on) -> list:
    """Per use, the largest distance from the points ``on[i]`` (its trace) to its 3-D curve:
    ``project(use.curve, on[i]).distances.max()``, the searches of all uses as one batch
    (:func:`splinekit.closest.curve_distances`)."""
    return [float(d.max()) for d in curve_distances([use.curve for use in uses], on)]


def _reparametrized(surface, uses, devs, aparts, extents) -> list:
    """Per use: ``(pcurve, deviation left)``, the use's pcurve on its 3-D curve's parameter, with
    16 to 256 pieces (four times more while that halves the deviation left and it exceeds twice
    its ``apart``, the distance between the two point sets, which no parameter can undo); None
    when no increasing map is found or the best one does not halve its ``dev``. All uses advance
    together, one batched search per piece count."""
    best = [None] * len(uses)
    active = list(range(len(uses)))
    for pieces in (16, 64, 256):
        if not active:
            break
        moved = _onto_curve_parameters(surface, [uses[i] for i in active], [extents[i] for i in active], pieces)
        done = {i for i, pc in zip(active, moved) if pc is None}
        pairs = [(i, pc) for i, pc in zip(active, moved) if pc is not None]
        if pairs:
            got = _deviations(surface, [pc for _, pc in pairs], [uses[i].curve for i, _ in pairs])[0]
            for (i, pc), g in zip(pairs, got.tolist()):
                if best[i] is not None and g > 0.5 * best[i][1]:  # no longer the map's resolution that limits it
                    done.add(i)
                    continue
                best[i] = (pc, g)
                if g <= 2.0 * aparts[i]:
                    done.add(i)
        active = [i for i in active if i not in done]
    return [b if b is not None and b[1] < 0.5 * dev else None for b, dev in zip(best, devs)]


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
    devs, on = _deviations(surface, [use.pcurve for use in uses], [use.curve for use in uses])
    off = [i for i, (use, dev) in enumerate(zip(uses, devs.tolist())) if dev > use.tolerance]
    fixed, lagging = {}, []
    for i, apart in zip(off, _aparts([uses[i] for i in off], [on[i] for i in off])):
        use, dev = uses[i], float(devs[i])
        if apart >= 0.5 * dev:  # the curves differ in shape, not only in parameter
            fixed[id(use)] = Edge(use.pcurve, use.curve, key=use.key, tolerance=MARGIN * dev)
            continue
        lagging.append((use, dev, apart, float(np.abs(on[i]).max())))
    if lagging:
        moved = _reparametrized(surface, *map(list, zip(*lagging)))
        for (use, dev, _, _), got in zip(lagging, moved):
            if got is not None:
                pc, left = got
                fixed[id(use)] = Edge(pc, use.curve, key=use.key, tolerance=max(use.tolerance, MARGIN * left))
            else:  # the curve is kept (a use without one leaves the edge to the other face's pcurve)
                fixed[id(use)] = Edge(use.pcurve, use.curve, key=use.key, tolerance=MARGIN * dev)
    return [[fixed.get(id(use), use) for use in lp] for lp in loops]
