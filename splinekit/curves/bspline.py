"""B-spline, NURBS and Bézier curves as immutable value types.

A curve of degree ``p`` has ``n`` control points ``(n, dim)``, a knot vector of
``n + p + 1`` values and, when rational, ``n`` positive weights. Internally a
rational curve keeps its homogeneous coefficients ``(w * P, w)`` ``(n, dim + 1)``
and every knot operation (insertion, refinement, removal, elevation,
splitting) acts on them, so rational and polynomial curves share one code path
(:mod:`splinekit.basis.algebra`). The knot operations and the measures are
mixins from :mod:`.knot_algebra` and :mod:`.measures`.

:class:`BezierCurve` lives here too: it wraps a B-spline curve on Bézier knots,
and :meth:`SplineCurve.to_bezier` returns Bézier curves; the two types convert
into each other, so they share one module rather than import each other.
"""

from __future__ import annotations

from math import comb

import numpy as np

from .._validate import (
    as_degree,
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
from ..basis.bernstein import bezier_knots
from ..basis.bspline import basis_ders_t, basis_funs_t, combine, find_span, span_bounds
from ..basis.knots import clamped_uniform, domain, validate_knots
from ..basis.rational import rational_curve_derivatives
from ..basis.taylor import MAX_DEGREE as TAYLOR_MAX_DEGREE, span_taylor
from ..errors import KnotRemovalError, ParameterError
from ..tolerances import ARC_LENGTH_RTOL
from .knot_algebra import CurveKnotAlgebra, _elevation_step
from .measures import CurveMeasures

__all__ = ["SplineCurve", "BSplineCurve", "NurbsCurve", "BezierCurve"]


class SplineCurve(CurveKnotAlgebra, CurveMeasures):
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
        job = self._kernel_job(flat.size)
        if job is not None:
            pts = np.empty((flat.size, self.dim))
            job[0].curve_points(*job[1:], flat, self._rational, pts)
            return pts
        span = find_span(p, U, flat)
        N = basis_funs_t(p, U, span, flat)
        pts = combine(self._coefs, p, span, N)
        if self._rational:
            pts = pts[:, :-1] / pts[:, -1:]
        return pts

    def _kernel_job(self, n: int):
        """The compiled kernels for ``n`` points and their leading arguments, or None (small job,
        compiled code off: the numpy path). Up to :data:`~splinekit.basis.taylor.MAX_DEGREE`:
        the Taylor-table kernels and this curve's :func:`~splinekit.basis.taylor.span_taylor`
        (built once); above it the A2.2 kernels, the knots and the coefficients."""
        p, U = self._degree, self._knots
        taylor = p <= TAYLOR_MAX_DEGREE  # one load call per job: each counts towards LOAD_WORK
        K = _kernels.load("splinekit.basis._taylor_kernels" if taylor else "splinekit.basis._numba_kernels", work=n)
        if K is None or not taylor:
            return None if K is None else (K, p, U, *span_bounds(p, U), self._coefs)
        if "taylor" not in self._cache:
            self._cache["taylor"] = span_taylor(p, U, self._coefs)
        return (K,) + self._cache["taylor"]

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
        job = self._kernel_job(flat.size)
        if job is not None:
            ders = np.empty((order + 1, flat.size, self.dim))
            binom = np.array([[comb(k, j) for j in range(order + 1)] for k in range(order + 1)], dtype=np.float64)
            job[0].curve_derivatives(*job[1:], flat, order, self._rational, binom, ders)
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

    # -- conversions ------------------------------------------------------------------
    def to_bezier(self):
        """Bézier decomposition: a list of :class:`~splinekit.BezierCurve`, one per
        non-empty knot span in order, each on the local parameter [0, 1]."""
        _, segs = algebra.bezier_segments(self._degree, self._knots, self._coefs)
        return [BezierCurve._from_coefs(s, self._rational) for s in segs]

    def to_nurbs(self):
        """This curve as a :class:`NurbsCurve` (unit weights if polynomial)."""
        if self._rational:
            return self
        return NurbsCurve._trusted(self._degree, self._knots, self.homogeneous_points, True)

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


class BezierCurve:
    """(Rational) Bézier curve on the parameter [0, 1].

    A Bézier curve of degree ``p`` is the B-spline on the knot vector
    ``[0]*(p+1) + [1]*(p+1)``; this class wraps that spline, so evaluation,
    derivatives, splitting and elevation run through the same vectorized code as
    every other spline (de Casteljau's triangle is the Cox-de Boor triangle on
    those knots).

    Parameters
    ----------
    control_points : array_like, shape (p + 1, dim)
        At least two points; the degree is ``len(control_points) - 1``.
    weights : array_like, shape (p + 1,), optional
        Positive weights for a rational curve.
    """

    __slots__ = ("_spline",)

    def __init__(self, control_points, weights=None):
        P = as_points(control_points, min_count=(2,))
        p = P.shape[0] - 1
        if weights is None:
            spline = BSplineCurve(p, bezier_knots(p), P)
        else:
            spline = NurbsCurve(p, bezier_knots(p), P, as_weights(weights, (p + 1,)))
        object.__setattr__(self, "_spline", spline)

    @classmethod
    def _from_coefs(cls, coefs: np.ndarray, rational: bool):
        obj = object.__new__(cls)
        p = coefs.shape[0] - 1
        object.__setattr__(obj, "_spline", BSplineCurve._trusted(p, bezier_knots(p), coefs, rational))
        return obj

    def __reduce__(self):
        return (type(self)._from_coefs, (np.array(self._spline._coefs), self.is_rational))

    def __setattr__(self, name, value):
        raise AttributeError("BezierCurve is immutable; operations return new curves")

    # attributes
    degree = property(lambda self: self._spline.degree, doc="Degree ``p``.")
    control_points = property(lambda self: self._spline.control_points, doc="``(p + 1, dim)`` (read-only).")
    weights = property(lambda self: self._spline.weights, doc="``(p + 1,)`` or ``None``.")
    dim = property(lambda self: self._spline.dim, doc="Number of coordinates.")
    is_rational = property(lambda self: self._spline.is_rational)
    domain = (0.0, 1.0)

    def __len__(self):
        return len(self._spline)

    def __eq__(self, other):
        if not isinstance(other, BezierCurve):
            return NotImplemented
        return self._spline == other._spline

    def __hash__(self):
        return hash(("bezier", hash(self._spline)))

    def almost_equal(self, other, tol: float = 1e-12) -> bool:
        return isinstance(other, BezierCurve) and self._spline.almost_equal(other._spline, tol)

    def __repr__(self):
        kind = "rational " if self.is_rational else ""
        return f"BezierCurve({kind}degree={self.degree}, dim={self.dim})"

    # evaluation
    def evaluate(self, t) -> np.ndarray:
        """Points ``t.shape + (dim,)`` for ``t`` in [0, 1]."""
        return self._spline.evaluate(t)

    __call__ = evaluate

    def derivatives(self, t, order: int = 1) -> np.ndarray:
        """``(order + 1,) + t.shape + (dim,)``: the curve and its derivatives."""
        return self._spline.derivatives(t, order)

    def tangent(self, t) -> np.ndarray:
        return self._spline.tangent(t)

    def arc_length(self, tol: float = ARC_LENGTH_RTOL) -> float:
        return self._spline.arc_length(tol=tol)

    # operations
    def split(self, t):
        """Two Bézier curves on [0, t] and [t, 1], each reparametrized to [0, 1]."""
        left, right = self._spline.split(t)
        return (
            BezierCurve._from_coefs(left._coefs, self.is_rational),
            BezierCurve._from_coefs(right._coefs, self.is_rational),
        )

    def elevate(self, by: int = 1):
        """The same curve with degree ``p + by``."""
        by = _elevation_step(by, self.degree)
        E = algebra.bezier_elevation_matrix(self.degree, by)
        return BezierCurve._from_coefs(E @ self._spline._coefs, self.is_rational)

    def transform(self, matrix):
        return BezierCurve._from_coefs(self._spline.transform(matrix)._coefs, self.is_rational)

    def reverse(self):
        return BezierCurve._from_coefs(self._spline._coefs[::-1], self.is_rational)

    @classmethod
    def from_bspline(cls, curve: SplineCurve):
        """The Bézier form of a single-span spline curve (use ``curve.to_bezier()``
        for several spans); the parameter is mapped onto [0, 1]."""
        if not isinstance(curve, SplineCurve):
            raise ParameterError(f"expected a BSplineCurve or NurbsCurve, got {type(curve).__name__}")
        if curve.bezier_breakpoints().size != 2:
            raise ParameterError(
                f"curve has {curve.bezier_breakpoints().size - 1} knot spans; a Bézier curve has one "
                "(use curve.to_bezier() for the list of segments)"
            )
        return curve.to_bezier()[0]

    def to_bspline(self):
        """This curve as a :class:`BSplineCurve` / :class:`NurbsCurve` on [0, 1]."""
        return self._spline


def _rebuild_curve(cls, degree, knots, coefs, rational):
    return cls._trusted(degree, knots, coefs, rational)
