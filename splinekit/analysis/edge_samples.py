"""Where the samples of shared edges come from: the corresponding parameters on both uses and
their frames, evaluated for many edges at once.

For each edge (a pair of uses, ``inner`` lying on ``outer``), ``inner`` is sampled at equal steps
of its pcurve; the corresponding parameters on ``outer`` are the same or the reversed fractions
when the two uses coincide there (patches sharing their boundary with proportional
parametrizations: the common case), else its closest points (a local search seeded from its
polyline). Every sample of every edge on one surface, or on patches of one structure
(:mod:`.stacked`), is evaluated in one call (curvature and first derivatives), so the number of
calls grows with the number of surfaces or structures, not of edges.
"""

from __future__ import annotations

import numpy as np

from ..closest import project
from ..diffgeom.curvature import curvature
from ..tolerances import GEOMETRIC_CONFUSION
from .compare import compare, curvature_rows, edge_tangent, finite_values, frame
from .matching import POLYLINE, polyline
from .sides import Side, Trace, extraordinary_corners
from .stacked import points_many, split

__all__ = ["measure", "measure_many"]


def _raw_many(requests) -> list:
    """Per request ``(side, t)``: ``(uv, d_uv, ders (2, 2, n, 3), curvature rows, extraordinary,
    corner normals or None)``, with one curvature and one derivative call per group of surfaces."""
    def both(surface, uv):
        c = curvature(surface, uv[:, 0], uv[:, 1])
        return c, np.asarray(surface.derivatives(uv[:, 0], uv[:, 1], 1), dtype=np.float64)

    out = []
    for (side, t), (uv, rows, (c, ders)) in zip(requests, split(requests, both)):
        d = ders[:, :, rows]
        finite_values(d[0, 0], side, "points")
        extraordinary, corner_normals = np.zeros(len(t), dtype=bool), None
        corners, normals = extraordinary_corners(side.surface)
        if len(corners):
            near = np.all(np.abs(uv[:, None, :] - corners[None]) <= 1e-12, axis=2)  # (n, k)
            extraordinary = near.any(axis=1)
            if normals is not None:
                corner_normals = normals[np.argmax(near, axis=1)]
        out.append((uv, side.direction(t), d, curvature_rows(c, rows), extraordinary, corner_normals))
    return out


def _corresponding(outer: Side, f: np.ndarray, points: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Pcurve parameters ``(n,)`` on ``outer`` of the points ``points`` of the inner use at
    fractions ``f``, given ``outer``'s points ``Q`` ``(2 n, 3)`` at ``f`` and ``1 - f``."""
    t = outer.fractions(np.concatenate([f, 1.0 - f]))
    d = np.linalg.norm(Q.reshape(2, len(f), -1) - points[None], axis=2).max(axis=1)
    k = int(np.argmin(d))
    if d[k] <= GEOMETRIC_CONFUSION * max(1.0, float(np.abs(points).max())):
        return t.reshape(2, -1)[k]
    return _closest_on(outer, points)


def _closest_on(outer: Side, points: np.ndarray) -> np.ndarray:
    """Pcurve parameters ``(n,)`` of the points of ``outer``'s use closest to ``points``,
    seeded from its polyline (a local search)."""
    poly = polyline(outer)
    nearest = np.argmin(np.linalg.norm(points[:, None] - poly[None], axis=2), axis=1)
    seeds = outer.fractions(nearest / (POLYLINE - 1))
    return np.asarray(project(Trace(outer), points, seeds=seeds).parameters, dtype=np.float64).reshape(-1)


def measure_many(pairs, samples: int, *, gap_tol=None, angle_tol=None, curvature_tol=None, swaps=None) -> list:
    """One :class:`~splinekit.analysis.EdgeContinuity` per pair ``(inner, outer)`` of uses,
    ``inner`` sampled at ``samples`` equal pcurve steps; ``swaps[k]``: report pair ``k`` with
    ``outer`` as side a. Tolerances as in :func:`~splinekit.analysis.edge_continuity`."""
    f = np.linspace(0.0, 1.0, samples)
    swaps = [False] * len(pairs) if swaps is None else swaps
    inner_raw = _raw_many([(inner, inner.fractions(f)) for inner, _ in pairs])
    both = np.concatenate([f, 1.0 - f])
    Qs = points_many([(outer, outer.fractions(both)) for _, outer in pairs])
    t_out = [_corresponding(outer, f, raw[2][0, 0], Q) for (_, outer), raw, Q in zip(pairs, inner_raw, Qs)]
    outer_raw = _raw_many([(outer, t) for (_, outer), t in zip(pairs, t_out)])
    out = []
    for (inner, outer), ri, ro, t, swap in zip(pairs, inner_raw, outer_raw, t_out, swaps):
        tangent = edge_tangent(ri[2], ri[1])
        fi = frame(inner, inner.fractions(f), ri[0], ri[1], ri[2], ri[3], tangent, ri[4], ri[5])
        fo = frame(outer, t, ro[0], ro[1], ro[2], ro[3], tangent, ro[4], ro[5])
        fa, fb = (fo, fi) if swap else (fi, fo)
        out.append(compare(fa, fb, gap_tol, angle_tol, curvature_tol))
    return out


def measure(inner: Side, outer: Side, samples: int, *, gap_tol=None, angle_tol=None, curvature_tol=None,
            swap: bool = False):
    """:func:`measure_many` of one pair."""
    return measure_many([(inner, outer)], samples, gap_tol=gap_tol, angle_tol=angle_tol, curvature_tol=curvature_tol,
                        swaps=[swap])[0]
