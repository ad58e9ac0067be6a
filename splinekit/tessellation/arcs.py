"""Circles and straight segments recognised among B-rep edges and surfaces, with closed-form maps.

A circular arc in splinekit is a rational quadratic NURBS curve (The NURBS Book A7.1). Its
parameter does not run at uniform angle, but each rational quadratic Bézier piece with end
weights ``w0, w2`` and middle weight ``w1`` becomes, after the Möbius reparametrization
``s = t / (t + lam (1 - t))`` with ``lam = sqrt(w0 / w2)``, the symmetric piece with weights
``1, cos(a), 1`` (``a``: half the piece's sweep), on which ``tan(phi / 2)`` is linear in ``s``:
``phi = a + 2 atan(tan(a / 2) (2 s - 1))`` is the angle swept from the piece's start. So the
angle <-> parameter map of a circle is exact and costs a few numpy calls for any number of
points (:class:`CircleMap`). Every map built here is checked against the curve's own evaluator
when it is built; a curve that fails the check is not a circle for the tessellator.
"""

from __future__ import annotations

import numpy as np

from ..curves import NurbsCurve

__all__ = ["Circle", "CircleMap", "CircleMaps", "Circles", "fit_circle", "fit_circles", "segments"]

REL = 1e-10
"""Relative agreement (of the radius, or of the model size) required to call samples a circle
or a straight segment; rational evaluation rounds at ~1e-15, files written by CAD systems keep
circles to ~1e-12 of their size."""


class Circle:
    """An arc of a circle in space: ``centre + radius (cos(theta) e1 + sin(theta) e2)`` for
    ``theta`` from 0 to ``sweep`` (radians, > 0); ``e1, e2`` orthonormal ``(3,)``,
    ``normal = e1 x e2``; ``closed``: the arc is the whole circle."""

    __slots__ = ("centre", "radius", "e1", "e2", "normal", "sweep", "closed")

    def points(self, theta):
        """``(n, 3)`` points at angles ``theta`` ``(n,)``."""
        return self.centre + self.radius * (np.cos(theta)[:, None] * self.e1 + np.sin(theta)[:, None] * self.e2)

    def angles(self, X):
        """``(n,)`` angles in ``[0, 2 pi)`` of the points ``X`` ``(n, 3)`` about the axis."""
        d = X - self.centre
        return np.mod(np.arctan2(d @ self.e2, d @ self.e1), 2.0 * np.pi)


def _cross(a, b):
    """``a x b`` of ``(..., 3)`` vectors (``np.cross`` costs ~10 us of axis handling per call)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _dot(a, b):
    return (a * b).sum(axis=-1)


def _norm(a):
    """Lengths of ``(..., d)`` vectors along the last axis: ``np.linalg.norm(a, axis=-1)`` bit for
    bit, without its ~10 us of argument handling per call (the plan makes hundreds of such calls)."""
    return np.sqrt((a * a).sum(axis=-1))


def _unwrap(p):
    """``np.unwrap(p, axis=-1)`` (period ``2 pi``) bit for bit: the same operations without its
    argument handling (~50 us per call on the small arrays of a plan)."""
    dd = p[..., 1:] - p[..., :-1]
    ddmod = np.mod(dd + np.pi, 2.0 * np.pi) - np.pi
    np.copyto(ddmod, np.pi, where=(ddmod == -np.pi) & (dd > 0))
    correct = ddmod - dd
    np.copyto(correct, 0.0, where=np.abs(dd) < np.pi)
    up = np.array(p, dtype=np.float64)
    up[..., 1:] = p[..., 1:] + correct.cumsum(axis=-1)
    return up


class Circles:
    """Several fitted circle arcs as arrays (see :func:`fit_circles`): per curve ``ok`` (a circle
    arc), and for those ``centre``, ``radius``, ``e1``, ``e2``, ``normal``, ``sweep``, ``closed``."""

    __slots__ = ("ok", "centre", "radius", "e1", "e2", "normal", "sweep", "closed")

    def circle(self, i) -> Circle:
        """Curve ``i``'s :class:`Circle`."""
        out = Circle()
        out.centre, out.radius, out.e1, out.e2 = self.centre[i], float(self.radius[i]), self.e1[i], self.e2[i]
        out.normal, out.sweep, out.closed = self.normal[i], float(self.sweep[i]), bool(self.closed[i])
        return out


