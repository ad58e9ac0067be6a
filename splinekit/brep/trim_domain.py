"""Where a face's trims lie in its surface's (u, v) domain, for the integration rules of
:mod:`.integrate`: the check that they stay in the domain, their bounding boxes, the closing of
their gaps, and the recognition of a trim that is just an axis-parallel rectangle."""

from __future__ import annotations

import numpy as np

from ..construct.curves import line
from ..errors import DomainError

_GL16 = np.polynomial.legendre.leggauss(16)


OUTSIDE_DOMAIN = 1e-3
"""Trims past the domain by more than this fraction of its width are checked in 3-D (approximated
trims overshoot by 1e-4, trims of another period by 1)."""
OUTSIDE_EDGE_TOLERANCES = 4.0  # and then by at most this many edge tolerances, measured in 3-D


__all__ = ["OUTSIDE_DOMAIN", "OUTSIDE_EDGE_TOLERANCES", "check_in_domain", "closed_pcurves", "gauss_on",
           "layout", "rectangle", "trim_bounds"]


def _samples(curve, per_piece: int = 33):
    """``(n, 2)`` points of a pcurve, ``per_piece`` on each of its Bézier pieces (ends included)."""
    b = curve.bezier_breakpoints()
    t = (b[:-1, None] + (b[1:] - b[:-1])[:, None] * np.linspace(0.0, 1.0, per_piece)).ravel()
    return curve.evaluate(t)


def _hull(curve):
    """``(lo (2,), hi (2,))`` of the pcurve's control points, which bound the curve (convex hull
    property), or None for a rational curve with a non-positive weight (no such bound)."""
    w = curve.weights
    if w is not None and not np.all(np.asarray(w) > 0):
        return None
    cp = np.asarray(curve.control_points, dtype=float)
    return cp.min(axis=0), cp.max(axis=0)


def trim_bounds(curves) -> tuple[np.ndarray, np.ndarray]:
    """``(lo (2,), hi (2,))``: a box in (u, v) that holds every curve (their control points'
    box, or their samples' for a curve with non-positive weights)."""
    boxes = []
    for c in curves:
        box = _hull(c)
        if box is None:
            pts = _samples(c)
            box = pts.min(axis=0), pts.max(axis=0)
        boxes.append(box)
    return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)


def check_in_domain(face, curves):
    """Raise DomainError when a trim (one of the pcurves ``curves``) leaves
    the surface's domain by more than :data:`OUTSIDE_DOMAIN` of its width and, in 3-D, by more
    than :data:`OUTSIDE_EDGE_TOLERANCES` times the face's largest edge tolerance: within that, the
    integrand over the excursion is the surface's polynomial extension, which is how OpenCascade
    evaluates such a face too (files with 5e-3 edge tolerances overshoot by 1e-2); beyond it the
    trim belongs to something else (another period of a periodic surface) and the result would
    be silently wrong. Trims whose control points stay within the domain's slack (most) are
    accepted without sampling them."""
    surface = face.surface
    (u0, u1), (v0, v1) = surface.domain
    slack = OUTSIDE_DOMAIN * np.array([u1 - u0, v1 - v0])
    lo_dom, hi_dom = np.array([u0, v0]) - slack, np.array([u1, v1]) + slack
    boxes = [_hull(c) for c in curves]
    if all(b is not None and np.all(b[0] >= lo_dom) and np.all(b[1] <= hi_dom) for b in boxes):
        return
    samples = [_samples(c) for c in curves]
    limit = OUTSIDE_EDGE_TOLERANCES * max([face.tolerance] + [e.tolerance for lp in face.loops for e in lp])
    for k, (a, b) in enumerate(surface.domain):
        slack = OUTSIDE_DOMAIN * (b - a)
        for i, pts in enumerate(samples):
            x = pts[:, k]
            lo, hi = float(x.min()), float(x.max())
            if lo >= a - slack and hi <= b + slack:
                continue
            out = pts[(x < a) | (x > b)]
            near = np.column_stack([np.clip(out[:, 0], u0, u1), np.clip(out[:, 1], v0, v1)])
            d = surface.derivatives(near[:, 0], near[:, 1], 1)
            step = out - near
            over = float(np.linalg.norm(d[1, 0] * step[:, :1] + d[0, 1] * step[:, 1:], axis=1).max())
            if over > limit:
                raise DomainError(
                    f"face{f' {face.name!r}' if face.name else ''}: trim {i} spans {'uv'[k]} in [{lo:.10g}, {hi:.10g}], "
                    f"past the surface's domain [{a:.10g}, {b:.10g}] by {over:.3g} in 3-D (more than {limit:.3g}, "
                    f"{OUTSIDE_EDGE_TOLERANCES:g} edge tolerances: trims of another period of a periodic surface?); "
                    "cannot integrate over it")


