"""Tensor-product B-spline and NURBS surfaces as immutable value types.

Control points are ``(nu, nv, dim)``; a rational surface keeps homogeneous
coefficients ``(w * P, w)`` ``(nu, nv, dim + 1)`` internally. Knot operations in
one direction reuse the curve algebra of :mod:`splinekit.basis.algebra` with the
other direction carried along as a trailing axis.
"""

from __future__ import annotations

import numpy as np

from .._validate import (
    as_affine,
    as_degree,
    as_direction,
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
from .. import _kernels, limits
from ..basis import algebra
from ..basis.bspline import basis_ders_t, basis_funs_t, combine, find_span, span_bounds
from ..basis.knots import clamped_uniform, domain, is_clamped, reparametrized, validate_knots
from ..basis.rational import rational_surface_derivatives
from ..errors import DomainError, KnotRemovalError, KnotVectorError, ParameterError
from ..curves.bspline import _elevation_step
from ..tolerances import DEFAULT, geometric_tolerance

__all__ = ["SplineSurface", "BSplineSurface", "NurbsSurface"]


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


class SplineSurface:
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

    def _grid_basis(self, us, vs, order=0):
        """Per direction: ``(span (m,), values (order + 1, p + 1, m))``."""
        (du, dv) = self.domain
        try:  # sizes first: a broadcast view of a huge length costs nothing until it is converted
            mu, mv = np.asarray(us).size, np.asarray(vs).size
        except (ValueError, TypeError):
            mu = mv = 0  # as_params names the problem
        # the grid (and its per-order partials, and one temporary each) and the two basis
        # tables with their parameters, spans and temporaries, before any of it exists
        grid = 16.0 * mu * mv * (self._coefs.shape[-1] + 1) * (order + 1) ** 2
        tables = 64.0 * (mu + mv) * (max(self._pu, self._pv) + 1) * (order + 1)
        limits.check(grid + tables, f"a {mu} x {mv} surface grid")
        us, vs = as_params(us, du, "us").ravel(), as_params(vs, dv, "vs").ravel()
        out = []
        for p, U, x in ((self._pu, self._ku, us), (self._pv, self._kv, vs)):
            span = find_span(p, U, x)
            out.append((span, basis_ders_t(p, U, span, x, order)))
        return out

    @staticmethod
    def _dense(span, vals, n):
        """Scatter local basis values ``(p + 1, m)`` into a dense ``(m, n)`` matrix."""
        p1, m = vals.shape
        dense = np.zeros((m, n))
        rows = np.arange(m)
        for r in range(p1):
            dense[rows, span - p1 + 1 + r] = vals[r]
        return dense

    def _coefs4(self):
        """Coefficients padded with zero columns to 4 (for the 4-lane kernels)."""
        if "coefs4" not in self._cache:
            k = self._coefs.shape[-1]
            pad = np.zeros(self.shape + (max(0, 4 - k),))
            self._cache["coefs4"] = np.ascontiguousarray(np.concatenate([self._coefs, pad], axis=-1))
        return self._cache["coefs4"]

    def _grid_contract(self, su, Nu_vals, sv, Nv_vals, divide):
        """``Nu @ C @ Nv^T`` per coordinate -> ``(mu, mv, k)`` (or ``(mu, mv, dim)``
        divided by the weight when ``divide``), from the banded basis values
        ``Nu_vals`` ``(p + 1, mu)`` and ``Nv_vals`` ``(q + 1, mv)``.

        Compiled path: both contractions in one kernel per grid row. numpy
        path: the u contraction gathers p + 1 rows of the net per grid row
        (small, ``(mu, nv, k)``) and the v contraction is one broadcast matmul.
        The u step avoids BLAS on purpose: BLAS worker threads left spinning
        after a call compete with the kernel's threads on a 2-core machine.
        """
        nu, nv, k = self._coefs.shape
        mu, mv = su.size, sv.size
        jit = _kernels.load("splinekit.basis._numba_kernels", work=mu * mv // 16)  # a grid point: 1/16 of a curve point
        if jit is not None:
            out = np.empty((mu, mv, k - 1 if divide else k))
            Nv_vals = np.ascontiguousarray(Nv_vals)
            if k == 4 or (k < 4 and not divide):
                jit.grid_tensor4(self._coefs4(), su, np.ascontiguousarray(Nu_vals), self._pu, sv, Nv_vals, self._pv,
                                 out.shape[-1], divide, out)
            else:
                R = combine(self._coefs, self._pu, su, Nu_vals)
                jit.grid_rows(R, sv, Nv_vals, self._pv, divide, out)
            return out
        R = combine(self._coefs, self._pu, su, Nu_vals)  # (mu, nv, k)
        out = np.matmul(self._dense(sv, Nv_vals, nv), R)  # broadcast over mu: (mu, mv, k)
        if divide:
            out = out[..., :-1] / out[..., -1:]
        return out

    def evaluate_grid(self, us, vs) -> np.ndarray:
        """Points on the tensor grid ``us x vs``: ``(len(us), len(vs), dim)``.

        Computed as ``Nu @ P @ Nv^T`` with the banded basis matrices of the
        two parameter vectors, never point by point.
        """
        (su, Nu), (sv, Nv) = self._grid_basis(us, vs)
        with np.errstate(over="ignore", invalid="ignore"):
            out = self._grid_contract(su, Nu[0], sv, Nv[0], self._rational)
        if not np.isfinite(out).all():
            out = overflow_safe(self, lambda s: s._grid_contract(su, Nu[0], sv, Nv[0], s._rational), self.control_points, 0)
        return out

    def derivatives_grid(self, us, vs, order: int = 1) -> np.ndarray:
        """Partial derivatives on a grid: ``(order + 1, order + 1, len(us), len(vs), dim)``."""
        order = as_order(order)
        (su, Nu), (sv, Nv) = self._grid_basis(us, vs, order)

        def compute(s):
            ders = np.stack(
                [np.stack([s._grid_contract(su, Nu[a], sv, Nv[b], False) for b in range(order + 1)]) for a in range(order + 1)]
            )
            return rational_surface_derivatives(ders) if s._rational else ders

        with np.errstate(over="ignore", invalid="ignore"):
            ders = compute(self)
        if not np.isfinite(ders).all():
            ders = overflow_safe(self, compute, self.control_points, 2)
        return ders

    @staticmethod
    def _cross(a, b):
        """Row-wise cross product of ``(..., 3)`` arrays (cheaper than np.cross here)."""
        out = np.empty(np.broadcast_shapes(a.shape, b.shape))
        out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
        out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
        out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
        return out

    def _normalize(self, n, Su, Sv, u, v, Suv=None):
        """Unit normals from ``n = Su x Sv`` (any positive multiple of it).

        Where ``Su x Sv`` (nearly) vanishes, at a collapsed edge such as the
        pole of a revolved sphere, the limit direction ``Su x Suv + Suv x Sv``
        is used, oriented like the normal at a point just inside the domain.
        """
        length = np.sqrt(np.einsum("...i,...i->...", n, n))
        size = np.sqrt(np.einsum("...i,...i->...", Su, Su)) + np.sqrt(np.einsum("...i,...i->...", Sv, Sv))
        weak = length <= 1e-10 * size**2
        if weak.any():
            n = n.copy()
            n[weak] = self._limit_normals(u[weak], v[weak])
            length = np.sqrt(np.einsum("...i,...i->...", n, n))
        return np.divide(n, length[..., None], out=np.zeros_like(n), where=length[..., None] > 0)

    def _limit_normals(self, u, v):
        """Normals at degenerate points (``Su x Sv = 0``): see :meth:`_normalize`."""
        d = self.derivatives(u, v, 1)
        Su, Sv, Suv = d[1, 0], d[0, 1], d[1, 1]
        alt = self._cross(Su, Suv) + self._cross(Suv, Sv)
        (a, b), (c, e) = self.domain
        du, dv = 1e-7 * (b - a), 1e-7 * (e - c)
        un = np.where(u + du <= b, u + du, u - du)
        vn = np.where(v + dv <= e, v + dv, v - dv)
        near = self.derivatives(un, vn, 1)
        ref = self._cross(near[1, 0], near[0, 1])
        flip = np.einsum("...i,...i->...", alt, ref) < 0
        alt[flip] *= -1.0
        tiny = np.linalg.norm(alt, axis=-1) <= 1e-14 * (np.linalg.norm(ref, axis=-1) + 1e-300)
        alt[tiny] = ref[tiny]
        return alt

    def _require_3d(self):
        if self.dim != 3:
            raise ParameterError(f"normals need a surface in 3-D space, this one has dim={self.dim}")

    def normal(self, u, v) -> np.ndarray:
        """Unit normals ``(Su x Sv) / |Su x Sv|`` at the pairs ``(u, v)``: ``u.shape + (3,)``."""
        self._require_3d()
        u, v = self._uv(u, v)
        s = self._unit_sized()
        d = s.derivatives(u, v, 1)
        return s._normalize(s._cross(d[1, 0], d[0, 1]), d[1, 0], d[0, 1], u, v)

    def _unit_sized(self):
        """This surface, or for coordinates beyond ``2**300`` a copy scaled by a power of two
        to size about 1: normals do not depend on the scale, and ``Su x Sv`` of a huge
        surface would overflow."""
        big = float(np.abs(self.control_points).max())
        return self if big < 2.0**300 else self._scaled(-int(np.frexp(big)[1]))

    def normal_grid(self, us, vs) -> np.ndarray:
        """Unit normals on the grid ``us x vs``: ``(len(us), len(vs), 3)``.

        Uses only the homogeneous value and first partials; for a rational
        surface ``Su x Sv`` is a positive multiple of
        ``(Au - wu C) x (Av - wv C)``, so no full quotient rule is needed.
        """
        self._require_3d()
        if self._unit_sized() is not self:
            return self._unit_sized().normal_grid(us, vs)
        (su, Nu), (sv, Nv) = self._grid_basis(us, vs, 1)
        jit = _kernels.load("splinekit.basis._numba_kernels", work=su.size * sv.size // 2)  # a grid normal: half a curve point
        if jit is not None:
            out = np.empty((su.size, sv.size, 3))
            weak = np.empty((su.size, sv.size), dtype=np.bool_)
            jit.grid_normals4(self._coefs4(), su, np.ascontiguousarray(Nu), self._pu, sv, np.ascontiguousarray(Nv),
                              self._pv, self._rational, out, weak)
            if weak.any():
                (du, dv) = self.domain
                U, V = np.meshgrid(as_params(us, du, "us").ravel(), as_params(vs, dv, "vs").ravel(), indexing="ij")
                n = self._limit_normals(U[weak], V[weak])
                out[weak] = n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
            return out
        Hu = self._grid_contract(su, Nu[1], sv, Nv[0], False)
        Hv = self._grid_contract(su, Nu[0], sv, Nv[1], False)
        if self._rational:
            H = self._grid_contract(su, Nu[0], sv, Nv[0], False)
            C = H[..., :3] / H[..., 3:]
            Su = Hu[..., :3] - Hu[..., 3:] * C
            Sv = Hv[..., :3] - Hv[..., 3:] * C
        else:
            Su, Sv = Hu, Hv
        (du, dv) = self.domain
        U, V = np.meshgrid(as_params(us, du, "us").ravel(), as_params(vs, dv, "vs").ravel(), indexing="ij", sparse=True)
        U, V = np.broadcast_arrays(U, V)
        return self._normalize(self._cross(Su, Sv), Su, Sv, U, V)

    # -- knot algebra -----------------------------------------------------------------
    def _dir(self, direction):
        d = as_direction(direction)
        if d == 0:
            return d, self._pu, self._ku, self._coefs
        return d, self._pv, self._kv, self._coefs.transpose(1, 0, 2)

    def _rebuild(self, d, p, U, coefs):
        if d == 0:
            return self._like(p, self._pv, U, self._kv, coefs)
        return self._like(self._pu, p, self._ku, U, np.ascontiguousarray(coefs.transpose(1, 0, 2)))

    def _knot_value(self, d, u, name=None):
        """A single parameter of direction ``d``, clamped and snapped like the curves'."""
        name = name or "uv"[d]
        a, b = self.domain[d]
        value = as_params(u, (a, b), name)
        if value.ndim != 0:
            raise ParameterError(f"{name} must be a single number, got an array of shape {value.shape}")
        u = float(value)
        U = self._ku if d == 0 else self._kv
        near = np.abs(U - u) <= DEFAULT.knot * (b - a)
        return float(U[near][0]) if near.any() else u

    def refine(self, knots, direction="u"):
        """Insert every value of ``knots`` in the given direction."""
        d, p, U, C = self._dir(direction)
        extra = as_float_array(knots, "knots", KnotVectorError).ravel()
        if extra.size == 0:
            return self
        extra = np.array([self._knot_value(d, x, "knots") for x in extra])
        tau = np.sort(np.concatenate([U, extra]), kind="stable")
        tau = validate_knots(tau, p, tau.size - p - 1, "refined knots")
        return self._rebuild(d, p, tau, algebra.refine(p, U, C, tau))

    def insert_knot(self, u, times: int = 1, direction="u"):
        """Insert the knot ``u`` ``times`` times in the given direction."""
        times = as_int(times, "times", minimum=0)
        d, p, U, _ = self._dir(direction)
        u = self._knot_value(d, u)
        a, b = self.domain[d]
        have = int(np.count_nonzero(U == u))
        limit = p if a < u < b else p + 1
        if have + times > limit:
            raise KnotVectorError(
                f"inserting knot {u!r} {times} times would give multiplicity {have + times}; at most {limit} allowed"
            )
        return self.refine(np.full(times, u), direction)

    def remove_knot(self, u, times: int = 1, tol: float | None = None, direction="u"):
        """Remove an interior knot, moving the surface at most ``tol``.

        ``tol`` defaults to ``1e-9`` times the control net's size (its
        largest coordinate, at least 1); see :meth:`SplineCurve.remove_knot`.
        """
        times = as_int(times, "times", minimum=1)
        tol = geometric_tolerance(tol, self.control_points)
        d, p, U, C = self._dir(direction)
        u = self._knot_value(d, u)
        a, b = self.domain[d]
        have = int(np.count_nonzero(U == u))
        if not a < u < b or have == 0:
            raise KnotRemovalError(f"{u!r} is not an interior {'uv'[d]} knot of this surface")
        if times > have:
            raise KnotRemovalError(f"knot {u!r} has multiplicity {have}; cannot remove it {times} times")
        tau, coefs, dev = algebra.remove_knots(p, U, C, u, times)
        allowed = tol
        if self._rational:
            w = self._coefs[..., -1]
            allowed = tol * w.min() / (1.0 + np.linalg.norm(self.control_points, axis=-1).max())
        worst = float(np.max(dev))
        if worst > allowed:
            raise KnotRemovalError(
                f"removing {'uv'[d]} knot {u!r} {times} time(s) would move the surface by up to {worst:.3g} "
                f"(coefficient space), more than the tolerance {allowed:.3g}"
            )
        return self._rebuild(d, p, tau, coefs)

    def elevate_degree(self, by: int = 1, direction="u"):
        """Raise the degree in one direction by ``by``; the surface is unchanged."""
        d, p, U, C = self._dir(direction)
        by = _elevation_step(by, p)
        if by == 0:
            return self
        U2, C2 = algebra.elevate(p, U, C, by)
        return self._rebuild(d, p + by, U2, C2)

    def clamp(self):
        """The same surface on clamped knot vectors in both directions."""
        s = self
        for direction in ("u", "v"):
            d, p, U, C = s._dir(direction)
            if not is_clamped(p, U):
                U2, C2 = algebra.clamp(p, U, C)
                s = s._rebuild(d, p, U2, C2)
        return s

    def split(self, u, direction="u"):
        """Two surfaces split at the interior parameter ``u`` of one direction."""
        d, p, U, C = self._dir(direction)
        u = self._knot_value(d, u)
        a, b = self.domain[d]
        if not a < u < b:
            raise DomainError(f"split parameter {u!r} must lie strictly inside ({a!r}, {b!r})")
        (kl, cl), (kr, cr) = algebra.split(p, U, C, u)
        return self._rebuild(d, p, kl, cl), self._rebuild(d, p, kr, cr)

    def bezier_breakpoints(self):
        """``(bu, bv)``: distinct knots of each domain; patch ``[i][j]`` of :meth:`to_bezier`
        covers ``[bu[i], bu[i+1]] x [bv[j], bv[j+1]]``."""
        out = []
        for p, U in ((self._pu, self._ku), (self._pv, self._kv)):
            a, b = domain(p, U)
            out.append(np.unique(U[(U >= a) & (U <= b)]))
        return tuple(out)

    def to_bezier(self):
        """Bézier decomposition: a list (over u spans) of lists (over v spans) of
        :class:`~splinekit.BezierSurface`, each on [0, 1] x [0, 1]."""
        from .bezier import BezierSurface

        _, su = algebra.bezier_segments(self._pu, self._ku, self._coefs)  # (su, pu+1, nv, k)
        _, sv = algebra.bezier_segments(self._pv, self._kv, su.transpose(2, 0, 1, 3))  # (sv, pv+1, su, pu+1, k)
        patches = sv.transpose(2, 3, 0, 1, 4)  # (su, pu+1, sv, pv+1, k)
        return [
            [BezierSurface._from_coefs(patches[i, :, j], self._rational) for j in range(patches.shape[2])]
            for i in range(patches.shape[0])
        ]

    def isocurve(self, u=None, v=None):
        """The curve ``v -> S(u, v)`` (give ``u``) or ``u -> S(u, v)`` (give ``v``)."""
        from ..curves.bspline import BSplineCurve

        if (u is None) == (v is None):
            raise ParameterError("give exactly one of u or v")
        d = 0 if u is not None else 1
        (du, dv) = self.domain
        value = as_params(u if d == 0 else v, du if d == 0 else dv, "u" if d == 0 else "v")
        if value.ndim != 0:
            raise ParameterError("isocurve takes a single parameter value")
        _, p, U, C = self._dir(d)
        flat = value.reshape(1)
        span = find_span(p, U, flat)
        N = basis_funs_t(p, U, span, flat)[:, 0]
        coefs = np.tensordot(N, C[span[0] - p : span[0] + 1], axes=(0, 0))  # (n_other, k)
        po, Uo = (self._pv, self._kv) if d == 0 else (self._pu, self._ku)
        return BSplineCurve._trusted(po, Uo, coefs, self._rational)

    def transpose(self):
        """Swap the roles of u and v (the normal flips)."""
        return self._like(self._pv, self._pu, self._kv, self._ku, np.ascontiguousarray(self._coefs.transpose(1, 0, 2)))

    def reverse(self, direction="u"):
        """Reverse the parameter direction (on the same domain)."""
        d, p, U, C = self._dir(direction)
        U2, C2 = algebra.reverse(p, U, C)
        return self._rebuild(d, p, U2, C2)

    def reparametrize(self, u_range=None, v_range=None):
        """Map the domains affinely onto ``u_range`` / ``v_range`` (``(start, end)`` pairs)."""
        knots = []
        for p, U, rng in ((self._pu, self._ku, u_range), (self._pv, self._kv, v_range)):
            if rng is None:
                knots.append(U)
                continue
            pair = as_float_array(rng, "range", DomainError)
            if pair.shape != (2,):
                raise DomainError(f"a parameter range is a pair (start, end), got {rng!r}")
            knots.append(reparametrized(p, U, pair[0], pair[1]))
        return self._like(self._pu, self._pv, knots[0], knots[1], self._coefs)

    def transform(self, matrix):
        """Apply an affine map (``(dim, dim)`` or ``(dim + 1, dim + 1)``) to the control points."""
        L, t = as_affine(matrix, self.dim)
        with np.errstate(over="ignore", invalid="ignore"):
            P = finite_points(self.control_points @ L.T + t, "the transform")
        if self._rational:
            P = homogeneous(P, self._coefs[..., -1])
        return self._like(self._pu, self._pv, self._ku, self._kv, P)

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



def _rebuild_surface(cls, pu, pv, ku, kv, coefs, rational):
    return cls._trusted(pu, pv, ku, kv, coefs, rational)
