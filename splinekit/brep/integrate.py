"""Adaptive quadrature over trimmed faces: integrals of smooth integrands over a face's (u, v)
domain to a requested relative tolerance, with an error estimate.

Two rules, both built on the 7-15 point Gauss-Kronrod pair (the 7-point Gauss rule is embedded in
the 15-point Kronrod rule, so the difference of the two costs no extra evaluation):

- **Untrimmed faces** (natural domain, or one loop around an axis-parallel rectangle): the tensor rule K15 x K15 on cells, starting from the
  surface's Bézier spans. A cell's error is ``|K x K - G x K| + |K x K - K x G|`` (the u and v
  parts); cells whose error is too large are bisected across the direction with the larger part.
- **Trimmed faces**: Green's theorem, ``integral over D of g du dv = closed integral over dD of
  G(u, v) dv`` with ``G(u, v) = integral from u_ref to u of g(s, v) ds`` (``u_ref`` the domain's
  left end). The outer integral runs along the pcurves (pieces split at their knots, K15 along
  each, bisected where needed); the inner one is an adaptive K15 in ``s``, broken at the
  surface's u-knots. The inner error is carried into the outer piece's error.

Both are *globally* adaptive over every face passed at once: each pass evaluates the new pieces
(cells or pcurve intervals) of every face (one vectorized evaluation per face), sums values and
error estimates, and bisects the pieces carrying the largest share of the error until the total
error of every component is below ``tol`` times that component's scale. The estimate
``|K15 - G7|`` is the error of the 7-point rule, an upper bound in practice for the 15-point
value returned: it brackets the true error on smooth integrands.

An integrand is a callable ``f(S, Su, Sv, sign) -> (n, k)`` given the points ``S`` ``(n, 3)``,
the partial derivatives ``Su``, ``Sv`` ``(n, 3)`` and the face's orientation ``sign`` (+1, or -1 for
a reversed face); ``k`` integrals are computed at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import limits
from .._validate import as_positive
from ..basis.bspline import basis_ders_t, find_span
from ..construct.curves import line
from ..errors import DomainError, ParameterError
from ..tolerances import INTEGRAL_RTOL

__all__ = ["Integral", "integrate", "integrate_face", "kronrod15", "DEFAULT_TOLERANCE"]

DEFAULT_TOLERANCE = INTEGRAL_RTOL
"""Default relative tolerance of the integrals."""

MAX_PASSES = 80
"""Passes of the outer adaptive loop before it gives up (and reports ``converged=False``)."""

MAX_INNER_LEVELS = 60
"""Bisection levels of the inner (Green) integrals before their error is accepted as it is."""

MAX_PIECES = 200_000
"""Cells or intervals in play at once (outer pieces of all faces, or inner intervals of one
pass) beyond which the integration stops refining and reports what it has (with its error
estimate and ``converged=False``) instead of exhausting memory on a singular integrand."""

# 7-15 Gauss-Kronrod on [-1, 1]: the non-negative nodes and their weights, computed with 40-digit
# arithmetic (Stieltjes polynomial roots, moment equations); tests check them against numpy's
# Gauss-Legendre rule and the rule's exactness for degree 22.
_XK = np.array([0.0, 0.2077849550078984676, 0.40584515137739716691, 0.58608723546769113029,
                0.74153118559939443986, 0.86486442335976907279, 0.94910791234275852453,
                0.99145537112081263921])
_WK = np.array([0.20948214108472782801, 0.20443294007529889241, 0.19035057806478540991,
                0.16900472663926790283, 0.14065325971552591875, 0.10479001032225018384,
                0.063092092629978553291, 0.022935322010529224964])
_WG = np.array([0.41795918367346938776, 0.0, 0.38183005050511894495, 0.0, 0.2797053914892766679, 0.0,
                0.12948496616886969327, 0.0])


def kronrod15() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 7-15 Gauss-Kronrod rule on ``[-1, 1]``: ``(nodes (15,), kronrod weights (15,),
    gauss weights (15,))``, nodes ascending; the Gauss weights are zero at the Kronrod-only nodes."""
    x = np.concatenate([-_XK[:0:-1], _XK])
    wk = np.concatenate([_WK[:0:-1], _WK])
    wg = np.concatenate([_WG[:0:-1], _WG])
    return x, wk, wg


