"""B-spline and NURBS curves as immutable value types.

A curve of degree ``p`` has ``n`` control points ``(n, dim)``, a knot vector of
``n + p + 1`` values and, when rational, ``n`` positive weights. Internally a
rational curve keeps its homogeneous coefficients ``(w * P, w)`` ``(n, dim + 1)``
and every knot operation (insertion, refinement, removal, elevation,
splitting) acts on them, so rational and polynomial curves share one code path
(:mod:`splinekit.basis.algebra`).
"""

from __future__ import annotations

from math import comb

import numpy as np

from .._validate import (
    MAX_DEGREE,
    as_affine,
    as_degree,
    as_float_array,
    as_int,
    as_order,
    as_params,
    as_points,
    as_positive,
    as_weights,
    finite_points,
    frozen,
    homogeneous,
    overflow_safe,
)
from .. import _kernels
from ..basis import algebra
from ..basis.bspline import basis_ders_t, basis_funs_t, combine, find_span, span_bounds
from ..basis.knots import clamped_uniform, domain, is_clamped, reparametrized, validate_knots
from ..basis.rational import rational_curve_derivatives
from ..errors import (
    DegreeError,
    DomainError,
    KnotRemovalError,
    KnotVectorError,
    ParameterError,
)
from ..tolerances import DEFAULT, geometric_tolerance

__all__ = ["SplineCurve", "BSplineCurve", "NurbsCurve"]

# Gauss-Legendre rule used per knot span (and per sub-interval) for arc length.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


