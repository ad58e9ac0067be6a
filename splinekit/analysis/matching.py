"""Finding the edge two faces or surfaces share, from their sampled boundaries.

Each edge use (:class:`~splinekit.analysis.sides.Side`) is sampled as a polyline of
:data:`POLYLINE` points. A use lies on another when every one of its :data:`PROBES` probe points
is within ``match_rtol`` times its own length of the other's polyline; this holds whatever the
two parametrizations are (reversed, reparametrized, one use part of a longer one). Uses that
carry the same B-rep key are paired without looking.
"""

from __future__ import annotations

import numpy as np

from ..brep.links import close_pairs, link_components
from ..errors import ParameterError
from .sides import Side
from .stacked import points_many

__all__ = ["NoSharedEdgeError", "POLYLINE", "PROBES", "candidate_pairs", "lies_on", "polyline", "polylines", "shared_edge"]

POLYLINE = 65
"""Points of a use's polyline (64 chords): the chord sag of a quarter circle is 5e-5 of its length."""

PROBES = 9
"""Probe points per use (among the polyline's, end points included)."""


class NoSharedEdgeError(ParameterError):
    """Two faces or surfaces given to the continuity analysis share no edge; the message names the
    closest pair of sides and their distance."""


def polyline(side: Side) -> np.ndarray:
    """``(POLYLINE, 3)`` points of the use at equal steps of its pcurve parameter."""
    pts = side.points(side.fractions(np.linspace(0.0, 1.0, POLYLINE)))
    if not np.isfinite(pts).all():
        raise ParameterError(f"patch {side.patch} evaluates to non-finite points along its side {side.name}")
    return pts


def polylines(sides: list) -> list:
    """:func:`polyline` of every use, evaluated per group of surfaces (:func:`.stacked.split`)."""
    f = np.linspace(0.0, 1.0, POLYLINE)
    out = points_many([(s, s.fractions(f)) for s in sides])
    for s, pts in zip(sides, out):
        if not np.isfinite(pts).all():
            raise ParameterError(f"patch {s.patch} evaluates to non-finite points along its side {s.name}")
    return out


def _length(pts: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())


def _distance_to_polyline(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """``(m,)`` distance of each point ``P`` ``(m, 3)`` to the polyline ``Q`` ``(k, 3)``."""
    A, D = Q[:-1], np.diff(Q, axis=0)
    dd = np.einsum("kd,kd->k", D, D)
    t = np.einsum("mkd,kd->mk", P[:, None, :] - A[None], D) / np.where(dd > 0, dd, 1.0)
    t = np.clip(t, 0.0, 1.0)
    closest = A[None] + t[..., None] * D[None]
    return np.sqrt(np.einsum("mkd,mkd->mk", P[:, None] - closest, P[:, None] - closest)).min(axis=1)


def lies_on(P: np.ndarray, Q: np.ndarray) -> float:
    """How far the use sampled as ``P`` is from lying on the one sampled as ``Q``: the largest
    distance of its probe points to ``Q``'s polyline over its own length (inf for a point)."""
    length = _length(P)
    if length <= 0:
        return np.inf
    probes = P[np.linspace(0, len(P) - 1, PROBES).round().astype(int)]
    return float(_distance_to_polyline(probes, Q).max()) / length


def shared_edge(sides_a: list, sides_b: list, match_rtol: float, same: bool = False):
    """``(inner, outer)``: the pair of uses, one of each list, that is one edge; ``inner`` is the
    one lying on the other (the one to sample). ``same``: both lists are one face's (a seam: a use
    is not paired with itself). NoSharedEdgeError when no pair lies within ``match_rtol``."""
    keyed = [(x, y) for x in sides_a for y in sides_b
             if x.key is not None and x.key == y.key and not x.degenerate and not (same and x is y)]
    if keyed:
        return keyed[0]
    A = [s for s in sides_a if not s.degenerate]
    B = [s for s in sides_b if not s.degenerate]
    if not A or not B:
        raise NoSharedEdgeError("a face or surface has no side of non-zero length, so the two share no edge")
    PA, PB = polylines(A), polylines(B)
    best, pair = np.inf, None
    for i, x in enumerate(A):
        for j, y in enumerate(B):
            if same and x is y:
                continue
            for score, inner, outer in ((lies_on(PA[i], PB[j]), x, y), (lies_on(PB[j], PA[i]), y, x)):
                if score < best:
                    best, pair = score, (inner, outer)
    if pair is None or best > match_rtol:
        where = f"; the closest are side {pair[0].name} of {pair[0].patch} and side {pair[1].name} of {pair[1].patch}, " \
                f"{best:.3g} of the edge's length apart" if pair is not None and np.isfinite(best) else ""
        raise NoSharedEdgeError(
            f"the two faces share no edge: no side of one lies on a side of the other within "
            f"{match_rtol:g} of its length{where}"
        )
    return pair


def candidate_pairs(sides: list, match_rtol: float) -> list:
    """``[(inner, outer), ...]``: the pairs of uses among ``sides`` (of many patches) that are one
    edge, found through their end points: uses whose end points coincide (either way round) within
    ``match_rtol`` of the longest use's length are candidates, kept when one lies on the other."""
    live = [s for s in sides if not s.degenerate]
    if len(live) < 2:
        return []
    P = polylines(live)
    ends = np.concatenate([np.array([p[0] for p in P]), np.array([p[-1] for p in P])])
    radius = match_rtol * max(_length(p) for p in P)
    links = close_pairs(ends, radius)
    labels = link_components(len(ends), links[:, 0], links[:, 1]) if len(links) else np.arange(len(ends))
    n = len(live)
    groups: dict = {}
    for i in range(n):
        key = tuple(sorted((int(labels[i]), int(labels[n + i]))))
        groups.setdefault(key, []).append(i)
    out = []
    for members in groups.values():
        for k, i in enumerate(members):
            for j in members[k + 1:]:
                x, y = live[i], live[j]
                fwd, back = lies_on(P[i], P[j]), lies_on(P[j], P[i])
                if min(fwd, back) <= match_rtol:
                    out.append((x, y) if fwd <= back else (y, x))
    return out