_X, _W_K, _W_G = kronrod15()
_T = 0.5 * (_X + 1.0)  # nodes on [0, 1]
_NQ = _X.size


@dataclass(frozen=True)
class Integral:
    """Result of an adaptive integration.

    Attributes
    ----------
    value : (k,) ndarray
        The integrals.
    error : (k,) ndarray
        Error estimates (absolute, same units as ``value``).
    evaluations : int
        Integrand evaluations used.
    converged : bool
        Whether every component met its tolerance.
    """

    value: np.ndarray
    error: np.ndarray
    evaluations: int
    converged: bool


# ---------------------------------------------------------------------------
# the surface on the nodes of many cells at once

def _cell_derivatives(surface, u, v):
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


# ---------------------------------------------------------------------------
# per-face rules: initial pieces, evaluation of pieces, bisection

class _TensorRule:
    """K15 x K15 on cells ``(m, 4)`` = ``[u0, u1, v0, v1]`` of an untrimmed face, or of a face
    whose only loop is an axis-parallel rectangle ``rect`` = ``(u0, u1, v0, v1)``."""

    def __init__(self, face, integrand, rect=None):
        self.surface = face.surface
        self.sign = -1.0 if face.reversed else 1.0
        self.integrand = integrand
        self.rect = rect
        if rect is not None:  # the rectangle's sides: the same domain check as Green's trims
            _check_in_domain(face, [_samples(e.pcurve) for e in face.loops[0]])

    def initial(self):
        bu, bv = self.surface.bezier_breakpoints()
        if self.rect is not None:
            u0, u1, v0, v1 = self.rect
            bu = np.concatenate([[u0], bu[(bu > u0) & (bu < u1)], [u1]])
            bv = np.concatenate([[v0], bv[(bv > v0) & (bv < v1)], [v1]])
        U0, V0 = np.meshgrid(bu[:-1], bv[:-1], indexing="ij")
        U1, V1 = np.meshgrid(bu[1:], bv[1:], indexing="ij")
        return np.stack([U0.ravel(), U1.ravel(), V0.ravel(), V1.ravel()], axis=1)

    def evaluate(self, cells, targets):
        m = len(cells)
        limits.check(m * _NQ * _NQ * 8 * 24, "tensor quadrature nodes")
        du, dv = cells[:, 1] - cells[:, 0], cells[:, 3] - cells[:, 2]
        u = cells[:, 0, None] + du[:, None] * _T  # (m, 15)
        v = cells[:, 2, None] + dv[:, None] * _T
        S, Su, Sv = (x.reshape(-1, 3) for x in _cell_derivatives(self.surface, u, v))
        f = self.integrand(S, Su, Sv, self.sign)  # (m * 225, k)
        k = f.shape[-1]
        f = f.reshape(m, _NQ, _NQ, k) * (0.25 * du * dv)[:, None, None, None]
        fk = np.einsum("j,mijc->mic", _W_K, f)  # v contracted with Kronrod
        fg = np.einsum("j,mijc->mic", _W_G, f)  # v contracted with Gauss
        kk = np.einsum("i,mic->mc", _W_K, fk)
        gk = np.einsum("i,mic->mc", _W_G, fk)
        kg = np.einsum("i,mic->mc", _W_K, fg)
        absval = np.einsum("i,j,mijc->mc", _W_K, _W_K, np.abs(f))
        err_u, err_v = np.abs(kk - gk), np.abs(kk - kg)
        return kk, err_u + err_v, absval, (err_u, err_v), m * _NQ * _NQ

    def split(self, cells, info, targets):
        err_u, err_v = info
        in_u = (err_u / targets).max(axis=1) >= (err_v / targets).max(axis=1)
        mid_u = 0.5 * (cells[:, 0] + cells[:, 1])
        mid_v = 0.5 * (cells[:, 2] + cells[:, 3])
        a, b = cells.copy(), cells.copy()
        a[in_u, 1] = b[in_u, 0] = mid_u[in_u]
        a[~in_u, 3] = b[~in_u, 2] = mid_v[~in_u]
        return np.concatenate([a, b])


