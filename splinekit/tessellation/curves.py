"""Adaptive polylines of curves within a chordal tolerance.

Per Bézier span the number of segments comes from a bound on the second
derivative (the chord of a step ``h`` deviates from the curve by at most
``h^2 / 8 max |C''|``): the control-polygon bound ``p (p - 1) max |D2 P|`` for a
polynomial span, sampled values with a margin for a rational one. The result
is then measured at every segment's parametric midpoint and spans over the
tolerance are refined, for a few rounds.
"""

from __future__ import annotations

import numpy as np

from .. import limits
from ..basis import algebra
from ..basis.bernstein import all_bernstein
from ..mesh.topology import ranges
from .result import Polyline

__all__ = ["tessellate_curve"]

MAX_COUNT = 1 << 16
MAX_ROUNDS = 8
BYTES_PER_POINT = 64
"""Peak memory per polyline point and coordinate (points, midpoints, tangents and
their temporaries), charged to the memory budget (:mod:`splinekit.limits`)."""


def _span_bounds(p, segs):
    """``(M, L)`` per Bézier span: bound of ``|C''|`` and mean speed, local parameter [0, 1]."""
    P = segs[..., :-1] / segs[..., -1:]
    w = segs[..., -1]
    rational = (w.max(axis=1) - w.min(axis=1)) > 1e-14 * w.max(axis=1)
    M = np.zeros(len(segs))
    if p >= 2:
        M = p * (p - 1) * np.linalg.norm(P[:, 2:] - 2 * P[:, 1:-1] + P[:, :-2], axis=-1).max(axis=1)
    L = p * np.linalg.norm(P[:, 1:] - P[:, :-1], axis=-1).mean(axis=1)
    if rational.any():
        t = np.linspace(0.0, 1.0, 9)
        B = all_bernstein(p, t, 2)  # (3, p + 1, 9)
        A = np.einsum("dis,cik->dcsk", B, segs[rational])
        w0, w1, w2 = A[0, ..., -1:], A[1, ..., -1:], A[2, ..., -1:]
        C0 = A[0, ..., :-1] / w0
        C1 = (A[1, ..., :-1] - w1 * C0) / w0
        C2 = (A[2, ..., :-1] - 2 * w1 * C1 - w2 * C0) / w0
        M[rational] = 1.5 * np.linalg.norm(C2, axis=-1).max(axis=1)
    return M, L


def _params(breaks, counts):
    """Parameters: ``counts[i]`` equal steps in span ``i``, shared ends once."""
    a, b = breaks[:-1], breaks[1:]
    k = ranges(np.zeros(counts.size, dtype=np.int64), counts)
    span = np.repeat(np.arange(counts.size), counts)
    t = a[span] + (b - a)[span] * (k / counts[span])
    return np.concatenate([t, breaks[-1:]]), span


def tessellate_curve(curve, tol: float, angle_tol) -> Polyline:
    """Polyline of a :class:`~splinekit.SplineCurve` (see :func:`splinekit.tessellation.tessellate`)."""
    p = curve.degree
    breaks, segs = algebra.bezier_segments(p, curve.knots, np.asarray(curve.homogeneous_points))
    M, L = _span_bounds(p, segs)
    n = np.sqrt(M / (8.0 * tol))
    if angle_tol is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            n = np.maximum(n, np.where(L > 0, M / (L * angle_tol), 0.0))
    counts = np.clip(np.ceil(np.nan_to_num(n, nan=MAX_COUNT, posinf=MAX_COUNT)), 1, MAX_COUNT).astype(np.int64)
    for _ in range(MAX_ROUNDS):
        total = float(counts.sum()) + 1.0
        limits.check(total * BYTES_PER_POINT * (curve.dim + 1), f"a polyline at tolerance {tol:.3g} ({total:,.0f} points)")
        t, span = _params(breaks, counts)
        X = curve.evaluate(t)
        mid = 0.5 * (t[:-1] + t[1:])
        dev = np.linalg.norm(curve.evaluate(mid) - 0.5 * (X[:-1] + X[1:]), axis=-1)
        worst = np.zeros(counts.size)
        np.maximum.at(worst, span, dev)
        factor = np.sqrt(worst / tol)
        if angle_tol is not None:
            D = curve.derivatives(t, 1)[1]
            length = np.linalg.norm(D, axis=-1)
            ok = (length[:-1] > 0) & (length[1:] > 0)
            cosang = np.einsum("ij,ij->i", D[:-1], D[1:]) / np.where(ok, length[:-1] * length[1:], 1.0)
            ang = np.where(ok, np.arccos(np.clip(cosang, -1.0, 1.0)), 0.0)
            turn = np.zeros(counts.size)
            np.maximum.at(turn, span, ang)
            factor = np.maximum(factor, turn / angle_tol)
        over = (factor > 1.0) & (counts < MAX_COUNT)
        if not over.any():
            break
        grown = np.ceil(counts * np.minimum(factor * 1.15, 8.0)).astype(np.int64)
        counts = np.where(over, np.minimum(np.maximum(grown, counts + 1), MAX_COUNT), counts)
    return Polyline(X, t, float(dev.max()) if dev.size else 0.0, tol)
