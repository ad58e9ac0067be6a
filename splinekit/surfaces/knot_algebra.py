"""Knot algebra of tensor-product spline surfaces, one direction at a time:
insertion, refinement, removal, degree elevation, clamping, splitting,
isocurves, transposition, reversal, reparametrization and affine maps.

:class:`SurfaceKnotAlgebra` is a mixin of
:class:`~splinekit.surfaces.bspline.SplineSurface`. An operation in ``v`` runs
the curve algebra of :mod:`splinekit.basis.algebra` on the net transposed, with
the other direction carried along as a trailing axis; results are new surfaces
of the same kind built through ``self._like``.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_affine, as_direction, as_float_array, as_int, as_params, finite_points, homogeneous
from ..basis import algebra
from ..basis.bspline import basis_funs_t, find_span
from ..basis.knots import domain, is_clamped, reparametrized, snapped_to_knots, validate_knots
from ..curves import BSplineCurve
from ..curves.knot_algebra import _elevation_step
from ..errors import DomainError, KnotRemovalError, KnotVectorError, ParameterError
from ..tolerances import DEFAULT, geometric_tolerance

__all__ = ["SurfaceKnotAlgebra"]


class SurfaceKnotAlgebra:
    """Knot operations shared by every spline surface (a mixin: it needs the
    surface's degrees, knots, ``_coefs``, ``_rational``, ``domain`` and ``_like``)."""

    __slots__ = ()

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
        return float(snapped_to_knots(self._ku if d == 0 else self._kv, value, DEFAULT.knot * (b - a)))

    def refine(self, knots, direction="u"):
        """Insert every value of ``knots`` in the given direction."""
        d, p, U, C = self._dir(direction)
        extra = as_float_array(knots, "knots", KnotVectorError).ravel()
        if extra.size == 0:
            return self
        a, b = self.domain[d]
        extra = snapped_to_knots(U, as_params(extra, (a, b), "knots"), DEFAULT.knot * (b - a))
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

    def isocurve(self, u=None, v=None):
        """The curve ``v -> S(u, v)`` (give ``u``) or ``u -> S(u, v)`` (give ``v``)."""
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