class _GreenRule:
    """Green's theorem along the trimming loops of a trimmed face; pieces ``(m, 3)`` =
    ``[edge index, t0, t1]`` of the face's pcurves."""

    def __init__(self, face, integrand):
        self.surface = face.surface
        self.sign = -1.0 if face.reversed else 1.0
        self.integrand = integrand
        (ua, ub), (v0, v1) = self.surface.domain
        self.pcurves = _closed_pcurves(face.loops, 1e-14 * max(ub - ua, v1 - v0))
        samples = [_samples(c) for c in self.pcurves]
        _check_in_domain(face, samples)
        # G is integrated from the left of the trims (any constant u_ref will do); trims a little
        # past the domain take the surface's polynomial extension, as OCC does. The margin keeps
        # nodes past the samples' extremes unclipped (clipping cut 5e-6 off a disc tangent to
        # the domain's sides at tolerances below 1e-8).
        lo, hi = np.min([x.min(axis=0) for x in samples], axis=0), np.max([x.max(axis=0) for x in samples], axis=0)
        mu, mv = OUTSIDE_DOMAIN * (ub - ua), OUTSIDE_DOMAIN * (v1 - v0)
        self.u_ref, self.u_end = min(ua, float(lo[0])) - mu, max(ub, float(hi[0])) + mu
        self.v_range = (min(v0, float(lo[1])) - mv, max(v1, float(hi[1])) + mv)
        self.width = max(self.u_end - self.u_ref, np.finfo(float).tiny)
        bu = self.surface.bezier_breakpoints()[0]
        self.u_breaks = np.concatenate([[self.u_ref], bu[(bu > self.u_ref) & (bu < self.u_end)], [self.u_end]])
        # total variation of v along the loops: bounds how inner errors add up in the outer sum
        total = 0.0
        for c in self.pcurves:
            t, w = _gauss_on(c.bezier_breakpoints())
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
        S, Su, Sv = (x.reshape(-1, 3) for x in _cell_derivatives(self.surface, s, v[:, None]))
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


_GL16 = np.polynomial.legendre.leggauss(16)


OUTSIDE_DOMAIN = 1e-3
"""Trims past the domain by more than this fraction of its width are checked in 3-D (approximated
trims overshoot by 1e-4, trims of another period by 1)."""
OUTSIDE_EDGE_TOLERANCES = 4.0  # and then by at most this many edge tolerances, measured in 3-D


def _samples(curve, per_piece: int = 33):
    """``(n, 2)`` points of a pcurve, ``per_piece`` on each of its Bézier pieces (ends included)."""
    b = curve.bezier_breakpoints()
    t = (b[:-1, None] + (b[1:] - b[:-1])[:, None] * np.linspace(0.0, 1.0, per_piece)).ravel()
    return curve.evaluate(t)


def _check_in_domain(face, samples):
    """Raise DomainError when a trim (its ``samples``, one ``(n, 2)`` array per pcurve) leaves
    the surface's domain by more than :data:`OUTSIDE_DOMAIN` of its width and, in 3-D, by more
    than :data:`OUTSIDE_EDGE_TOLERANCES` times the face's largest edge tolerance: within that, the
    integrand over the excursion is the surface's polynomial extension, which is how OpenCascade
    evaluates such a face too (files with 5e-3 edge tolerances overshoot by 1e-2); beyond it the
    trim belongs to something else (another period of a periodic surface) and the result would
    be silently wrong."""
    surface = face.surface
    limit = OUTSIDE_EDGE_TOLERANCES * max([face.tolerance] + [e.tolerance for lp in face.loops for e in lp])
    (u0, u1), (v0, v1) = surface.domain
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


def _closed_pcurves(loops, tiny):
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


def _gauss_on(breaks):
    """16-point Gauss-Legendre nodes and weights on every interval between consecutive ``breaks``."""
    g, w = _GL16
    breaks = np.asarray(breaks, dtype=float)
    mid, half = 0.5 * (breaks[1:] + breaks[:-1]), 0.5 * (breaks[1:] - breaks[:-1])
    return (mid[:, None] + half[:, None] * g).ravel(), (half[:, None] * w).ravel()


def _rectangle(face, rel: float = 1e-12):
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


def _rule_for(face, integrand):
    if not face.is_trimmed:
        return _TensorRule(face, integrand)
    rect = _rectangle(face)
    return _GreenRule(face, integrand) if rect is None else _TensorRule(face, integrand, rect)


# ---------------------------------------------------------------------------
# the globally adaptive loop

