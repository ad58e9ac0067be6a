"""Many spline patches of one structure (degrees, knot vectors, rational or not) evaluated as one:
each query point names its patch, and one basis evaluation serves every patch.

Patch sets such as the teapot's 32 Bézier patches or the bicubic patches a subdivision surface
converts to share their structure, so the continuity analysis evaluates the samples of all their
edges in a few calls instead of a few per patch (:mod:`.sampling`).
"""

from __future__ import annotations

import numpy as np

from ..basis.bernstein import bezier_knots
from ..basis.bspline import basis_ders_t, find_span
from ..basis.rational import rational_surface_derivatives
from ..surfaces import BezierSurface, SplineSurface

__all__ = ["Stacked", "StackMismatch", "groups", "points_many", "split", "structure"]


class StackMismatch(Exception):
    """A query that does not name a patch per point (an internal signal, never raised to users)."""


def structure(surface):
    """A hashable key shared by patches :class:`Stacked` can evaluate together, or None."""
    if isinstance(surface, BezierSurface):
        p, q = surface.control_points.shape[0] - 1, surface.control_points.shape[1] - 1
        ku, kv = bezier_knots(p), bezier_knots(q)
    elif isinstance(surface, SplineSurface):
        p, q, ku, kv = surface.degree_u, surface.degree_v, surface.knots_u, surface.knots_v
    else:
        return None
    if surface.control_points.shape[-1] != 3:
        return None
    return (p, q, tuple(np.asarray(ku).tolist()), tuple(np.asarray(kv).tolist()), surface.weights is not None)


class Stacked:
    """The patches ``surfaces`` (one :func:`structure`) as one parametric surface queried pointwise:
    set ``index`` (``(m,)`` patch numbers) before calling ``evaluate`` / ``derivatives`` with ``m``
    parameter pairs."""

    def __init__(self, surfaces):
        key = structure(surfaces[0])
        self.p, self.q, ku, kv, rational = key
        self.ku, self.kv = np.array(ku), np.array(kv)
        self.domain = surfaces[0].domain
        nets = []
        for s in surfaces:
            P = np.asarray(s.control_points, dtype=np.float64)
            if rational:
                w = np.asarray(s.weights, dtype=np.float64)[..., None]
                P = np.concatenate([P * w, w], axis=-1)
            nets.append(P)
        self.coefs = np.stack(nets)  # (k, nu, nv, d) homogeneous when rational
        self.rational = rational
        self.index = np.zeros(0, dtype=np.int64)

    def derivatives(self, u, v, order: int = 1) -> np.ndarray:
        u = np.asarray(u, dtype=np.float64)
        fu, fv = u.ravel(), np.asarray(v, dtype=np.float64).ravel()
        if fu.size != self.index.size:
            raise StackMismatch
        su, sv = find_span(self.p, self.ku, fu), find_span(self.q, self.kv, fv)
        Nu = basis_ders_t(self.p, self.ku, su, fu, order)  # (order + 1, p + 1, m)
        Nv = basis_ders_t(self.q, self.kv, sv, fv, order)
        rows = su[:, None] - self.p + np.arange(self.p + 1)
        cols = sv[:, None] - self.q + np.arange(self.q + 1)
        G = self.coefs[self.index[:, None, None], rows[:, :, None], cols[:, None, :]]  # (m, p + 1, q + 1, d)
        ders = np.einsum("kam,lbm,mabd->klmd", Nu, Nv, G, optimize=True)
        if self.rational:
            ders = rational_surface_derivatives(ders)
        return ders.reshape(ders.shape[:2] + u.shape + (3,))

    def evaluate(self, u, v) -> np.ndarray:
        return self.derivatives(u, v, 0)[0, 0]


def groups(requests):
    """``(surface, index or None, members)`` per group of ``requests`` (pairs ``(side, t)``): the
    requests on one surface, or on several patches of one structure , whose
    surface is then a :class:`Stacked` and ``index`` the patch number of each request."""
    by_key: dict = {}
    for i, (side, _) in enumerate(requests):
        key = structure(side.surface)
        by_key.setdefault(("one", id(side.surface)) if key is None else key, []).append(i)
    for key, members in by_key.items():
        surfaces = {id(requests[i][0].surface): requests[i][0].surface for i in members}
        if key[0] == "one" or len(surfaces) == 1:
            yield requests[members[0]][0].surface, None, members
            continue
        number = {k: n for n, k in enumerate(surfaces)}
        yield Stacked(list(surfaces.values())), [number[id(requests[i][0].surface)] for i in members], members


def _evaluate_group(requests, members, surface, index, what):
    """``what(surface, uv)`` on the concatenated parameters of ``members``, with the patch numbers
    set on a stacked surface; ``(uvs, result)``. A stacked call that diffgeom re-enters with
    other points (a singular sample) is redone patch by patch."""
    uvs = [requests[i][0].uv(requests[i][1]) for i in members]
    uv = np.concatenate(uvs)
    if index is not None:
        surface.index = np.repeat(np.asarray(index, dtype=np.int64), [len(x) for x in uvs])
    try:
        return uvs, what(surface, uv)
    except StackMismatch:
        return uvs, None


def split(requests, what):
    """Per request (a pair ``(side, t)``), ``(uv, rows of the group's result, result)`` of
    ``what(surface, uv)`` called once per group (:func:`groups`); groups whose stacked call failed
    are evaluated per surface."""
    out = [None] * len(requests)
    for surface, index, members in groups(requests):
        uvs, result = _evaluate_group(requests, members, surface, index, what)
        if result is None:  # per surface instead
            for i, uv_i in zip(members, uvs):
                out[i] = (uv_i, slice(0, len(uv_i)), what(requests[i][0].surface, uv_i))
            continue
        start = 0
        for i, uv_i in zip(members, uvs):
            out[i] = (uv_i, slice(start, start + len(uv_i)), result)
            start += len(uv_i)
    return out


def points_many(requests) -> list:
    """Points ``(n, 3)`` of each request ``(side, t)``, one evaluation per group of surfaces."""
    def points(surface, uv):
        return np.asarray(surface.evaluate(uv[:, 0], uv[:, 1]), dtype=np.float64).reshape(-1, 3)

    return [res[rows] for _, rows, res in split(requests, points)]