def fit_circles(X, scale, through=None) -> Circles:
    """The circle arcs through the samples ``X`` ``(n, k, 3)`` of ``n`` curves (in order along
    each curve, ``k >= 7``, spread over the curve's parameter): curve ``i`` is one (``ok[i]``) if
    every sample lies on one circle within ``REL * max(radius, scale)`` and the angle grows
    monotonically. Conics (rational quadratic pieces) with five points on a circle are that
    circle, so enough samples per piece make this exact for the curves the tessellator meets.
    The circle through the first sample and those at a third and two thirds; angle 0 at the
    first sample."""
    k = X.shape[1]
    a, b, c = X[:, 0], X[:, k // 3], X[:, (2 * k) // 3]
    u, v = b - a, c - a
    n = _cross(u, v)
    nn = _dot(n, n)
    good = nn > 0
    nn = np.where(good, nn, 1.0)
    out = Circles()
    centre = out.centre = a + (_cross(n, u) * _dot(v, v)[:, None] + _cross(v, n) * _dot(u, u)[:, None]) / (2.0 * nn)[:, None]
    d = X - centre[:, None]
    r = out.radius = _norm(d[:, 0])
    eps = REL * np.maximum(r, scale)
    normal = out.normal = n / np.sqrt(nn)[:, None]
    on = (np.abs(_norm(d) - r[:, None]).max(axis=1) <= eps) & (np.abs(_dot(d, normal[:, None])).max(axis=1) <= eps)
    e1 = out.e1 = d[:, 0] / np.where(r > 0, r, 1.0)[:, None]
    e2 = out.e2 = _cross(normal, e1)
    theta = _unwrap(np.arctan2(_dot(d, e2[:, None]), _dot(d, e1[:, None])))
    step = np.diff(theta, axis=1)
    closed = out.closed = _norm(X[:, -1] - X[:, 0]) <= eps
    out.sweep = np.where(closed, 2.0 * np.pi, theta[:, -1] - theta[:, 0])
    out.ok = good & on & (step > 0).all(axis=1) & (step.max(axis=1) < np.pi / 2) & (out.sweep <= 2.0 * np.pi + 1e-9)
    return out


def fit_circle(X, scale) -> Circle | None:
    """The :class:`Circle` through the samples ``X`` ``(k, 3)`` of one curve, or None (see
    :func:`fit_circles`)."""
    c = fit_circles(X[None], scale)
    return c.circle(0) if c.ok[0] else None


def segments(X, scale):
    """``(n,)`` bool: whether the samples ``X`` ``(n, k, 3)`` of each curve lie on the straight
    segment between its first and last (within ``REL * scale``), in order, with distinct ends."""
    a, b = X[:, :1], X[:, -1:]
    ab = b - a
    L2 = _dot(ab, ab)[:, 0]
    long = np.sqrt(L2) > REL * scale
    t = _dot(X - a, ab) / np.where(long, L2, 1.0)[:, None]
    off = _norm(X - a - t[..., None] * ab)
    return long & (off.max(axis=1) <= REL * scale) & (np.diff(t, axis=1) > 0).all(axis=1)


class CircleMap:
    """The exact angle <-> parameter map of a rational quadratic B-spline circle (arc).

    Attributes: ``circle`` (:class:`Circle`, its angle 0 at the curve's start and growing with
    the parameter), per Bézier piece ``lo, hi`` (parameters), ``start`` (angle at the piece's
    start), ``half`` (half its sweep) and ``lam`` (the Möbius factor). Built by :meth:`of`.
    """

    __slots__ = ("circle", "lo", "hi", "start", "half", "lam", "t_half")

    @classmethod
    def of(cls, curve, scale):
        """The map of ``curve`` (a :class:`~splinekit.NurbsCurve` or B-spline of degree 2 in 3-D),
        or None if it is not a circle arc in this exact sense."""
        if curve.degree != 2 or curve.weights is None:
            return None
        return cls.of_net(curve.knots, curve.control_points, curve.weights, scale, curve)

    @classmethod
    def of_net(cls, knots, P, W, scale, curve=None):
        """:meth:`of` the rational quadratic curve with ``knots``, control points ``P`` ``(n, 3)``
        and weights ``W`` ``(n,)`` (``curve``: that curve, if at hand; built only when its joints
        are not of multiplicity 2)."""
        breaks, mult = np.unique(np.asarray(knots, dtype=np.float64), return_counts=True)
        if mult[0] == 3 and mult[-1] == 3 and (mult[1:-1] == 2).all():
            # joints of multiplicity 2 (circles as CAD systems write them): the pieces' control
            # points are the curve's, three at a time, and the curve is evaluated piece by piece
            idx = 2 * np.arange(len(breaks) - 1)[:, None] + np.arange(3)
            P, W = np.asarray(P, dtype=np.float64)[idx], np.asarray(W, dtype=np.float64)[idx]  # (k, 3, 3), (k, 3)
            if (W <= 0).any():
                return None
            lo, hi = breaks[0], breaks[-1]
            t = np.linspace(lo, hi, 8 * len(P) + 1)
            j = np.clip(np.searchsorted(breaks, t, side="right") - 1, 0, len(P) - 1)
            x = ((t - breaks[j]) / (breaks[j + 1] - breaks[j]))[:, None]
            B = np.concatenate([(1.0 - x) ** 2, 2.0 * x * (1.0 - x), x * x], axis=1) * W[j]  # (m, 3)
            X = np.einsum("mi,mid->md", B, P[j]) / B.sum(axis=1, keepdims=True)
        else:
            if curve is None:
                curve = NurbsCurve(2, knots, P, W)
            pieces = curve.to_bezier()
            if len(breaks) != len(pieces) + 1:
                return None
            P = np.array([p.control_points for p in pieces])
            W = np.array([p.weights for p in pieces])
            lo, hi = curve.domain
            t = np.linspace(lo, hi, 8 * len(P) + 1)
            X = curve.evaluate(t)
        circle = fit_circle(X, scale)
        if circle is None:
            return None
        if (W <= 0).any():
            return None
        cos_half = W[:, 1] / np.sqrt(W[:, 0] * W[:, 2])
        if (cos_half <= 0).any() or (cos_half >= 1).any():
            return None
        m = cls()
        m.circle, m.lo, m.hi = circle, breaks[:-1], breaks[1:]
        m.half = np.arccos(cos_half)
        m.start = np.unwrap(circle.angles(P[:, 0]))
        m.start -= m.start[0]
        m.lam = np.sqrt(W[:, 0] / W[:, 2])
        m.t_half = np.tan(m.half / 2.0)
        # checked against the curve's points: the map's angles at the samples' parameters
        if np.abs(circle.points(m.angle(t)) - X).max() > REL * max(circle.radius, scale):
            return None
        return m

    @classmethod
    def batch(cls, nets, scale):
        """``[CircleMap or None]``: :meth:`of_net` of every ``(knots, P, W)`` in ``nets``, those
        with joints of multiplicity 2 and the same number of pieces in one vectorised pass
        (the same samples, fit and check as :meth:`of_net`), any other one by one."""
        out = [None] * len(nets)
        shapes: dict = {}
        for i, (knots, P, W) in enumerate(nets):
            n = len(knots)
            if n % 2 == 0 and n >= 6 and len(P) == n - 3 and np.ndim(W) == 1:
                shapes.setdefault(n, []).append(i)
            else:
                out[i] = cls.of_net(knots, P, W, scale)
        for n, members in shapes.items():
            K = (n - 4) // 2  # pieces
            kn = np.array([nets[i][0] for i in members], dtype=np.float64)  # (m, 2K + 4)
            inner = kn[:, 3:-3]
            breaks = np.concatenate([kn[:, 2:3], inner[:, ::2], kn[:, -3:-2]], axis=1)  # (m, K + 1)
            regular = ((kn[:, 0] == kn[:, 2]) & (kn[:, -1] == kn[:, -3]) & (inner[:, ::2] == inner[:, 1::2]).all(axis=1)
                       & (np.diff(breaks, axis=1) > 0).all(axis=1))  # fmt: skip
            idx = 2 * np.arange(K)[:, None] + np.arange(3)
            P = np.array([nets[i][1] for i in members], dtype=np.float64)[:, idx]  # (m, K, 3, 3)
            W = np.array([nets[i][2] for i in members], dtype=np.float64)[:, idx]  # (m, K, 3)
            regular &= (W > 0).all(axis=(1, 2))
            for k in np.flatnonzero(~regular):
                out[members[k]] = cls.of_net(*nets[members[k]], scale)
            if not regular.any():
                continue
            sel = np.flatnonzero(regular)
            members, breaks, P, W = [members[k] for k in sel], breaks[sel], P[sel], W[sel]
            m = len(members)
            t = np.linspace(breaks[:, 0], breaks[:, -1], 8 * K + 1, axis=1)  # (m, 8K + 1)
            rows = np.arange(m)[:, None]
            j = (breaks[:, None, 1:K] <= t[:, :, None]).sum(axis=2)  # the piece of each sample
            x = (t - breaks[rows, j]) / (breaks[rows, j + 1] - breaks[rows, j])
            B = np.stack([(1.0 - x) ** 2, 2.0 * x * (1.0 - x), x * x], axis=2) * W[rows, j]  # (m, s, 3)
            X = np.einsum("msi,msid->msd", B, P[rows, j]) / B.sum(axis=2)[..., None]
            fits = fit_circles(X, scale)
            cos_half = W[:, :, 1] / np.sqrt(W[:, :, 0] * W[:, :, 2])
            ok = fits.ok & ((cos_half > 0) & (cos_half < 1)).all(axis=1)
            half = np.arccos(np.clip(cos_half, -1.0, 1.0))
            d = P[:, :, 0] - fits.centre[:, None]
            start = _unwrap(np.mod(np.arctan2(_dot(d, fits.e2[:, None]), _dot(d, fits.e1[:, None])), 2.0 * np.pi))
            start -= start[:, :1]
            lam = np.sqrt(W[:, :, 0] / W[:, :, 2])
            t_half = np.tan(half / 2.0)
            # checked against the curves' points: the maps' angles at the samples' parameters (as :meth:`angle`)
            k = np.minimum((breaks[:, None, 1:] < t[:, :, None]).sum(axis=2), K - 1)
            x = (t - breaks[rows, k]) / (breaks[rows, k + 1] - breaks[rows, k])
            s_ = x / (x + lam[rows, k] * (1.0 - x))
            theta = start[rows, k] + half[rows, k] + 2.0 * np.arctan(t_half[rows, k] * (2.0 * s_ - 1.0))
            Y = fits.centre[:, None] + fits.radius[:, None, None] * (np.cos(theta)[..., None] * fits.e1[:, None] + np.sin(theta)[..., None] * fits.e2[:, None])
            ok &= np.abs(Y - X).max(axis=(1, 2)) <= REL * np.maximum(fits.radius, scale)
            for q in np.flatnonzero(ok):
                cm = out[members[q]] = cls()
                cm.circle, cm.lo, cm.hi = fits.circle(q), breaks[q, :-1], breaks[q, 1:]
                cm.half, cm.start, cm.lam, cm.t_half = half[q], start[q], lam[q], t_half[q]
        return out

    def _piece(self, t):
        return np.clip(np.searchsorted(self.hi, t, side="left"), 0, len(self.hi) - 1)

    def angle(self, t):
        """``(n,)`` angles (from the curve's start) at parameters ``t`` ``(n,)``."""
        k = self._piece(t)
        x = (t - self.lo[k]) / (self.hi[k] - self.lo[k])
        s = x / (x + self.lam[k] * (1.0 - x))
        return self.start[k] + self.half[k] + 2.0 * np.arctan(self.t_half[k] * (2.0 * s - 1.0))

    def param(self, theta):
        """``(n,)`` parameters at angles ``theta`` ``(n,)`` (from the curve's start, in
        ``[0, sweep]``)."""
        ends = self.start + 2.0 * self.half
        k = np.clip(np.searchsorted(ends, theta, side="left"), 0, len(ends) - 1)
        s = 0.5 * (np.tan((theta - self.start[k] - self.half[k]) / 2.0) / self.t_half[k] + 1.0)
        x = self.lam[k] * s / ((1.0 - s) + self.lam[k] * s)
        return self.lo[k] + x * (self.hi[k] - self.lo[k])


class CircleMaps:
    """Several :class:`CircleMap` as one table, so that points on different circles are mapped
    in one pass: :meth:`angle` and :meth:`param` take the map ``q`` ``(n,)`` of every point."""

    __slots__ = ("lo", "hi", "start", "half", "lam", "t_half", "first", "last", "t0", "t1", "tkey", "akey", "sweep",
                 "kappa", "full", "table")  # fmt: skip

    def __init__(self, maps):
        cat = lambda name: np.concatenate([getattr(m, name) for m in maps])  # noqa: E731
        self.lo, self.hi, self.start, self.half = cat("lo"), cat("hi"), cat("start"), cat("half")
        self.lam, self.t_half = cat("lam"), cat("t_half")
        count = np.array([len(m.lo) for m in maps], dtype=np.int64)
        self.first = np.cumsum(count) - count
        self.last = self.first + count - 1
        self.t0 = np.array([m.lo[0] for m in maps])
        self.t1 = np.array([m.hi[-1] for m in maps])
        self.sweep = np.array([m.circle.sweep for m in maps])
        q = np.repeat(np.arange(len(maps)), count)
        # sorted search keys: map q's pieces end at 2 q + (fraction of its domain), 8 q + angle
        self.tkey = 2.0 * q + (self.hi - self.t0[q]) / (self.t1 - self.t0)[q]
        self.akey = 8.0 * q + self.start + 2.0 * self.half
        self.kappa = np.maximum.reduceat(_kappa(self.half, self.t_half, self.lam), self.first) if maps else np.zeros(0)
        self.full = bool((self.sweep >= 2.0 * np.pi - 1e-12).all())
        # per piece, the columns both maps read (one gather per call instead of six)
        self.table = np.column_stack([self.lo, self.hi - self.lo, self.start + self.half, self.lam, self.t_half])

    def _piece(self, keys, key, q):
        return np.minimum(np.maximum(np.searchsorted(keys, key, side="left"), self.first[q]), self.last[q])

    def angle(self, q, t):
        """Angles (from each circle's start) at parameters ``t`` of maps ``q`` (same shapes)."""
        k = self._piece(self.tkey, 2.0 * q + (t - self.t0[q]) / (self.t1 - self.t0)[q], q)
        lo, span, mid, lam, th = self.table[k].T
        x = (t - lo) / span
        s = x / (x + lam * (1.0 - x))
        return mid + 2.0 * np.arctan(th * (2.0 * s - 1.0))

    def param(self, q, theta):
        """Parameters of maps ``q`` at angles ``theta`` (any branch: taken into ``[0, sweep]``,
        an arc's far side split halfway)."""
        th = np.mod(theta, 2.0 * np.pi)
        if not self.full:
            sw = self.sweep[q]
            th = np.where(th > 0.5 * (sw + 2.0 * np.pi), th - 2.0 * np.pi, th)
        k = self._piece(self.akey, 8.0 * q + th, q)
        lo, span, mid, lam, tq = self.table[k].T
        s = 0.5 * (np.tan(0.5 * (th - mid)) / tq + 1.0)
        return lo + span * (lam * s / ((1.0 - s) + lam * s))


def _kappa(half, t_half, lam):
    """``max |u''(theta) / u'(theta)|`` on each circle-map piece (``u``: parameter, ``theta``: angle;
    ``half``, ``t_half``, ``lam`` ``(k,)``: the pieces' columns of :class:`CircleMap`): how far a
    parametric midpoint strays from the angular one, in units of the squared step (it moves by
    ``kappa step^2 / 8`` radians to leading order). In closed form on each piece: with
    ``t = tan((theta - mid) / 2)``, ``s = (t / tan(half / 2) + 1) / 2`` and ``x = lam s / (1 + (lam - 1) s)``,
    ``u''/u' = x''/x' s' + s''/s' = -2 (lam - 1) s' / (1 + (lam - 1) s) + t``, taken at 257 angles per
    piece (all pieces of all maps in one pass). Returns ``(k,)``."""
    a = np.linspace(-1.0, 1.0, 257)[None, :] * half[:, None]  # theta - mid over each piece
    t = np.tan(0.5 * a)
    tq = t_half[:, None]
    s = 0.5 * (t / tq + 1.0)
    ds = (1.0 + t * t) / (4.0 * tq)
    lam = lam[:, None]
    return np.abs(-2.0 * (lam - 1.0) * ds / (1.0 + (lam - 1.0) * s) + t).max(axis=1)
