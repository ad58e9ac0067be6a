"""Loop corners a STEP file can carry: a pcurve whose trace runs past its edge's curve end is
pulled back to where OCC's STEP reader would end it.

A STEP file carries no pcurve ranges. OCC's reader sets each pcurve's range by projecting the
ends of the edge's 3-D curve onto the pcurve's trace on the surface (ShapeFix_EdgeProjAux, from
StepToTopoDS_TranslateEdgeLoop; a plain closest point). Where a trace runs past the curve's end
(a loose edge of a part from another CAD system: the trace ends within the edge's tolerance of
the curve's end, but further along), the end projects inside the trace, the pcurve's range no
longer matches the curve's, and the reader replaces the pcurve by the projection of the 3-D curve
(XSAlgo_ShapeProcessor::CheckPCurve takes the projection whenever the ranges differ). The new
pcurve ends short of the next pcurve in the loop, and the wire repair (ShapeFix_Wire::FixLacking)
bends both ends to their middle: the corner moves, and a long neighbour turns about its far end.
On NX 9's part (face 30, a straight pcurve 34 mm long) that moved the area 9.4e-9 relative on
each round trip, and a second round trip moved it again (2.0e-8): the reader's result is no state
it reads back unchanged.

Writing cannot avoid it when the vertex cannot follow a lengthened curve (NX's corner: the curve
continues a straight edge tangentially, and the reader needs the vertex past the end of both), so
the corner is settled when the part is read: :func:`settle_corners` moves such a pcurve's end
pole to the point of its trace nearest the curve's end, and the next pcurve's start with it. The
part then holds a corner the reader keeps (NX: round trip 2e-11), at a cost of the overshoot
(7.8e-5 mm on NX, within the edge's tolerance of 1.6e-4 mm): area 1.9e-8 relative from OCC's own
reading of the file.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from splinekit.brep import Edge, Shell, Solid, TrimmedFace
from splinekit.curves import BSplineCurve, NurbsCurve
from splinekit.curves.batch import CurveBatch

__all__ = ["settle_corners"]

_MARGIN = 1e-3
"""A trace end counts as running past its curve's end when it lies more than this fraction of the
edge's tolerance beyond the curve end's normal plane (smaller: a rounding the reader's projection
does not see)."""

_MIN_COS = 0.5
"""The trace and the curve must run the same way at the end (cosine of their tangents)."""

_MIN_RELATIVE = 1e-8
"""Overshoots below this fraction of the part's size are left alone: the reader's re-fit moves a
corner by about the overshoot, which then changes no area by more than about 1e-11 (NX: the
re-read of a settled part has three of 8e-8 mm, on edges of tolerance 1e-7)."""

_WIDEN = 1.1
"""A measured deviation becomes a tolerance times this (OCC's check samples other parameters)."""

_SAMPLES = 129
"""Points at which a moved pcurve's trace is compared with its 3-D curve to widen its tolerance."""


def _on_surface(surface, uv, order: int = 0):
    """``surface`` (derivatives to ``order``) at the ``(n, 2)`` ``uv``, clamped to its domain (a
    file's pcurves may overshoot the domain by a rounding)."""
    (u0, u1), (v0, v1) = surface.domain
    return surface.derivatives(np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1), order)