def integrate(faces, integrand, *, tol: float = DEFAULT_TOLERANCE, scale=None) -> Integral:
    """Integrals of ``integrand`` over the trimmed domains of ``faces``, summed.

    Parameters
    ----------
    faces : sequence of TrimmedFace
    integrand : callable ``f(S, Su, Sv, sign) -> (n, k)``
        ``S``, ``Su``, ``Sv``: ``(n, 3)`` points and partial derivatives; ``sign``: -1.0 for a
        reversed face, else 1.0. Integrated with respect to ``du dv``.
    tol : float
        Relative tolerance: the loop stops when every component's error estimate is at most
        ``tol * scale`` of that component.
    scale : callable ``(value (k,), abs_value (k,)) -> (k,)``, optional
        The magnitude each component's error is measured against, from the current estimates of
        the integrals and of the integrals of their absolute values. Default: the integral of
        ``|f|`` (QUADPACK's choice), which is the integral itself for a positive integrand.

    Returns
    -------
    Integral
        ``value`` and ``error`` ``(k,)``, evaluation count, convergence flag.
    """
    tol = as_positive(tol, "tol")
    if tol < 1e-15:
        raise ParameterError(f"tol = {tol!r} is below what double precision can deliver (1e-15)")
    faces = list(faces)
    if not faces:
        raise ParameterError("nothing to integrate: no faces")
    rules = [_rule_for(f, integrand) for f in faces]
    new = [r.initial() for r in rules]
    # accepted pieces per face: pieces, values, errors, absolute values, split info
    pieces = [np.empty((0, 4 if isinstance(r, _TensorRule) else 3)) for r in rules]
    vals, errs, abss, infos = [None] * len(rules), [None] * len(rules), [None] * len(rules), [None] * len(rules)
    n_eval = 0
    targets = None
    converged = False
    for _pass in range(MAX_PASSES):
        for i, r in enumerate(rules):
            if len(new[i]) == 0:
                continue
            val, err, absval, info, used = r.evaluate(new[i], targets)
            n_eval += used
            if vals[i] is None:
                pieces[i], vals[i], errs[i], abss[i], infos[i] = new[i], val, err, absval, info
            else:
                pieces[i] = np.concatenate([pieces[i], new[i]])
                vals[i] = np.concatenate([vals[i], val])
                errs[i] = np.concatenate([errs[i], err])
                abss[i] = np.concatenate([abss[i], absval])
                if info is not None:
                    infos[i] = tuple(np.concatenate([a, b]) for a, b in zip(infos[i], info))
        total = sum(v.sum(axis=0) for v in vals)
        total_err = sum(e.sum(axis=0) for e in errs)
        total_abs = sum(a.sum(axis=0) for a in abss)
        magnitude = total_abs if scale is None else np.asarray(scale(total, total_abs), dtype=float)
        tiny = np.finfo(float).tiny
        targets = np.maximum(tol * np.abs(magnitude), 1e3 * np.finfo(float).eps * tol * total_abs + tiny)
        if np.all(total_err <= targets):
            converged = True
            break
        if sum(len(p) for p in pieces) > MAX_PIECES:
            break
        # bisect the pieces that carry the largest share of the error: keep (unsplit) the
        # smallest-error pieces whose errors add up to at most half the budget
        scores = [np.max(e / targets, axis=1) for e in errs]
        flat = np.concatenate(scores)
        order = np.argsort(flat)
        keep_flat = np.zeros(flat.size, bool)
        keep_flat[order[np.cumsum(flat[order]) <= 0.5]] = True
        start = 0
        for i, r in enumerate(rules):
            m = len(scores[i])
            split = ~keep_flat[start:start + m]
            start += m
            if not split.any():
                new[i] = pieces[i][:0]
                continue
            info_split = None if infos[i] is None else tuple(a[split] for a in infos[i])
            new[i] = r.split(pieces[i][split], info_split, targets)
            keep = ~split
            pieces[i], vals[i], errs[i], abss[i] = pieces[i][keep], vals[i][keep], errs[i][keep], abss[i][keep]
            if infos[i] is not None:
                infos[i] = tuple(a[keep] for a in infos[i])
    return Integral(np.asarray(total, float), np.asarray(total_err, float), int(n_eval), converged)


def integrate_face(face, integrand, *, tol: float = DEFAULT_TOLERANCE, scale=None) -> Integral:
    """:func:`integrate` over one face."""
    return integrate([face], integrand, tol=tol, scale=scale)
