"""Exact rational forms of OpenCascade's elementary surfaces and circular edges, built natively,
with the maps that carry a face's pcurves from OCC's angle parameters onto them.

A cylinder, cone, sphere or torus is a surface of revolution of a line or circle; its rational
form (The NURBS Book A7.1, A8.1) cuts every angle range ``[a, b]`` into ``n = ceil((b - a) / 90
deg)`` equal segments, each a rational quadratic with middle weight ``cos(step / 2)``, and puts
the knots AT the angles ``a + k step``: the rational parameter ``t`` equals the angle at every
knot, and inside a segment the two are related by the half-angle tangent (:class:`AngleMap`)::

    tan((theta - mid) / 2) = tan(step / 4) (2 lam - 1),   t = knot + step lam

That map is not linear, so a pcurve that runs along an angle (a circle edge: a parallel, a
meridian) is carried over by giving the EDGE the same kind of parameter: a circular edge's 3-D
curve becomes its rational arc on the same range, cut at its own angles (:func:`edge_arc`), and
each of its pcurves becomes ``t(s) = Psi_face(c + sigma Psi_edge^-1(s))``. Between consecutive
knots of either map that is a linear fractional (Möbius) function of ``s`` (the tangent of a
difference of angles is one of the tangents'), i.e. exactly a rational linear segment
(:func:`mapped_isoline`). Every use of the edge is built from the same 3-D circle, so all of them
share the new parameter, as OCC's SameParameter requires.
"""

from __future__ import annotations

import math

import numpy as np

from ..construct.curves import unit_arc
from ..curves import BSplineCurve, NurbsCurve
from ..surfaces import BSplineSurface, NurbsSurface

__all__ = ["AngleMap", "edge_arc", "mapped_isoline", "revolved_surface", "plane_patch"]


class AngleMap:
    """The rational parameter ``t`` of an arc over the angle range ``[start, end]`` (radians,
    ``start < end``) as a function of the angle, and back; knots at ``start + k * step``."""

    def __init__(self, start: float, end: float):
        self.start, self.end = float(start), float(end)
        self.n = max(1, math.ceil((self.end - self.start) / (0.5 * math.pi) - 1e-9))
        self.step = (self.end - self.start) / self.n
        self.knots = self.start + self.step * np.arange(self.n + 1)
        self.knots[-1] = self.end
        self._tq = math.tan(0.25 * self.step)

    def _segment(self, x):
        k = np.floor((np.asarray(x, dtype=np.float64) - self.start) / self.step).astype(np.int64)
        return np.clip(k, 0, self.n - 1)

    def __call__(self, theta):
        """``t`` at the angles ``theta`` (array)."""
        theta = np.asarray(theta, dtype=np.float64)
        k = self._segment(theta)
        mid = self.knots[k] + 0.5 * self.step
        lam = 0.5 * (np.tan(0.5 * (theta - mid)) / self._tq + 1.0)
        return self.knots[k] + self.step * lam

    def inverse(self, t):
        """The angles at the rational parameters ``t`` (array)."""
        t = np.asarray(t, dtype=np.float64)
        k = self._segment(t)
        lam = (t - self.knots[k]) / self.step
        return self.knots[k] + 0.5 * self.step + 2.0 * np.arctan(self._tq * (2.0 * lam - 1.0))

    def arc(self):
        """``(knots, coords (2n + 1, 2), weights)``: the unit arc over the range, knots on the angles."""
        knots, coords, weights = unit_arc(self.start, self.end)
        return self.start + (self.end - self.start) * knots, coords, weights


def edge_arc(center, x_axis, y_axis, first: float, last: float):
    """The conic ``center + cos(theta) x_axis + sin(theta) y_axis`` (a circle or ellipse, 2-D or
    3-D: the axes carry the radii) over ``[first, last]`` as a rational quadratic NURBS whose
    parameter is the edge's new one (:class:`AngleMap` of ``[first, last]``)."""
    knots, coords, weights = AngleMap(first, last).arc()
    P = np.asarray(center, float) + coords[:, :1] * np.asarray(x_axis, float) + coords[:, 1:] * np.asarray(y_axis, float)
    return NurbsCurve(2, knots, P, weights)


