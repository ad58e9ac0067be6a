"""Tensor-product B-spline, NURBS and Bézier surfaces as immutable value types.

Control points are ``(nu, nv, dim)``; a rational surface keeps homogeneous
coefficients ``(w * P, w)`` ``(nu, nv, dim + 1)`` internally. Grid evaluation,
normals and the knot algebra are mixins from :mod:`.grid`, :mod:`.normals` and
:mod:`.knot_algebra`.

:class:`BezierSurface` lives here too: it wraps a B-spline surface on Bézier
knots, and :meth:`SplineSurface.to_bezier` returns Bézier patches; the two types
convert into each other, so they share one module rather than import each other.
"""

from __future__ import annotations

import numpy as np

from .._validate import (
    as_degree,
    as_direction,
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
from ..basis.bspline import basis_ders_t, basis_funs_t, find_span, span_bounds
from ..basis.knots import clamped_uniform, domain, validate_knots
from ..basis.rational import rational_surface_derivatives
from ..curves.knot_algebra import _elevation_step
from ..errors import KnotRemovalError, ParameterError
from .grid import SurfaceGrids
from .knot_algebra import SurfaceKnotAlgebra
from .normals import SurfaceNormals

__all__ = ["SplineSurface", "BSplineSurface", "NurbsSurface", "BezierSurface"]


def _tensor_combine(coefs, p, q, su, sv, Nu, Nv):
    """``sum_ij Nu[..., i, m] Nv[..., j, m] C[su-p+i, sv-q+j]``.

    ``coefs`` ``(nu, nv, k)``, ``Nu`` ``(a, p + 1, m)``, ``Nv`` ``(b, q + 1, m)``;
    returns ``(a, b, m, k)``. Loops run over the degrees only.
    """
    nu, nv, k = coefs.shape
    flat = coefs.reshape(nu * nv, k)
    out = None
    for i in range(p + 1):
        base = (su - p + i) * nv + (sv - q)
        inner = None
        for j in range(q + 1):
            term = Nv[:, j, :, None] * flat[base + j]  # (b, m, k)
            inner = term if inner is None else inner + term
        term = Nu[:, None, i, :, None] * inner[None]  # (a, b, m, k)
        out = term if out is None else out + term
    return out


class SplineSurface(SurfaceGrids, SurfaceNormals, SurfaceKnotAlgebra):
    """Common implementation of :class:`BSplineSurface` and :class:`NurbsSurface`."""

    __slots__ = ("_pu", "_pv", "_ku", "_kv", "_coefs", "_rational", "_cache")

    @classmethod
    def _trusted(cls, pu, pv, ku, kv, coefs, rational):
        if rational and cls is BSplineSurface:
            cls = NurbsSurface
        finite_points(coefs, "the operation")  # knot algebra near the float limit can overflow
        obj = object.__new__(cls)
        obj._set(int(pu), int(pv), ku, kv, coefs, bool(rational))
        return obj

    def _set(self, pu, pv, ku, kv, coefs, rational):
        for name, value in (
            ("_pu", pu),
            ("_pv", pv),
            ("_ku", frozen(ku)),
            ("_kv", frozen(kv)),
            ("_coefs", frozen(coefs)),
            ("_rational", rational),
            ("_cache", {}),
        ):
            object.__setattr__(self, name, value)

    def _like(self, pu, pv, ku, kv, coefs):
        if self._rational and not (coefs[..., -1] > 0).all():
            raise KnotRemovalError("the result would have non-positive weights")
        return type(self)._trusted(pu, pv, ku, kv, coefs, self._rational)

    def __setattr__(self, name, value):
        raise AttributeError(f"{type(self).__name__} is immutable; operations return new surfaces")

    def __reduce__(self):  # pickling and copy go through the trusted constructor
        args = (type(self), self._pu, self._pv, np.array(self._ku), np.array(self._kv), np.array(self._coefs), self._rational)
        return (_rebuild_surface, args)

    # -- attributes -------------------------------------------------------------------
    degree_u = property(lambda self: self._pu, doc="Degree in u.")
    degree_v = property(lambda self: self._pv, doc="Degree in v.")
    knots_u = property(lambda self: self._ku, doc="Full knot vector in u (read-only).")
    knots_v = property(lambda self: self._kv, doc="Full knot vector in v (read-only).")
    is_rational = property(lambda self: self._rational)

    @property
    def control_points(self) -> np.ndarray:
        """Cartesian control points ``(nu, nv, dim)`` (read-only)."""
        if not self._rational:
            return self._coefs
        if "points" not in self._cache:
            self._cache["points"] = frozen(self._coefs[..., :-1] / self._coefs[..., -1:])
        return self._cache["points"]

    @property
    def weights(self):
        """``(nu, nv)`` weights of a rational surface, else ``None``."""
        return self._coefs[..., -1] if self._rational else None

    @property
    def homogeneous_points(self) -> np.ndarray:
        """``(w * P, w)`` ``(nu, nv, dim + 1)``."""
        if self._rational:
            return self._coefs
        ones = np.ones(self._coefs.shape[:2] + (1,))
        return frozen(np.concatenate([self._coefs, ones], axis=-1))

    @property
    def dim(self) -> int:
        return self._coefs.shape[-1] - self._rational

    @property
    def shape(self) -> tuple[int, int]:
        """Control net size ``(nu, nv)``."""
        return self._coefs.shape[:2]

    @property
    def domain(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """``((u0, u1), (v0, v1))``."""
        return domain(self._pu, self._ku), domain(self._pv, self._kv)

    def __eq__(self, other):
        if not isinstance(other, SplineSurface):
            return NotImplemented
        return (
            (self._rational, self._pu, self._pv) == (other._rational, other._pu, other._pv)
            and self._ku.shape == other._ku.shape
            and self._kv.shape == other._kv.shape
            and self._coefs.shape == other._coefs.shape
            and bool(np.array_equal(self._ku, other._ku))
            and bool(np.array_equal(self._kv, other._kv))
            and bool(np.array_equal(self._coefs, other._coefs))
        )

    def __hash__(self):
        return hash((self._rational, self._pu, self._pv, self._ku.tobytes(), self._kv.tobytes(), self._coefs.tobytes()))

    def almost_equal(self, other, tol: float = 1e-12) -> bool:
        tol = as_positive(tol, "tol", allow_zero=True)
        return (
            isinstance(other, SplineSurface)
            and (self._rational, self._pu, self._pv) == (other._rational, other._pu, other._pv)
            and self._ku.shape == other._ku.shape
            and self._kv.shape == other._kv.shape
            and self._coefs.shape == other._coefs.shape
            and bool(np.allclose(self._ku, other._ku, rtol=0, atol=tol))
            and bool(np.allclose(self._kv, other._kv, rtol=0, atol=tol))
            and bool(np.allclose(self._coefs, other._coefs, rtol=0, atol=tol))
        )

    def __repr__(self):
        (a, b), (c, d) = self.domain
        return (
            f"{type(self).__name__}(degree=({self._pu}, {self._pv}), control_net={self.shape}, dim={self.dim}, "
            f"domain=[{a:g}, {b:g}] x [{c:g}, {d:g}])"
        )

    # -- evaluation -------------------------------------------------------------------
    def _uv(self, u, v):
        (du, dv) = self.domain
        u = as_params(u, du, "u")
        v = as_params(v, dv, "v")
        try:
            u, v = np.broadcast_arrays(u, v)
        except ValueError:
            raise ParameterError(f"u and v must have the same shape, got {u.shape} and {v.shape}") from None
        return u, v

    def evaluate(self, u, v) -> np.ndarray:
        """Points at the pairs ``(u[i], v[i])``: ``u.shape + (dim,)``.

        Always finite (see :meth:`SplineCurve.evaluate <splinekit.curves.bspline.SplineCurve.evaluate>`)."""
        u, v = self._uv(u, v)
        fu, fv = u.ravel(), v.ravel()
        with np.errstate(over="ignore", invalid="ignore"):
            pts = self._points(fu, fv)
        if not np.isfinite(pts).all():
            pts = overflow_safe(self, lambda s: s._points(fu, fv), self.control_points, 0)
        return pts.reshape(u.shape + (self.dim,))

    def _scaled(self, k: int):
        """This surface with its coordinates multiplied by ``2**k`` (exact; weights unchanged)."""
        coefs = np.array(self._coefs)
        coefs[..., : self.dim] = np.ldexp(coefs[..., : self.dim], k)
        obj = object.__new__(type(self))
        obj._set(self._pu, self._pv, self._ku, self._kv, coefs, self._rational)
        return obj

    def _points(self, fu, fv):
        """Points ``(n, dim)`` at checked flat parameters (no overflow handling)."""
        jit = _kernels.load("splinekit.basis._numba_kernels", work=3 * fu.size // 2)  # a surface point: 1.5 curve points
        if jit is not None:
            pts = np.empty((fu.size, self.dim))
            spans = (*span_bounds(self._pu, self._ku), *span_bounds(self._pv, self._kv))
            bases = (self._pu, self._ku, *spans[:2], self._pv, self._kv, *spans[2:])
            k = self._coefs.shape[-1]
            if k == 4 or (k < 4 and not self._rational):
                jit.surface_points4(*bases, self._coefs4(), fu, fv, self.dim, self._rational, pts)
            else:
                jit.surface_points(*bases, self._coefs, fu, fv, self._rational, pts)
            return pts
        su = find_span(self._pu, self._ku, fu)
        sv = find_span(self._pv, self._kv, fv)
        Nu = basis_funs_t(self._pu, self._ku, su, fu)[None]
        Nv = basis_funs_t(self._pv, self._kv, sv, fv)[None]
        pts = _tensor_combine(self._coefs, self._pu, self._pv, su, sv, Nu, Nv)[0, 0]
        if self._rational:
            pts = pts[:, :-1] / pts[:, -1:]
        return pts

    __call__ = evaluate

    def derivatives(self, u, v, order: int = 1) -> np.ndarray:
        """Partial derivatives ``(order + 1, order + 1) + u.shape + (dim,)``.

        Entry ``[k, l]`` is ``d^(k+l) S / du^k dv^l`` (rational: A4.4).
        """
        order = as_order(order)
        u, v = self._uv(u, v)
        fu, fv = u.ravel(), v.ravel()
        with np.errstate(over="ignore", invalid="ignore"):
            ders = self._derivatives(fu, fv, order)
        if not np.isfinite(ders).all():
            ders = overflow_safe(self, lambda s: s._derivatives(fu, fv, order), self.control_points, 2)
        return ders.reshape((order + 1, order + 1) + u.shape + (self.dim,))

    def _derivatives(self, fu, fv, order):
        su = find_span(self._pu, self._ku, fu)
        sv = find_span(self._pv, self._kv, fv)
        Nu = basis_ders_t(self._pu, self._ku, su, fu, order)
        Nv = basis_ders_t(self._pv, self._kv, sv, fv, order)
        ders = _tensor_combine(self._coefs, self._pu, self._pv, su, sv, Nu, Nv)
        if self._rational:
            ders = rational_surface_derivatives(ders)
        return ders

    # -- conversions ------------------------------------------------------------------
    def to_bezier(self):
        """Bézier decomposition: a list (over u spans) of lists (over v spans) of
        :class:`~splinekit.BezierSurface`, each on [0, 1] x [0, 1]."""

        _, su = algebra.bezier_segments(self._pu, self._ku, self._coefs)  # (su, pu+1, nv, k)
        _, sv = algebra.bezier_segments(self._pv, self._kv, su.transpose(2, 0, 1, 3))  # (sv, pv+1, su, pu+1, k)
        patches = sv.transpose(2, 3, 0, 1, 4)  # (su, pu+1, sv, pv+1, k)
        return [
            [BezierSurface._from_coefs(patches[i, :, j], self._rational) for j in range(patches.shape[2])]
            for i in range(patches.shape[0])
        ]

    def to_nurbs(self):
        if self._rational:
            return self
        return NurbsSurface._trusted(self._pu, self._pv, self._ku, self._kv, self.homogeneous_points, True)


class BSplineSurface(SplineSurface):
    """Non-rational tensor-product B-spline surface.

    Parameters
    ----------
    degree_u, degree_v : int
        Degrees ``p, q >= 1``.
    knots_u, knots_v : array_like
        Knot vectors of lengths ``nu + p + 1`` and ``nv + q + 1``.
    control_points : array_like, shape (nu, nv, dim)
    """

    __slots__ = ()

    def __init__(self, degree_u, degree_v, knots_u, knots_v, control_points):
        pu, pv = as_degree(degree_u, "degree_u"), as_degree(degree_v, "degree_v")
        P = as_points(control_points, leading=2, min_count=(pu + 1, pv + 1))
        ku = validate_knots(knots_u, pu, P.shape[0], "knots_u")
        kv = validate_knots(knots_v, pv, P.shape[1], "knots_v")
        self._set(pu, pv, ku, kv, P, False)

    @classmethod
    def uniform(cls, degree_u, degree_v, control_points):
        """Surface on clamped uniform knot vectors over [0, 1] x [0, 1]."""
        pu, pv = as_degree(degree_u, "degree_u"), as_degree(degree_v, "degree_v")
        P = as_points(control_points, leading=2, min_count=(pu + 1, pv + 1))
        return cls(pu, pv, clamped_uniform(pu, P.shape[0]), clamped_uniform(pv, P.shape[1]), P)


class NurbsSurface(BSplineSurface):
    """Rational tensor-product B-spline (NURBS) surface; ``weights`` ``(nu, nv)`` > 0."""

    __slots__ = ()

    def __init__(self, degree_u, degree_v, knots_u, knots_v, control_points, weights):
        pu, pv = as_degree(degree_u, "degree_u"), as_degree(degree_v, "degree_v")
        P = as_points(control_points, leading=2, min_count=(pu + 1, pv + 1))
        ku = validate_knots(knots_u, pu, P.shape[0], "knots_u")
        kv = validate_knots(knots_v, pv, P.shape[1], "knots_v")
        w = as_weights(weights, P.shape[:2])
        self._set(pu, pv, ku, kv, homogeneous(P, w), True)

    @classmethod
    def uniform(cls, degree_u, degree_v, control_points, weights=None):
        pu, pv = as_degree(degree_u, "degree_u"), as_degree(degree_v, "degree_v")
        P = as_points(control_points, leading=2, min_count=(pu + 1, pv + 1))
        w = np.ones(P.shape[:2]) if weights is None else weights
        return cls(pu, pv, clamped_uniform(pu, P.shape[0]), clamped_uniform(pv, P.shape[1]), P, w)



class BezierSurface:
    """(Rational) tensor-product Bézier patch on [0, 1] x [0, 1].

    A patch of degrees ``(m, n)`` is the B-spline surface on Bézier knot
    vectors; this class wraps that surface, so every operation shares its code.

    Parameters
    ----------
    control_points : array_like, shape (m + 1, n + 1, dim)
        At least 2 x 2 points; degrees are ``(m, n)``.
    weights : array_like, shape (m + 1, n + 1), optional
    """

    __slots__ = ("_spline",)

    def __init__(self, control_points, weights=None):
        P = as_points(control_points, leading=2, min_count=(2, 2))
        m, n = P.shape[0] - 1, P.shape[1] - 1
        if weights is None:
            s = BSplineSurface(m, n, bezier_knots(m), bezier_knots(n), P)
        else:
            s = NurbsSurface(m, n, bezier_knots(m), bezier_knots(n), P, as_weights(weights, P.shape[:2]))
        object.__setattr__(self, "_spline", s)

    @classmethod
    def _from_coefs(cls, coefs, rational):
        obj = object.__new__(cls)
        m, n = coefs.shape[0] - 1, coefs.shape[1] - 1
        s = BSplineSurface._trusted(m, n, bezier_knots(m), bezier_knots(n), np.ascontiguousarray(coefs), rational)
        object.__setattr__(obj, "_spline", s)
        return obj

    def __reduce__(self):
        return (type(self)._from_coefs, (np.array(self._spline._coefs), self.is_rational))

    def __setattr__(self, name, value):
        raise AttributeError("BezierSurface is immutable; operations return new surfaces")

    degree_u = property(lambda self: self._spline.degree_u)
    degree_v = property(lambda self: self._spline.degree_v)
    control_points = property(lambda self: self._spline.control_points, doc="``(m + 1, n + 1, dim)`` (read-only).")
    weights = property(lambda self: self._spline.weights)
    dim = property(lambda self: self._spline.dim)
    is_rational = property(lambda self: self._spline.is_rational)
    shape = property(lambda self: self._spline.shape)
    domain = ((0.0, 1.0), (0.0, 1.0))

    def __eq__(self, other):
        if not isinstance(other, BezierSurface):
            return NotImplemented
        return self._spline == other._spline

    def __hash__(self):
        return hash(("bezier", hash(self._spline)))

    def almost_equal(self, other, tol: float = 1e-12) -> bool:
        return isinstance(other, BezierSurface) and self._spline.almost_equal(other._spline, tol)

    def __repr__(self):
        kind = "rational " if self.is_rational else ""
        return f"BezierSurface({kind}degree=({self.degree_u}, {self.degree_v}), dim={self.dim})"

    def evaluate(self, u, v):
        """Points at pairs ``(u, v)``: ``u.shape + (dim,)``."""
        return self._spline.evaluate(u, v)

    __call__ = evaluate

    def evaluate_grid(self, us, vs):
        return self._spline.evaluate_grid(us, vs)

    def derivatives(self, u, v, order: int = 1):
        """``(order + 1, order + 1) + u.shape + (dim,)``; ``[k, l]`` is d^(k+l)S/du^k dv^l."""
        return self._spline.derivatives(u, v, order)

    def normal(self, u, v):
        return self._spline.normal(u, v)

    def split(self, t, direction="u"):
        """Two patches split at ``t`` in one direction, each on [0, 1]^2."""
        a, b = self._spline.split(t, direction)
        return BezierSurface._from_coefs(a._coefs, self.is_rational), BezierSurface._from_coefs(b._coefs, self.is_rational)

    def elevate(self, by: int = 1, direction="u"):
        """The same patch with one degree raised by ``by``."""
        d = as_direction(direction)
        by = _elevation_step(by, self.degree_u if d == 0 else self.degree_v)
        C = self._spline._coefs
        if d == 0:
            C = np.einsum("ij,jk...->ik...", algebra.bezier_elevation_matrix(self.degree_u, by), C)
        else:
            C = np.einsum("ij,kj...->ki...", algebra.bezier_elevation_matrix(self.degree_v, by), C)
        return BezierSurface._from_coefs(C, self.is_rational)

    def transform(self, matrix):
        return BezierSurface._from_coefs(self._spline.transform(matrix)._coefs, self.is_rational)

    @classmethod
    def from_bspline(cls, surface: SplineSurface):
        """The Bézier form of a single-patch spline surface (else use ``surface.to_bezier()``)."""
        if not isinstance(surface, SplineSurface):
            raise ParameterError(f"expected a BSplineSurface or NurbsSurface, got {type(surface).__name__}")
        bu, bv = surface.bezier_breakpoints()
        if bu.size != 2 or bv.size != 2:
            raise ParameterError(
                f"surface has {bu.size - 1} x {bv.size - 1} patches; use surface.to_bezier() for the list"
            )
        return surface.to_bezier()[0][0]

    def to_bspline(self):
        """This patch as a :class:`BSplineSurface` / :class:`NurbsSurface` on [0, 1]^2."""
        return self._spline


def _rebuild_surface(cls, pu, pv, ku, kv, coefs, rational):
    return cls._trusted(pu, pv, ku, kv, coefs, rational)
