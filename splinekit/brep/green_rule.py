"""Green's theorem rule of :mod:`.integrate` for trimmed faces: ``integral over D of g du dv =
closed integral over dD of G(u, v) dv`` with ``G(u, v) = integral from u_ref to u of g(s, v) ds``
(``u_ref`` left of the trims). The outer integral runs along the pcurves (pieces split at their
knots, K15 along each, bisected by :func:`.integrate.integrate` where needed); the inner one is an
adaptive K15 in ``s``, broken at the surface's u-knots, whose error is carried into the outer
piece's error."""

from __future__ import annotations

import numpy as np

from .. import limits
from ..basis.bspline import basis_ders_t, find_span
from .kronrod import NODES01 as _T
from .kronrod import NQ as _NQ
from .kronrod import W_GAUSS as _W_G
from .kronrod import W_KRONROD as _W_K
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
    D = np.einsum("dmibk,ebmj->demijk", A, Nv)  # (2, 2, m, a, b, k)
    if not surface._rational:
        return D[0, 0], D[1, 0], D[0, 1]
    w = D[..., -1:]
    S = D[0, 0, ..., :-1] / w[0, 0]
    Su = (D[1, 0, ..., :-1] - w[1, 0] * S) / w[0, 0]
    Sv = (D[0, 1, ..., :-1] - w[0, 1] * S) / w[0, 0]
    return S, Su, Sv


class GreenRule:
    """Green's theorem along the trimming loops of a trimmed face; pieces ``(m, 3)`` =
    ``[edge index, t0, t1]`` of the face's pcurves."""

    def __init__(self, face, integrand):
        self.surface = face.surface
        self.sign = -1.0 if face.reversed else 1.0
        self.integrand = integrand
        (ua, ub), (v0, v1) = self.surface.domain
        self.pcurves = closed_pcurves(face.loops, 1e-14 * max(ub - ua, v1 - v0))
        check_in_domain(face, self.pcurves)
        # G is integrated from the left of the trims (any constant u_ref will do); trims a little
        # past the domain take the surface's polynomial extension, as OCC does. The margin keeps
        # nodes past the trims' extremes unclipped (clipping cut 5e-6 off a disc tangent to
        # the domain's sides at tolerances below 1e-8).
        lo, hi = trim_bounds(self.pcurves)
        mu, mv = OUTSIDE_DOMAIN * (ub - ua), OUTSIDE_DOMAIN * (v1 - v0)
        self.u_ref, self.u_end = min(ua, float(lo[0])) - mu, max(ub, float(hi[0])) + mu
        self.v_range = (min(v0, float(lo[1])) - mv, max(v1, float(hi[1])) + mv)
        self.width = max(self.u_end - self.u_ref, np.finfo(float).tiny)
        bu = self.surface.bezier_breakpoints()[0]
        self.u_breaks = np.concatenate([[self.u_ref], bu[(bu > self.u_ref) & (bu < self.u_end)], [self.u_end]])
        # total variation of v along the loops: bounds how inner errors add up in the outer sum
        total = 0.0
        for c in self.pcurves:
            t, w = gauss_on(c.bezier_breakpoints())
            total += float(w @ np.abs(c.derivatives(t, 1)[1][:, 1]))
        self.v_length = max(total, np.finfo(float).tiny)
        self.inner_scale = None  # per-component magnitude of g, set on the first pass

    def initial(self):
        rows = []
        for i, c in enumerate(self.pcurves):
            b = c.bezier_breakpoints()
            rows.append(np.stack([np.full(len(b) - 1, float(i)), b[:-1], b[1:]], axis=1))
        return np.concatenate(rows)

    def _pcurve_points(self, pieces):
        """``uv (m, 15, 2)`` and ``d(uv)/dt (m, 15, 2)`` at the K15 nodes of the pieces."""
        m = len(pieces)
        t = pieces[:, 1, None] + (pieces[:, 2] - pieces[:, 1])[:, None] * _T
        uv = np.empty((m, _NQ, 2))
        duv = np.empty((m, _NQ, 2))
        edge = pieces[:, 0].astype(np.intp)
        for i in np.unique(edge):  # one vectorized call per pcurve
            sel = edge == i
            d = self.pcurves[i].derivatives(t[sel].ravel(), 1)
            uv[sel] = d[0].reshape(-1, _NQ, 2)
            duv[sel] = d[1].reshape(-1, _NQ, 2)
        return uv, duv

    def evaluate(self, pieces, targets):
        m = len(pieces)
        uv, duv = self._pcurve_points(pieces)
        inner_tol = None if targets is None else 0.1 * targets / self.v_length
        G, G_err, n_eval = self._inner(uv[..., 0].ravel(), uv[..., 1].ravel(), inner_tol)
        k = G.shape[-1]
        half = 0.5 * (pieces[:, 2] - pieces[:, 1])
        vt = duv[..., 1] * half[:, None]  # dv/dt times the Jacobian of the map to [-1, 1]: (m, 15)
        f = G.reshape(m, _NQ, k) * vt[..., None]
        qk = np.einsum("i,mic->mc", _W_K, f)
        qg = np.einsum("i,mic->mc", _W_G, f)
        inner = np.einsum("i,mic->mc", _W_K, G_err.reshape(m, _NQ, k) * np.abs(vt)[..., None])
        absval = np.einsum("i,mic->mc", _W_K, np.abs(f))
        return qk, np.abs(qk - qg) + inner, absval, None, n_eval

    def split(self, pieces, info, targets):
        mid = 0.5 * (pieces[:, 1] + pieces[:, 2])
        a, b = pieces.copy(), pieces.copy()
        a[:, 2] = b[:, 1] = mid
        return np.concatenate([a, b])

    def _g(self, s, v):
        """The integrand at the nodes ``s`` ``(q, 15)`` of ``q`` intervals, each at its ``v`` ``(q,)``."""
        S, Su, Sv = (x.reshape(-1, 3) for x in cell_derivatives(self.surface, s, v[:, None]))
        return self.integrand(S, Su, Sv, self.sign)

    def _inner(self, u, v, tol):
        """``G(u, v) = integral from u_ref to u of g(s, v) ds`` at ``n`` points: ``(G (n, k),
        error (n, k), evaluations)``, adaptive K15 broken at the surface's u-knots.

        An interval is accepted when its error is within ``tol * length / width`` (``tol``:
        ``(k,)`` absolute tolerance of G per component), so every G meets ``tol``. On the first
        pass (``tol`` None) the tolerance is ``1e-13`` times the largest ``|g|`` seen times the length.
        """
        n = u.size
        # rounding of the pcurves' evaluation: stay within the range the trims span
        u = np.clip(u, self.u_ref, self.u_end)
        v = np.clip(v, *self.v_range)
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
            limits.check(q * _NQ * 8 * 24, "inner quadrature nodes")
            h = s1 - s0
            s = s0[:, None] + h[:, None] * _T
            f = self._g(s, vv).reshape(q, _NQ, -1)
            n_eval += f.shape[0] * _NQ
            if G is None:
                k = f.shape[-1]
                G, G_err = np.zeros((n, k)), np.zeros((n, k))
                if self.inner_scale is None:
                    self.inner_scale = np.maximum(np.abs(f).max(axis=(0, 1)), np.finfo(float).tiny)
            f = f * (0.5 * h)[:, None, None]
            qk = np.einsum("i,qic->qc", _W_K, f)
            err = np.abs(qk - np.einsum("i,qic->qc", _W_G, f))
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
