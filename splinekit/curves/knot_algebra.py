"""Knot algebra of spline curves: insertion, refinement, removal, degree
elevation, clamping, splitting, reversal, reparametrization and affine maps.

:class:`CurveKnotAlgebra` is a mixin of :class:`~splinekit.curves.bspline.SplineCurve`;
its methods act on the curve's (homogeneous, if rational) coefficients through
:mod:`splinekit.basis.algebra` and return new curves of the same kind through
``self._like``, so they never name a curve class.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._validate import MAX_DEGREE, as_affine, as_float_array, as_int, as_params, finite_points, homogeneous
from ..basis import algebra
from ..basis.knots import is_clamped, reparametrized, snapped_to_knots, validate_knots
from ..errors import DegreeError, DomainError, KnotRemovalError, KnotVectorError, ParameterError
from ..tolerances import DEFAULT, geometric_tolerance

__all__ = ["CurveKnotAlgebra"]


def _elevation_step(by, degree: int) -> int:
    """``by`` checked so that ``degree + by`` stays within MAX_DEGREE."""
    by = as_int(by, "by", minimum=0)
    if degree + by > MAX_DEGREE:
        raise DegreeError(f"elevating degree {degree} by {by} exceeds the largest supported degree {MAX_DEGREE}")
    return by


class CurveKnotAlgebra:
    """Knot operations shared by every spline curve (a mixin: it needs the
    curve's ``_degree``, ``_knots``, ``_coefs``, ``_rational``, ``domain`` and ``_like``)."""

    __slots__ = ()

    def _knot_value(self, u, name="u"):
        """A single parameter in the domain (clamped within the parameter
        slack), snapped onto an existing knot within the knot tolerance."""
        a, b = self.domain
        value = as_params(u, (a, b), name)
        if value.ndim != 0:
            raise ParameterError(f"{name} must be a single number, got an array of shape {value.shape}")
        return float(snapped_to_knots(self._knots, value, DEFAULT.knot * (b - a)))

    def elevation_matrix(self, by: int = 1):
        """Sparse ``(n_new, n)`` matrix mapping control coefficients onto the
        degree-elevated curve's (see :meth:`elevate_degree`)."""
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
        a, b = self.domain
        extra = snapped_to_knots(self._knots, as_params(extra, (a, b), "knots"), DEFAULT.knot * (b - a))
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