class SplineCurve:
    """Common implementation of :class:`BSplineCurve` and :class:`NurbsCurve`.

    Do not instantiate directly; the subclasses validate their arguments.
    """

    __slots__ = ("_degree", "_knots", "_coefs", "_rational", "_cache")

    # -- construction -----------------------------------------------------------------
    @classmethod
    def _trusted(cls, degree: int, knots: np.ndarray, coefs: np.ndarray, rational: bool):
        """Build without checks from (homogeneous, if rational) coefficients."""
        if rational and cls is BSplineCurve:
            cls = NurbsCurve
        # knot algebra on coordinates near the float limit can overflow (differences,
        # products): refused here, so that no curve holds a non-finite control point
        finite_points(coefs, "the operation")
        obj = object.__new__(cls)
        obj._set(int(degree), knots, coefs, bool(rational))
        return obj

    def _set(self, p, U, coefs, rational):
        for name, value in (
            ("_degree", p),
            ("_knots", frozen(U)),
            ("_coefs", frozen(coefs)),
            ("_rational", rational),
            ("_cache", {}),
        ):
            object.__setattr__(self, name, value)

    def _like(self, degree: int, knots: np.ndarray, coefs: np.ndarray):
        """A new curve of the same kind (rational or not) as ``self``."""
        if self._rational:
            w = coefs[:, -1]
            if not (w > 0).all():
                raise KnotRemovalError("the result would have non-positive weights")
        return type(self)._trusted(degree, knots, coefs, self._rational)

    def __setattr__(self, name, value):
        raise AttributeError(f"{type(self).__name__} is immutable; operations return new curves")

    def __reduce__(self):  # pickling and copy go through the trusted constructor
        return (_rebuild_curve, (type(self), self._degree, np.array(self._knots), np.array(self._coefs), self._rational))

    # -- attributes -------------------------------------------------------------------
    @property
    def degree(self) -> int:
        """Polynomial degree ``p``."""
        return self._degree

    @property
    def knots(self) -> np.ndarray:
        """Full knot vector ``(n + p + 1,)`` with multiplicities repeated (read-only)."""
        return self._knots

    @property
    def control_points(self) -> np.ndarray:
        """Cartesian control points ``(n, dim)`` (read-only)."""
        if not self._rational:
            return self._coefs
        if "points" not in self._cache:
            self._cache["points"] = frozen(self._coefs[:, :-1] / self._coefs[:, -1:])
        return self._cache["points"]

    @property
    def weights(self):
        """Weights ``(n,)`` for a rational curve, ``None`` otherwise."""
        return self._coefs[:, -1] if self._rational else None

    @property
    def homogeneous_points(self) -> np.ndarray:
        """``(w * P, w)`` ``(n, dim + 1)``; weights of one for a polynomial curve."""
        if self._rational:
            return self._coefs
        return frozen(np.column_stack([self._coefs, np.ones(len(self._coefs))]))

    @property
    def is_rational(self) -> bool:
        return self._rational

    @property
    def dim(self) -> int:
        """Number of coordinates of a point."""
        return self._coefs.shape[1] - self._rational

    @property
    def domain(self) -> tuple[float, float]:
        """Parameter domain ``(U[p], U[n])``."""
        return domain(self._degree, self._knots)

    def __len__(self) -> int:
        """Number of control points."""
        return self._coefs.shape[0]

    # -- value semantics --------------------------------------------------------------
    def __eq__(self, other):
        if not isinstance(other, SplineCurve):
            return NotImplemented
        return (
            self._rational == other._rational
            and self._degree == other._degree
            and self._knots.shape == other._knots.shape
            and self._coefs.shape == other._coefs.shape
            and bool(np.array_equal(self._knots, other._knots))
            and bool(np.array_equal(self._coefs, other._coefs))
        )

    def __hash__(self):
        return hash((self._rational, self._degree, self._knots.tobytes(), self._coefs.tobytes()))

    def almost_equal(self, other, tol: float = 1e-12) -> bool:
        """Same kind, degree and knot count, knots and coefficients within ``tol``."""
        tol = as_positive(tol, "tol", allow_zero=True)
        return (
            isinstance(other, SplineCurve)
            and self._rational == other._rational
            and self._degree == other._degree
            and self._knots.shape == other._knots.shape
            and self._coefs.shape == other._coefs.shape
            and bool(np.allclose(self._knots, other._knots, rtol=0, atol=tol))
            and bool(np.allclose(self._coefs, other._coefs, rtol=0, atol=tol))
        )

    def __repr__(self):
        a, b = self.domain
        kind = type(self).__name__
        return (
            f"{kind}(degree={self._degree}, n_control={len(self)}, dim={self.dim}, "
            f"domain=[{a:g}, {b:g}], spans={np.unique(self._knots[self._degree:len(self) + 1]).size - 1})"
        )

    # -- evaluation -------------------------------------------------------------------
    def _params(self, u, name="u"):
        return as_params(u, self.domain, name)

    def evaluate(self, u) -> np.ndarray:
        """Points ``u.shape + (dim,)`` at the parameters ``u``.

        Always finite: a point is a convex combination of the control points, so
        only rounding near the float limit can overflow; such points are
        evaluated again on the curve scaled by a power of two (see
        :func:`splinekit._validate.overflow_safe`).
        """
        u = self._params(u)
        flat = u.ravel()
        with np.errstate(over="ignore", invalid="ignore"):
            pts = self._points(flat)
        if not np.isfinite(pts).all():
            pts = overflow_safe(self, lambda c: c._points(flat), self.control_points, 0)
        return pts.reshape(u.shape + (self.dim,))

    def _points(self, flat):
        """Points ``(n, dim)`` at the checked parameters ``flat`` (no overflow handling)."""
        p, U = self._degree, self._knots
        jit = _kernels.load("splinekit.basis._numba_kernels", work=flat.size)
        if jit is not None:
            pts = np.empty((flat.size, self.dim))
            jit.curve_points(p, U, *span_bounds(p, U), self._coefs, flat, self._rational, pts)
            return pts
        span = find_span(p, U, flat)
        N = basis_funs_t(p, U, span, flat)
        pts = combine(self._coefs, p, span, N)
        if self._rational:
            pts = pts[:, :-1] / pts[:, -1:]
        return pts

    def _scaled(self, k: int):
        """This curve with its coordinates multiplied by ``2**k`` (exact; weights unchanged)."""
        coefs = np.array(self._coefs)
        coefs[:, : self.dim] = np.ldexp(coefs[:, : self.dim], k)
        obj = object.__new__(type(self))
        obj._set(self._degree, self._knots, coefs, self._rational)
        return obj

    __call__ = evaluate

    def derivatives(self, u, order: int = 1) -> np.ndarray:
        """``C, C', ..., C^(order)`` at ``u``: ``(order + 1,) + u.shape + (dim,)``.

        Rational curves use the quotient rule of The NURBS Book A4.2.
        """
        order = as_order(order)
        u = self._params(u)
        flat = u.ravel()
        with np.errstate(over="ignore", invalid="ignore"):
            ders = self._derivatives(flat, order)
        if not np.isfinite(ders).all():
            ders = overflow_safe(self, lambda c: c._derivatives(flat, order), self.control_points, 1)
        return ders.reshape((order + 1,) + u.shape + (self.dim,))

    def _derivatives(self, flat, order):
        """``(order + 1, n, dim)`` at the checked parameters ``flat`` (no overflow handling)."""
        p, U = self._degree, self._knots
        jit = _kernels.load("splinekit.basis._numba_kernels", work=flat.size)
        if jit is not None:
            ders = np.empty((order + 1, flat.size, self.dim))
            binom = np.array([[comb(k, j) for j in range(order + 1)] for k in range(order + 1)], dtype=np.float64)
            jit.curve_derivatives(p, U, *span_bounds(p, U), self._coefs, flat, order, self._rational, binom, ders)
            return ders
        span = find_span(p, U, flat)
        ders = combine(self._coefs, p, span, basis_ders_t(p, U, span, flat, order))
        if self._rational:
            ders = rational_curve_derivatives(ders)
        return ders

    def tangent(self, u) -> np.ndarray:
        """Unit tangent vectors ``u.shape + (dim,)``.

        Where the first derivative vanishes (a cusp of the parametrization),
        the direction of the first non-vanishing higher derivative is used.
        """
        big = float(np.abs(self.control_points).max())
        if big >= 2.0**300:  # tangents do not depend on the scale; huge derivatives would overflow
            return self._scaled(-int(np.frexp(big)[1])).tangent(u)
        u = self._params(u)
        order = max(self._degree, 1)
        d = self.derivatives(u.ravel(), order)[1:]
        norms = np.linalg.norm(d, axis=-1)
        scale = max(float(np.abs(self.control_points).max()), 1.0)
        usable = norms > 1e-12 * scale
        first = np.where(usable.any(axis=0), usable.argmax(axis=0), 0)
        m = np.arange(d.shape[1])
        vec = d[first, m]
        n = norms[first, m]
        out = np.divide(vec, n[:, None], out=np.zeros_like(vec), where=n[:, None] > 0)
        return out.reshape(u.shape + (self.dim,))

    # -- knot algebra -----------------------------------------------------------------
    def _knot_value(self, u, name="u"):
        """A single parameter in the domain (clamped within the parameter
        slack), snapped onto an existing knot within the knot tolerance."""
        a, b = self.domain
        value = as_params(u, (a, b), name)
        if value.ndim != 0:
            raise ParameterError(f"{name} must be a single number, got an array of shape {value.shape}")
        u = float(value)
        near = np.abs(self._knots - u) <= DEFAULT.knot * (b - a)
        return float(self._knots[near][0]) if near.any() else u

    def elevation_matrix(self, by: int = 1):
        """Sparse ``(n_new, n)`` matrix mapping control coefficients onto the
        degree-elevated curve's (see :meth:`elevate_degree`)."""
        import scipy.sparse as sp

        by = _elevation_step(by, self._degree)
        if by == 0:
            return sp.identity(len(self), format="csr")
        _, M = algebra.elevate(self._degree, self._knots, np.eye(len(self)), by)
        M[np.abs(M) < 1e-15] = 0.0
        return sp.csr_matrix(M)

    def refine(self, knots):
        """Insert every value of ``knots`` (repeats allowed) at once (knot refinement)."""
        extra = as_float_array(knots, "knots", KnotVectorError).ravel()
        if extra.size == 0:
            return self
        extra = np.array([self._knot_value(x, "knots") for x in extra])
        tau = np.sort(np.concatenate([self._knots, extra]), kind="stable")
        tau = validate_knots(tau, self._degree, tau.size - self._degree - 1, "refined knots")
        coefs = algebra.refine(self._degree, self._knots, self._coefs, tau)
        return self._like(self._degree, tau, coefs)

    def insert_knot(self, u, times: int = 1):
        """Insert the knot ``u`` ``times`` times (its multiplicity may reach the degree)."""
        times = as_int(times, "times", minimum=0)
        u = self._knot_value(u)
        have = int(np.count_nonzero(self._knots == u))
        a, b = self.domain
        limit = self._degree if a < u < b else self._degree + 1
        if have + times > limit:
            raise KnotVectorError(
                f"inserting knot {u!r} {times} times would give multiplicity {have + times}; at most {limit} allowed"
            )
        return self.refine(np.full(times, u))

    def remove_knot(self, u, times: int = 1, tol: float | None = None):
        """Remove the interior knot ``u`` ``times`` times, moving the curve at most ``tol``.

        ``tol`` is a distance in model units; the default is ``1e-9`` times the
        size of the control net (its largest coordinate, at least 1). Raises
        :class:`KnotRemovalError` when the knot is absent or the removal would
        move the curve further than ``tol``.
        """
        times = as_int(times, "times", minimum=1)
        tol = geometric_tolerance(tol, self.control_points)
        u = self._knot_value(u)
        a, b = self.domain
        have = int(np.count_nonzero(self._knots == u))
        if not a < u < b or have == 0:
            raise KnotRemovalError(f"{u!r} is not an interior knot of this curve")
        if times > have:
            raise KnotRemovalError(f"knot {u!r} has multiplicity {have}; cannot remove it {times} times")
        tau, coefs, dev = algebra.remove_knots(self._degree, self._knots, self._coefs, u, times)
        allowed = tol
        if self._rational:
            # NURBS Book eq. (5.30): a homogeneous bound that implies the Cartesian one
            w = self._coefs[:, -1]
            allowed = tol * w.min() / (1.0 + np.linalg.norm(self.control_points, axis=1).max())
        if float(dev) > allowed:
            raise KnotRemovalError(
                f"removing knot {u!r} {times} time(s) would move the curve by up to {float(dev):.3g} "
                f"(coefficient space), more than the tolerance {allowed:.3g}"
            )
        return self._like(self._degree, tau, coefs)

    def elevate_degree(self, by: int = 1):
        """The same curve with degree raised by ``by`` (continuity kept at every knot)."""
        by = _elevation_step(by, self._degree)
        if by == 0:
            return self
        U, coefs = algebra.elevate(self._degree, self._knots, self._coefs, by)
        return self._like(self._degree + by, U, coefs)

    def clamp(self):
        """The same curve on a clamped knot vector (end knots of multiplicity p + 1)."""
        if is_clamped(self._degree, self._knots):
            return self
        U, coefs = algebra.clamp(self._degree, self._knots, self._coefs)
        return self._like(self._degree, U, coefs)

    def to_bezier(self):
        """Bézier decomposition: a list of :class:`~splinekit.BezierCurve`, one per
        non-empty knot span in order, each on the local parameter [0, 1]."""
        from .bezier import BezierCurve

        _, segs = algebra.bezier_segments(self._degree, self._knots, self._coefs)
        return [BezierCurve._from_coefs(s, self._rational) for s in segs]

    def bezier_breakpoints(self) -> np.ndarray:
        """Distinct knots of the domain: the span ``i`` of :meth:`to_bezier` is ``[b[i], b[i+1]]``."""
        a, b = self.domain
        k = self._knots
        return np.unique(k[(k >= a) & (k <= b)])

    def split(self, u):
        """Two curves ``(left, right)`` on ``[a, u]`` and ``[u, b]``."""
        u = self._knot_value(u)
        a, b = self.domain
        if not a < u < b:
            raise DomainError(f"split parameter {u!r} must lie strictly inside the domain ({a!r}, {b!r})")
        (kl, cl), (kr, cr) = algebra.split(self._degree, self._knots, self._coefs, u)
        return self._like(self._degree, kl, cl), self._like(self._degree, kr, cr)

    def segment(self, u0, u1):
        """The piece of the curve on ``[u0, u1]``, keeping its parametrization."""
        u0, u1 = self._knot_value(u0, "u0"), self._knot_value(u1, "u1")
        if not u0 < u1:
            raise DomainError(f"segment needs u0 < u1, got [{u0!r}, {u1!r}]")
        a, b = self.domain
        curve = self
        if u1 < b:
            curve = curve.split(u1)[0]
        if u0 > a:
            curve = curve.split(u0)[1]
        return curve

    def reverse(self):
        """The same point set traversed backwards, on the same domain."""
        U, coefs = algebra.reverse(self._degree, self._knots, self._coefs)
        return self._like(self._degree, U, coefs)

    def reparametrize(self, start: float, end: float):
        """The same curve with its domain mapped affinely onto ``[start, end]``."""
        U = reparametrized(self._degree, self._knots, start, end)
        return self._like(self._degree, U, self._coefs)

    def transform(self, matrix):
        """Apply an affine map: ``(dim, dim)`` linear or ``(dim + 1, dim + 1)`` homogeneous.

        Affine invariance: mapping the Cartesian control points maps the curve;
        the weights stay as they are.
        """
        L, t = as_affine(matrix, self.dim)
        with np.errstate(over="ignore", invalid="ignore"):
            P = finite_points(self.control_points @ L.T + t, "the transform")
        if self._rational:
            return self._like(self._degree, self._knots, homogeneous(P, self._coefs[:, -1]))
        return self._like(self._degree, self._knots, P)

    def to_nurbs(self):
        """This curve as a :class:`NurbsCurve` (unit weights if polynomial)."""
        if self._rational:
            return self
        return NurbsCurve._trusted(self._degree, self._knots, self.homogeneous_points, True)

    # -- measures ---------------------------------------------------------------------
    def arc_length(self, start=None, end=None, tol: float = 1e-12) -> float:
        """Length of the curve between parameters ``start`` and ``end`` (default: the domain).

        Gauss-Legendre quadrature (8 points) on every knot span, with the spans
        halved uniformly until two successive estimates agree to ``tol``
        (relative); at most 2**10 pieces per span.
        """
        tol = as_positive(tol, "tol")
        a, b = self.domain
        s = a if start is None else float(self._params(start, "start"))
        e = b if end is None else float(self._params(end, "end"))
        if e < s:
            return -self.arc_length(e, s, tol)
        if e == s:
            return 0.0
        k = self.bezier_breakpoints()
        edges = np.unique(np.concatenate([[s], k[(k > s) & (k < e)], [e]]))
        previous = None
        for level in range(11):
            pieces = 2**level
            t = np.linspace(0.0, 1.0, pieces + 1)
            lo = edges[:-1, None] + (edges[1:] - edges[:-1])[:, None] * t[None, :-1]
            width = (edges[1:] - edges[:-1])[:, None] / pieces
            mid = lo + 0.5 * width
            x = (mid[..., None] + 0.5 * width[..., None] * _GL_X).ravel()
            speed = np.linalg.norm(self.derivatives(x, 1)[1], axis=-1)
            total = float((speed.reshape(mid.shape + (_GL_X.size,)) * _GL_W * 0.5 * width[..., None]).sum())
            if previous is not None and abs(total - previous) <= tol * max(abs(total), 1e-300):
                return total
            previous = total
        return total

    def is_closed(self, tol: float | None = None) -> bool:
        """True when the end point equals the start point within ``tol``
        (default: 1e-9 times the control net's size)."""
        tol = geometric_tolerance(tol, self.control_points)
        a, b = self.domain
        ends = self.evaluate(np.array([a, b]))
        return bool(np.linalg.norm(ends[1] - ends[0]) <= tol)

    # -- constructors -----------------------------------------------------------------
    @classmethod
    def closed(cls, degree: int, control_points, weights=None):
        """A closed curve, ``C^(p-1)`` everywhere including the seam.

        The ``n`` control points form a cyclic polygon; the curve is built on
        uniform knots with the first ``p`` points repeated, then clamped, so it
        is returned on a clamped knot vector over ``[0, 1]`` whose ends match.
        """
        p = as_degree(degree)
        P = as_points(control_points, min_count=(p + 1,))
        n = P.shape[0]
        wrapped = np.vstack([P, P[:p]])
        knots = np.arange(n + 2 * p + 1, dtype=np.float64)
        if weights is not None:
            w = as_weights(weights, (n,))
            w = np.concatenate([w, w[:p]])
            coefs = homogeneous(wrapped, w)
        else:
            coefs = wrapped
        U, C = algebra.clamp(p, knots, coefs)
        U = (U - U[0]) / (U[-1] - U[0])
        rational = weights is not None
        target = NurbsCurve if rational else BSplineCurve
        return target._trusted(p, U, C, rational)