def closed_pcurves(loops, tiny):
    """The pcurves of the loops, with a straight piece across every gap between one pcurve's
    end and the next one's start (approximated trims, e.g. OCC's NURBS conversion, leave gaps
    of 1e-7 in (u, v)): Green's theorem needs closed loops, and on an open one the result
    depends on the direction of the inner integral by G times the gap."""
    out = []
    for loop in loops:
        for edge, following in zip(loop, loop[1:] + loop[:1]):
            out.append(edge.pcurve)
            a, b = edge.end_uv, following.start_uv
            if np.abs(a - b).max() > tiny:
                out.append(line(a, b))
    return out


def gauss_on(breaks):
    """16-point Gauss-Legendre nodes and weights on every interval between consecutive ``breaks``."""
    g, w = _GL16
    breaks = np.asarray(breaks, dtype=float)
    mid, half = 0.5 * (breaks[1:] + breaks[:-1]), 0.5 * (breaks[1:] - breaks[:-1])
    return (mid[:, None] + half[:, None] * g).ravel(), (half[:, None] * w).ravel()


def layout(face):
    """``(kind, rect)``: ``("natural", None)`` for an untrimmed face, ``("rectangle", (u0, u1, v0,
    v1))`` for a face whose only loop is an axis-parallel rectangle (its sides checked against
    the domain like any trim), ``("trimmed", None)`` otherwise. Cached on the face."""
    if "layout" not in face._cache:
        rect = rectangle(face) if face.is_trimmed else None
        if rect is not None:
            check_in_domain(face, [e.pcurve for e in face.loops[0]])
        kind = "natural" if not face.is_trimmed else "trimmed" if rect is None else "rectangle"
        face._cache["layout"] = (kind, rect)
    return face._cache["layout"]


def rectangle(face, rel: float = 1e-12):
    """``(u0, u1, v0, v1)`` when the face's only loop runs counter-clockwise around that
    axis-parallel rectangle (every pcurve straight along one of its sides: OCC's trims of
    spheres, tori, cylinders and untrimmed B-spline faces), else None. Such a face gets the
    tensor rule, cheaper than Green's theorem and adaptive in both directions at poles."""
    if len(face.loops) != 1:
        return None
    cps = [np.asarray(e.pcurve.control_points, dtype=float) for e in face.loops[0]]
    pts = np.concatenate(cps)
    (u0, v0), (u1, v1) = pts.min(axis=0), pts.max(axis=0)
    eps = rel * max(u1 - u0, v1 - v0, np.finfo(float).tiny)
    if not (u1 - u0 > eps and v1 - v0 > eps):
        return None
    for cp in cps:
        if not any(np.all(np.abs(cp[:, k] - side) <= eps) for k, side in ((0, u0), (0, u1), (1, v0), (1, v1))):
            return None
    ends = np.array([c[0] for c in cps] + [cps[-1][-1]])  # straight pieces: the end points' polygon
    area = 0.5 * float(np.sum(ends[:-1, 0] * ends[1:, 1] - ends[1:, 0] * ends[:-1, 1]))
    if abs(area - (u1 - u0) * (v1 - v0)) > 1e-9 * (u1 - u0) * (v1 - v0):
        return None
    return float(u0), float(u1), float(v0), float(v1)