def _overshoots(faces, least: float) -> list:
    """Per face of ``faces``, ``(loop, position, end, d)`` for each edge use whose trace runs ``d``
    past the normal plane of its curve's end (``end`` 0: the start, 1: the end), ``d`` over
    ``least``. The pcurves and curves of all faces are evaluated in one batch each; the surfaces
    face by face."""
    uses = [(f, j, k, e) for f, face in enumerate(faces) for j, loop in enumerate(face.loops)
            for k, e in enumerate(loop) if e.curve is not None and not e.degenerate]
    if not uses:
        return [[] for _ in faces]
    t = np.array([e.domain for *_, e in uses], dtype=np.float64).ravel()
    index = np.repeat(np.arange(len(uses)), 2)
    uv, duv = CurveBatch([e.pcurve for *_, e in uses]).derivatives(index, t, 1)
    P, dP = CurveBatch([e.curve for *_, e in uses]).derivatives(index, t, 1)
    owner = np.repeat([f for f, *_ in uses], 2)
    cut = np.flatnonzero(np.diff(owner)) + 1  # uses come face by face
    Q, dQ = np.empty_like(P), np.empty_like(P)
    for lo, hi in zip(np.r_[0, cut], np.r_[cut, owner.size]):
        S = _on_surface(faces[owner[lo]].surface, uv[lo:hi], 1)
        Q[lo:hi], dQ[lo:hi] = S[0, 0], S[1, 0] * duv[lo:hi, :1] + S[0, 1] * duv[lo:hi, 1:]
    outward = np.tile([-1.0, 1.0], len(uses))[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        U = outward * dQ / np.linalg.norm(dQ, axis=1, keepdims=True)
        T = outward * dP / np.linalg.norm(dP, axis=1, keepdims=True)
    d = np.einsum("ij,ij->i", Q - P, U)
    cos = np.einsum("ij,ij->i", U, T)
    tol = np.repeat([e.tolerance for *_, e in uses], 2)
    hit = np.flatnonzero((d > np.maximum(_MARGIN * tol, least)) & (d <= tol) & (cos >= _MIN_COS))
    found = [[] for _ in faces]
    for i in hit.tolist():
        f, j, k, _ = uses[i // 2]
        found[f].append((j, k, i % 2, float(d[i])))
    return found


def _clamped(curve, at_end: int) -> bool:
    """Whether ``curve`` interpolates its first (``at_end`` 0) or last (1) pole at that end of its
    domain, so moving the pole moves the end point."""
    p, U = curve.degree, np.asarray(curve.knots)
    ends = U[-(p + 1):] if at_end else U[:p + 1]
    return bool(np.all(ends == ends[0]))


def _with_pole(curve, at_end: int, point):
    """``curve`` with its first (``at_end`` 0) or last (1) pole at ``point``."""
    poles = np.array(curve.control_points)
    poles[-1 if at_end else 0] = point
    if curve.weights is None:
        return BSplineCurve(curve.degree, curve.knots, poles)
    return NurbsCurve(curve.degree, curve.knots, poles, curve.weights)


def _nearest_on_trace(surface, edge, at_end: int, d: float):
    """The parameter of ``edge``'s trace nearest its curve's end (``at_end`` 0: start, 1: end),
    searched within about four times the overshoot ``d`` of that end: the root of ``(trace(s) -
    P) . trace'(s)`` (the curve end ``P`` in the trace's normal plane), or None if there is none."""
    a, b = edge.domain
    end = b if at_end else a
    P = edge.curve.evaluate(np.array([end]))[0]

    def trace(s):  # the trace's point and derivative at s
        uv, duv = edge.pcurve.derivatives(np.array([s]), 1)[:, 0]
        S = _on_surface(surface, uv[None], 1)
        return S[0, 0][0], S[1, 0][0] * duv[0] + S[0, 1][0] * duv[1]

    def along(s):  # (trace(s) - P) . trace'(s): zero where P lies in the trace's normal plane
        Q, dQ = trace(s)
        return float((Q - P) @ dQ)

    speed = float(np.linalg.norm(trace(end)[1]))
    reach = min(b - a, 4.0 * d / speed) if speed > 0 else b - a
    lo, hi = (end - reach, end) if at_end else (end, end + reach)
    if not along(lo) < 0.0 < along(hi):  # the trace does not cross P's normal plane there
        return None
    return brentq(along, lo, hi, xtol=1e-15 * max(1.0, abs(end)), rtol=1e-15)


def _settled_face(face, found):
    """``face`` with the pcurve ends ``found`` (:func:`_overshoots`) pulled back (see the module
    docstring), or ``face`` itself when there are none."""
    if not found:
        return face
    loops = [list(loop) for loop in face.loops]
    for j, k, at_end, d in found:
        edge = loops[j][k]
        if not _clamped(edge.pcurve, at_end):
            continue
        s = _nearest_on_trace(face.surface, edge, at_end, d)
        if s is None:
            continue
        old = edge.pcurve.evaluate(np.array([edge.domain[at_end]]))[0]
        new = edge.pcurve.evaluate(np.array([s]))[0]
        loops[j][k] = _replaced(face.surface, edge, _with_pole(edge.pcurve, at_end, new))
        # the neighbour that met this end in (u, v) follows it; one that did not keeps its end
        n = (k + 1) % len(loops[j]) if at_end else k - 1
        other = loops[j][n]
        other_uv = other.pcurve.evaluate(np.array([other.domain[1 - at_end]]))[0]
        if n != k and _clamped(other.pcurve, 1 - at_end) and np.allclose(other_uv, old, rtol=1e-12, atol=1e-14):
            loops[j][n] = _replaced(face.surface, other, _with_pole(other.pcurve, 1 - at_end, new))
    return TrimmedFace(face.surface, loops, reversed=face.reversed, tolerance=face.tolerance, name=face.name)


def _replaced(surface, edge, pcurve):
    """``edge`` with ``pcurve``, its tolerance widened to cover how far the new trace lies from
    the 3-D curve at the same parameter (the pole moved along the trace, so inside the edge the
    trace slides along the curve by up to the overshoot)."""
    t = np.linspace(*edge.domain, _SAMPLES)
    gap = np.linalg.norm(_on_surface(surface, pcurve.evaluate(t))[0, 0] - edge.curve.evaluate(t), axis=1).max()
    return Edge(pcurve, edge.curve, key=edge.key, degenerate=edge.degenerate,
                tolerance=max(edge.tolerance, _WIDEN * float(gap)))


def settle_corners(obj):
    """``obj`` (a Solid, Shell or TrimmedFace read from a STEP file; anything else is returned as
    it is) with every pcurve whose trace runs past its edge's curve end pulled back to the point
    nearest that end, and the next pcurve of its loop with it, so that OCC's STEP reader keeps
    the corners when the part is written and read again (see the module docstring). Parts without
    such ends come back as the same object."""
    faces = [obj] if isinstance(obj, TrimmedFace) else list(obj.faces) if isinstance(obj, (Shell, Solid)) else []
    if not faces:
        return obj
    poles = np.concatenate([np.asarray(f.surface.control_points).reshape(-1, 3) for f in faces])
    least = _MIN_RELATIVE * float(np.linalg.norm(poles.max(axis=0) - poles.min(axis=0)))
    settled = {id(f): _settled_face(f, found) for f, found in zip(faces, _overshoots(faces, least)) if found}
    return _settled(obj, settled) if settled else obj


def _settled(obj, settled: dict):
    """``obj`` with each face whose id is a key of ``settled`` replaced by its value."""
    if isinstance(obj, TrimmedFace):
        return settled.get(id(obj), obj)
    if isinstance(obj, Shell):
        faces = [settled.get(id(f), f) for f in obj.faces]
        return obj if all(a is b for a, b in zip(faces, obj.faces)) else Shell(faces, name=obj.name)
    shells = [_settled(s, settled) for s in obj.shells]
    return obj if all(a is b for a, b in zip(shells, obj.shells)) else Solid(shells, name=obj.name)