class BSplineCurve(SplineCurve):
    """Non-rational B-spline curve.

    Parameters
    ----------
    degree : int
        Polynomial degree ``p >= 1``.
    knots : array_like, shape (n + p + 1,)
        Non-decreasing knot vector (clamped or not); the domain is ``[U[p], U[n]]``.
    control_points : array_like, shape (n, dim)
        Control points of any dimension, ``n >= p + 1``.
    """

    __slots__ = ()

    def __init__(self, degree, knots, control_points):
        p = as_degree(degree)
        P = as_points(control_points, min_count=(p + 1,))
        U = validate_knots(knots, p, P.shape[0])
        self._set(p, U, P, False)

    @classmethod
    def uniform(cls, degree, control_points, start: float = 0.0, end: float = 1.0):
        """Curve on a clamped knot vector with uniformly spaced interior knots."""
        p = as_degree(degree)
        P = as_points(control_points, min_count=(p + 1,))
        return cls(p, clamped_uniform(p, P.shape[0], start, end), P)


class NurbsCurve(BSplineCurve):
    """Rational B-spline (NURBS) curve.

    Parameters
    ----------
    degree, knots, control_points
        As for :class:`BSplineCurve`; ``control_points`` are Cartesian.
    weights : array_like, shape (n,)
        Finite, strictly positive weights.
    """

    __slots__ = ()

    def __init__(self, degree, knots, control_points, weights):
        p = as_degree(degree)
        P = as_points(control_points, min_count=(p + 1,))
        U = validate_knots(knots, p, P.shape[0])
        w = as_weights(weights, (P.shape[0],))
        self._set(p, U, homogeneous(P, w), True)

    @classmethod
    def uniform(cls, degree, control_points, weights=None, start: float = 0.0, end: float = 1.0):
        """Curve on a clamped uniform knot vector (unit weights by default)."""
        p = as_degree(degree)
        P = as_points(control_points, min_count=(p + 1,))
        w = np.ones(P.shape[0]) if weights is None else weights
        return cls(p, clamped_uniform(p, P.shape[0], start, end), P, w)



def _elevation_step(by, degree: int) -> int:
    """``by`` checked so that ``degree + by`` stays within MAX_DEGREE."""
    by = as_int(by, "by", minimum=0)
    if degree + by > MAX_DEGREE:
        raise DegreeError(f"elevating degree {degree} by {by} exceeds the largest supported degree {MAX_DEGREE}")
    return by


def _rebuild_curve(cls, degree, knots, coefs, rational):
    return cls._trusted(degree, knots, coefs, rational)