def _mobius_pieces(s_breaks, t_of_s):
    """Rational linear pieces through ``t_of_s`` between the sorted breakpoints: returns
    ``(knots, t values at the breakpoints, weights)`` of one degree-1 NURBS. Each piece's weight
    ratio makes it pass through the map's value at the piece's middle (a Möbius map is fixed by
    three values)."""
    s = np.asarray(s_breaks, dtype=np.float64)
    t = t_of_s(s)
    tm = t_of_s(0.5 * (s[:-1] + s[1:]))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = (tm - t[:-1]) / (t[1:] - tm)
    ratio = np.where(np.isfinite(ratio) & (ratio > 0), ratio, 1.0)  # a constant piece: any weight
    weights = np.concatenate([[1.0], np.cumprod(ratio)])
    weights /= weights.max()
    knots = np.concatenate([[s[0]], s, [s[-1]]])
    return knots, t, weights


def mapped_isoline(coord: int, c: float, sigma: float, other: float, domain, face_map: AngleMap,
                   edge_map: AngleMap | None):
    """The pcurve, on the rational surface, of an edge that ran along angle coordinate ``coord``
    (0: u, 1: v) as ``angle = c + sigma * w`` (``w``: the edge's old parameter, an angle when the
    edge is a circle) with the other coordinate fixed at ``other`` (already mapped).

    ``edge_map``: the edge's own :class:`AngleMap` (its new parameter ``s``), or None for a
    degenerate edge (a pole), whose parameter is free: its pcurve is then the straight segment
    between the mapped ends, on the same domain. ``domain``: the edge's ``(first, last)``."""
    a, b = float(domain[0]), float(domain[1])
    if edge_map is None:
        ends = face_map(np.array([c + sigma * a, c + sigma * b]))
        P = np.zeros((2, 2))
        P[:, coord], P[:, 1 - coord] = ends, other
        return BSplineCurve(1, [a, a, b, b], P)
    # breakpoints: the edge's knots and the parameters where the face's angle crosses its knots
    inner = face_map.knots[1:-1]
    s_cross = edge_map(((inner - c) / sigma))
    s_cross = s_cross[(s_cross > a) & (s_cross < b)]
    breaks = np.union1d(edge_map.knots, s_cross)
    span = b - a
    keep = np.concatenate([[True], np.diff(breaks) > 1e-12 * span])
    breaks = breaks[keep]
    breaks[-1] = b
    knots, t, w = _mobius_pieces(breaks, lambda s: face_map(c + sigma * edge_map.inverse(s)))
    P = np.zeros((len(t), 2))
    P[:, coord], P[:, 1 - coord] = t, other
    return NurbsCurve(1, knots, P, w)


def revolved_surface(origin, x_dir, y_dir, z_dir, u_map: AngleMap, meridian):
    """``origin + rho (cos u x_dir + sin u y_dir) + z z_dir`` with ``(rho, z)`` the rational
    ``meridian`` ``(knots_v, points (m, 2), weights (m,) or None, degree_v)``, as one NURBS
    surface over the u range of ``u_map`` (A8.1: poles ``rho_j A_i + z_j Z``, weights
    ``wu_i wv_j``)."""
    ku, A, wu = u_map.arc()
    kv, M, wv, dv = meridian
    O, X, Y, Z = (np.asarray(x, dtype=np.float64) for x in (origin, x_dir, y_dir, z_dir))
    ring = A[:, :1] * X + A[:, 1:] * Y  # (nu, 3) unit-arc poles in the plane
    P = O + M[None, :, :1] * ring[:, None, :] + M[None, :, 1:] * Z
    W = wu[:, None] * (np.ones(len(M)) if wv is None else wv)[None, :]
    return NurbsSurface(2, dv, ku, kv, P, W)


def line_meridian(rho0, z0, rho1, z1, v0, v1):
    """A straight meridian (cylinder, cone) from ``(rho0, z0)`` at ``v0`` to ``(rho1, z1)`` at ``v1``."""
    return np.array([v0, v0, v1, v1], float), np.array([[rho0, z0], [rho1, z1]], float), None, 1


def circle_meridian(rho_c, z_c, r, v_map: AngleMap):
    """A circular meridian ``(rho_c + r cos v, z_c + r sin v)`` over ``v_map``'s range (sphere, torus)."""
    kv, C, wv = v_map.arc()
    return kv, np.array([rho_c, z_c]) + r * C, wv, 2


def plane_patch(origin, x_dir, y_dir, box):
    """The plane ``origin + u x_dir + v y_dir`` over ``box = ((u0, v0), (u1, v1))``, bilinear
    (OCC's parameter kept)."""
    (u0, v0), (u1, v1) = box
    O, X, Y = (np.asarray(x, dtype=np.float64) for x in (origin, x_dir, y_dir))
    P = np.array([[O + u * X + v * Y for v in (v0, v1)] for u in (u0, u1)])
    return BSplineSurface(1, 1, [u0, u0, u1, u1], [v0, v0, v1, v1], P)
