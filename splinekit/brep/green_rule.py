"""Green's theorem rule of :mod:`.integrate` for trimmed faces: ``integral over D of g du dv =
closed integral over dD of G(u, v) dv`` with ``G(u, v) = integral from u_ref to u of g(s, v) ds``
(``u_ref`` left of the trims). The outer integral runs along the pcurves (pieces split at their
knots, a Gauss-Kronrod rule along each, bisected by :func:`.integrate.integrate` where needed);
the inner one is an adaptive Gauss-Kronrod rule in ``s``, broken at the surface's u-knots, whose
error is carried into the outer piece's error."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .. import limits
from ..basis.algebra import bezier_elevation_matrix, bezier_segments
from ..basis.bspline import basis_ders_t, find_span
from .tensor_rule import bernstein_ders
from .trim_domain import OUTSIDE_DOMAIN, check_in_domain, closed_pcurves, gauss_on, trim_bounds

__all__ = ["GreenRule", "cell_derivatives", "MAX_INNER_LEVELS", "MAX_PIECES"]

MAX_INNER_LEVELS = 60
"""Bisection levels of the inner (Green) integrals before their error is accepted as it is."""

MAX_PIECES = 200_000
"""Cells or intervals in play at once (outer pieces of all faces, or inner intervals of one
pass) beyond which the integration stops refining and reports what it has (with its error
estimate and ``converged=False``) instead of exhausting memory on a singular integrand."""


# ---------------------------------------------------------------------------
# the surface on the nodes of many cells at once

def cell_derivatives(surface, u, v):
    """``S``, ``Su``, ``Sv`` ``(m, a, b, 3)`` on the tensor grids ``u[c] x v[c]`` of ``m`` cells
    (``u`` ``(m, a)``, ``v`` ``(m, b)``), each cell inside one knot span of the surface.

    Exploits the tensor structure: the basis functions are evaluated per node row and
    contracted with the cell's local ``(p + 1) x (q + 1)`` net, two small products instead of a
    full basis product per point. Rational surfaces: quotient rule on the homogeneous values.
    """
    p, q, U, V, C = surface._pu, surface._pv, surface._ku, surface._kv, surface._coefs
    m, a = u.shape
    b = v.shape[1]
    su = find_span(p, U, u[:, a // 2])
    sv = find_span(q, V, v[:, b // 2])
    Nu = basis_ders_t(p, U, np.repeat(su, a), u.ravel(), 1).reshape(2, p + 1, m, a)
    Nv = basis_ders_t(q, V, np.repeat(sv, b), v.ravel(), 1).reshape(2, q + 1, m, b)
    net = C[(su[:, None] - p + np.arange(p + 1))[:, :, None], (sv[:, None] - q + np.arange(q + 1))[:, None, :]]
    A = np.einsum("dami,mabk->dmibk", Nu, net)  # contracted in u: (2, m, a, q + 1, k)
    # then in v by batched matmuls on contiguous operands (einsum's generic loop was 5x slower)
    Nv = np.ascontiguousarray(Nv.transpose(0, 2, 3, 1))[:, :, None]  # (2, m, 1, b, q + 1)
    D00, D10, D01 = Nv[0] @ A[0], Nv[0] @ A[1], Nv[1] @ A[0]  # (m, a, b, k)
    if not surface._rational:
        return D00, D10, D01
    w = D00[..., -1:]
    S = D00[..., :-1] / w
    return S, (D10[..., :-1] - D10[..., -1:] * S) / w, (D01[..., :-1] - D01[..., -1:] * S) / w


class GreenRule:
    """Green's theorem along the trimming loops of a trimmed face; pieces ``(m, 3)`` =
    ``[segment, a0, a1]``: intervals in the local ``[0, 1]`` parameters of the Bézier segments of
    the face's pcurves."""

    def __init__(self, face, integrand, gk, inner_gk):
        self.gk, self.inner_gk = gk, inner_gk  # Gauss-Kronrod pairs along the trims and across the face
        self.surface = face.surface
        self.sign = -1.0 if face.reversed else 1.0
        self.integrand = integrand
        trims = _trims(face)
        self.pcurves, self.affine, self.initial_pieces = trims.pcurves, trims.affine, trims.pieces
        self.segments, self.seg_width = trims.segments, trims.seg_width
        self.u_ref, self.u_end, self.v_range, self.width = trims.u_ref, trims.u_end, trims.v_range, trims.width
        self.u_breaks, self.v_length = trims.u_breaks, trims.v_length
        self.inner_scale = None  # per-component magnitude of g, set on the first pass
        degree = getattr(integrand, "polynomial_degree", None)
        # on a plane, g is a polynomial of the integrand's degree in s: a Gauss rule of that
        # order gives G exactly, no adaptive inner integral needed
        self.exact_inner = None
        if self.affine is not None and degree is not None:
            self.exact_inner = _gauss_legendre(int(degree) // 2 + 1)

    def initial(self):
        return self.initial_pieces

    def _pcurve_points(self, pieces):
        """``uv (m, n, 2)`` and ``d(uv)/dt (m, n, 2)`` at the n Kronrod nodes of the pieces, all
        in one evaluation of the trims' Bézier segments (raised to one degree)."""
        seg = pieces[:, 0].astype(np.intp)
        a = pieces[:, 1, None] + (pieces[:, 2] - pieces[:, 1])[:, None] * self.gk.t  # (m, n) local
        B = bernstein_ders(self.segments.shape[1] - 1, a)  # (2, P + 1, m, n)
        H = np.einsum("dimn,mik->dmnk", B, self.segments[seg])  # homogeneous (w u, w v, w) and d/da
        w = H[0, ..., 2:]
        uv = H[0, ..., :2] / w
        duv = (H[1, ..., :2] - H[1, ..., 2:] * uv) / (w * self.seg_width[seg][:, None, None])
        return uv, duv

    def evaluate(self, pieces, targets):
        m = len(pieces)
        uv, duv = self._pcurve_points(pieces)
        inner_tol = None if targets is None else 0.1 * targets / self.v_length
        G, G_err, n_eval = self._inner(uv[..., 0].ravel(), uv[..., 1].ravel(), inner_tol)
        k = G.shape[-1]
        half = 0.5 * (pieces[:, 2] - pieces[:, 1]) * self.seg_width[pieces[:, 0].astype(np.intp)]  # in t
        vt = duv[..., 1] * half[:, None]  # dv/dt times the Jacobian of the map to [-1, 1]: (m, n)
        f = G.reshape(m, self.gk.n, k) * vt[..., None]
        qk = np.einsum("i,mic->mc", self.gk.wk, f)
        qg = np.einsum("i,mic->mc", self.gk.wg, f)
        inner = np.einsum("i,mic->mc", self.gk.wk, G_err.reshape(m, self.gk.n, k) * np.abs(vt)[..., None])
        absval = np.einsum("i,mic->mc", self.gk.wk, np.abs(f))
        return qk, np.abs(qk - qg) + inner, absval, None, n_eval

    def split(self, pieces, info, targets):
        mid = 0.5 * (pieces[:, 1] + pieces[:, 2])
        a, b = pieces.copy(), pieces.copy()
        a[:, 2] = b[:, 1] = mid
        return np.concatenate([a, b])

    def _g(self, s, v):
        """The integrand at the nodes ``s`` ``(q, n)`` of ``q`` intervals, each at its ``v`` ``(q,)``."""
        S, Su, Sv = (x.reshape(-1, 3) for x in cell_derivatives(self.surface, s, v[:, None]))
        return self.integrand(S, Su, Sv, self.sign)

    def _inner_exact(self, u, v):
        """:meth:`_inner` on an affine surface for an integrand polynomial of degree
        ``integrand.polynomial_degree`` in the point: a Gauss rule exact for that degree on
        ``[u_ref, u]``. The error is rounding: 64 machine epsilons of the integral of ``|g|``."""
        x, w = self.exact_inner
        origin, du, dv = self.affine
        h = u - self.u_ref
        s = self.u_ref + 0.5 * h[:, None] * (x + 1.0)  # (n, g)
        S = origin + s[..., None] * du + v[:, None, None] * dv
        S = S.reshape(-1, 3)
        f = self.integrand(S, np.broadcast_to(du, S.shape), np.broadcast_to(dv, S.shape), self.sign)
        f = f.reshape(s.shape + f.shape[-1:]) * (0.5 * h)[:, None, None]
        G = np.einsum("g,ngc->nc", w, f)
        err = 64.0 * np.finfo(float).eps * np.einsum("g,ngc->nc", w, np.abs(f))
        return G, err, f.shape[0] * f.shape[1]

    def _inner(self, u, v, tol):
        """``G(u, v) = integral from u_ref to u of g(s, v) ds`` at ``n`` points: ``(G (n, k),
        error (n, k), evaluations)``, adaptive Gauss-Kronrod broken at the surface's u-knots.

        An interval is accepted when its error is within ``tol * length / width`` (``tol``:
        ``(k,)`` absolute tolerance of G per component), so every G meets ``tol``. On the first
        pass (``tol`` None) the tolerance is ``1e-13`` times the largest ``|g|`` seen times the length.
        """
        n = u.size
        # rounding of the pcurves' evaluation: stay within the range the trims span
        u = np.clip(u, self.u_ref, self.u_end)
        v = np.clip(v, *self.v_range)
        if self.exact_inner is not None:
            return self._inner_exact(u, v)
        interior = self.u_breaks[1:-1]
        # intervals [u_ref, b1], [b1, b2], ..., [b_j, u] for the breaks b below u
        count = np.searchsorted(interior, u, side="left")  # breaks strictly below u (u > b)
        owners = np.repeat(np.arange(n), count + 1)
        first = np.repeat(np.cumsum(count + 1) - (count + 1), count + 1)
        pos = np.arange(owners.size) - first  # position within the node's chain
        edges = np.concatenate([[self.u_ref], interior])
        s0 = edges[pos]
        s1 = np.where(pos == count[owners], u[owners], edges[np.minimum(pos + 1, edges.size - 1)])
        vv = v[owners]
        G = None
        n_eval = 0
        for level in range(MAX_INNER_LEVELS + 1):
            q = s0.size
            limits.check(q * self.inner_gk.n * 8 * 24, "inner quadrature nodes")
            h = s1 - s0
            s = s0[:, None] + h[:, None] * self.inner_gk.t
            f = self._g(s, vv).reshape(q, self.inner_gk.n, -1)
            n_eval += f.shape[0] * self.inner_gk.n
            if G is None:
                k = f.shape[-1]
                G, G_err = np.zeros((n, k)), np.zeros((n, k))
                if self.inner_scale is None:
                    self.inner_scale = np.maximum(np.abs(f).max(axis=(0, 1)), np.finfo(float).tiny)
            f = f * (0.5 * h)[:, None, None]
            qk = np.einsum("i,qic->qc", self.inner_gk.wk, f)
            err = np.abs(qk - np.einsum("i,qic->qc", self.inner_gk.wg, f))
            if tol is None:
                allowed = 1e-13 * self.inner_scale * np.abs(h)[:, None]
            else:
                allowed = tol * (np.abs(h) / self.width)[:, None]
            done = np.all(err <= allowed, axis=1) | (level == MAX_INNER_LEVELS)
            done |= np.abs(h) <= 1e-13 * self.width  # at rounding level: splitting cannot help
            if 2 * np.count_nonzero(~done) > MAX_PIECES:
                done[:] = True
            np.add.at(G, owners[done], qk[done])
            np.add.at(G_err, owners[done], err[done])
            if done.all():
                break
            keep = ~done
            mid = 0.5 * (s0[keep] + s1[keep])
            s0 = np.concatenate([s0[keep], mid])
            s1 = np.concatenate([mid, s1[keep]])
            owners = np.concatenate([owners[keep], owners[keep]])
            vv = np.concatenate([vv[keep], vv[keep]])
        return G, G_err, n_eval


@functools.lru_cache(maxsize=8)
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """numpy's n-point Gauss-Legendre rule on [-1, 1], computed once per n."""
    return np.polynomial.legendre.leggauss(n)


@dataclass(frozen=True)
class _Trims:
    """What Green's rule needs of a face's trims, whatever the integrand (cached on the face)."""

    pcurves: list  # the loops' pcurves, gaps closed by straight pieces
    segments: np.ndarray  # (s, P + 1, 3) their Bézier segments, homogeneous, raised to one degree P
    seg_width: np.ndarray  # (s,) the segments' lengths in their curves' parameters
    pieces: np.ndarray  # (s, 3) initial pieces [segment, a0, a1] (local parameters): the segments
    u_ref: float  # the inner integrals run from u_ref ...
    u_end: float  # ... to at most u_end
    v_range: tuple  # (lo, hi) of v along the trims, with a margin
    width: float  # u_end - u_ref
    u_breaks: np.ndarray  # u_ref, the surface's u-knots between, u_end: the inner intervals' breaks
    v_length: float  # total variation of v along the loops
    affine: tuple | None  # (origin, Su, Sv) when the surface is a plane (:func:`_affine_map`)


def _trims(face) -> _Trims:
    if "green trims" in face._cache:
        return face._cache["green trims"]
    surface = face.surface
    (ua, ub), (v0, v1) = surface.domain
    pcurves = closed_pcurves(face.loops, 1e-14 * max(ub - ua, v1 - v0))
    check_in_domain(face, pcurves)
    # G is integrated from the left of the trims (any constant u_ref will do); trims a little
    # past the domain take the surface's polynomial extension, as OCC does. The margin keeps
    # nodes past the trims' extremes unclipped (clipping cut 5e-6 off a disc tangent to
    # the domain's sides at tolerances below 1e-8).
    lo, hi = trim_bounds(pcurves)
    mu, mv = OUTSIDE_DOMAIN * (ub - ua), OUTSIDE_DOMAIN * (v1 - v0)
    u_ref, u_end = min(ua, float(lo[0])) - mu, max(ub, float(hi[0])) + mu
    bu = surface.bezier_breakpoints()[0]
    # total variation of v along the loops: bounds how inner errors add up in the outer sum
    total, segments, widths = 0.0, [], []
    for c in pcurves:
        breaks, seg = bezier_segments(c._degree, c._knots, c._coefs)  # (s, p + 1, 2 or 3)
        if not c._rational:
            seg = np.concatenate([seg, np.ones(seg.shape[:2] + (1,))], axis=2)
        segments.append(seg)
        widths.append(np.diff(breaks))
        t, w = gauss_on(breaks)
        total += float(w @ np.abs(c.derivatives(t, 1)[1][:, 1]))
    top = max(s.shape[1] for s in segments) - 1
    segments = np.concatenate([np.einsum("ij,sjk->sik", bezier_elevation_matrix(s.shape[1] - 1, top - s.shape[1] + 1), s)
                               if s.shape[1] - 1 < top else s for s in segments])
    count = len(segments)
    trims = _Trims(pcurves=pcurves, segments=segments, seg_width=np.concatenate(widths),
                   pieces=np.stack([np.arange(count, dtype=float), np.zeros(count), np.ones(count)], axis=1),
                   u_ref=u_ref, u_end=u_end,
                   v_range=(min(v0, float(lo[1])) - mv, max(v1, float(hi[1])) + mv),
                   width=max(u_end - u_ref, np.finfo(float).tiny),
                   u_breaks=np.concatenate([[u_ref], bu[(bu > u_ref) & (bu < u_end)], [u_end]]),
                   v_length=max(total, np.finfo(float).tiny), affine=_affine_map(surface))
    face._cache["green trims"] = trims
    return trims


def _affine_map(surface, rel: float = 1e-14):
    """``(origin, Su, Sv)`` (each ``(3,)``) with ``S(u, v) = origin + u Su + v Sv`` when the surface
    is that affine map (a non-rational bilinear patch whose net is a parallelogram: a plane, as
    STEP files and OCC write them), else None."""
    if surface._rational or (surface._pu, surface._pv) != (1, 1) or surface._coefs.shape[:2] != (2, 2):
        return None
    P = surface._coefs
    if np.abs(P[1, 1] - P[1, 0] - P[0, 1] + P[0, 0]).max() > rel * max(np.abs(P).max(), np.finfo(float).tiny):
        return None
    (u0, u1), (v0, v1) = surface.domain
    Su, Sv = (P[1, 0] - P[0, 0]) / (u1 - u0), (P[0, 1] - P[0, 0]) / (v1 - v0)
    return P[0, 0] - u0 * Su - v0 * Sv, Su, Sv
