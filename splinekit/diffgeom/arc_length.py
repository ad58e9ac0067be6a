"""Arc length of curves: lengths between parameters, the parameters at given
lengths, equal-length subdivision and the arc-length parametrization.

Every function takes a *curve object* with ``.derivatives(u, order)`` and
``.domain`` (see :mod:`splinekit.diffgeom.curves`); lengths are in the
curve's length units.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_int, as_params, as_real
from ..curves.differential import _ZERO_DERIVATIVE, _check_curve, _ders, _domain, _dot, _params, _require_regular, _scales
from ..errors import DomainError, ParameterError
from ..tolerances import ARC_LENGTH_RTOL
from .parametric_curve import ParametricCurve

__all__ = [
    "MAX_PARAMETERS",
    "arc_length",
    "arc_length_parameters",
    "equal_arc_length_parameters",
    "reparametrize_by_arc_length",
]

_EPS = np.finfo(np.float64).eps
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


# ----------------------------------------------------------------------------------------
class _ArcLengthTable:
    """Cumulative arc length at the edges of a partition of the domain.

    The domain is cut at the curve's breakpoints (its distinct knots, where the
    speed may be non-smooth), and every span into ``2**level`` equal pieces;
    each piece is integrated with 8-point Gauss-Legendre. ``level`` grows until
    every piece's integral agrees with the sum of its two halves to ``tol``
    times the total length (at most ``2**12`` pieces per span). The length from
    the start to any ``u`` is then the table value at the piece's left edge
    plus one more 8-point rule on the remainder.
    """

    MAX_LEVEL = 12

    def __init__(self, curve, tol: float):
        _check_curve(curve)
        self.curve = curve
        self.a, self.b = _domain(curve)
        breaks = getattr(curve, "bezier_breakpoints", None)
        edges = np.asarray(breaks(), dtype=np.float64) if callable(breaks) else np.array([self.a, self.b])
        edges = edges[(edges >= self.a) & (edges <= self.b)]
        edges = np.unique(np.concatenate([[self.a], edges, [self.b]]))
        previous = self._pieces(edges)
        for _ in range(self.MAX_LEVEL):
            mid = 0.5 * (edges[:-1] + edges[1:])
            finer = np.empty(2 * edges.size - 1)
            finer[0::2], finer[1::2] = edges, mid
            pieces = self._pieces(finer)
            total = float(pieces.sum())
            converged = np.abs(pieces[0::2] + pieces[1::2] - previous).max() <= tol * max(total, 1e-300)
            edges, previous = finer, pieces
            if converged:
                break
        self.edges = edges
        self.cumulative = np.concatenate([[0.0], np.cumsum(previous)])
        self.length = float(self.cumulative[-1])

    def _integral(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Gauss-Legendre (8 points) of the speed over each ``[lo, hi]``."""
        half = 0.5 * (hi - lo)
        x = (0.5 * (lo + hi))[:, None] + half[:, None] * _GL_X
        x = np.clip(x, self.a, self.b)
        d1 = _ders(self.curve, x.ravel(), 1)[1]
        speed = np.sqrt(_dot(d1, d1)).reshape(x.shape)
        return (speed @ _GL_W) * half

    def _pieces(self, edges: np.ndarray) -> np.ndarray:
        return self._integral(edges[:-1], edges[1:])

    def length_at(self, u: np.ndarray) -> np.ndarray:
        """Arc length from the domain start to each ``u`` (1-D, inside the domain)."""
        j = np.clip(np.searchsorted(self.edges, u, side="right") - 1, 0, self.edges.size - 2)
        return self.cumulative[j] + self._integral(self.edges[j], u)

    def parameters_at(self, s: np.ndarray, tol: float) -> np.ndarray:
        """Parameters ``u`` with ``length_at(u) = s`` (1-D, ``0 <= s <= length``).

        Newton's method on ``length_at(u) - s`` inside the piece bracketing
        ``s``, falling back to bisection whenever a Newton step would leave the
        current bracket (or the speed vanishes). Stops when the residual is at
        most ``tol * length`` or the bracket has shrunk to rounding.
        """
        j = np.clip(np.searchsorted(self.cumulative, s, side="right") - 1, 0, self.edges.size - 2)
        lo, hi = self.edges[j].copy(), self.edges[j + 1].copy()
        s_lo, s_hi = self.cumulative[j], self.cumulative[j + 1]
        width = s_hi - s_lo
        frac = np.divide(s - s_lo, width, out=np.full_like(s, 0.5), where=width > 0)
        u = lo + np.clip(frac, 0.0, 1.0) * (hi - lo)
        active = np.arange(s.size)
        goal = tol * max(self.length, 1e-300)
        for _ in range(200):  # bisection alone halves the bracket: 200 steps exhaust a double
            ua, ja = u[active], j[active]
            g = self.cumulative[ja] + self._integral(self.edges[ja], ua) - s[active]
            done = (np.abs(g) <= goal) | (hi[active] - lo[active] <= 4 * _EPS * np.maximum(np.abs(ua), 1.0))
            below = g < 0
            lo[active] = np.where(below, ua, lo[active])
            hi[active] = np.where(below, hi[active], ua)
            d1 = _ders(self.curve, ua, 1)[1]
            speed = np.sqrt(_dot(d1, d1))
            step = np.divide(g, speed, out=np.full_like(g, np.inf), where=speed > 0)
            newton = ua - step
            inside = (newton > lo[active]) & (newton < hi[active])
            u[active] = np.where(done, ua, np.where(inside, newton, 0.5 * (lo[active] + hi[active])))
            active = active[~done]
            if active.size == 0:
                break
        return u


def _tolerance(tol) -> float:
    tol = as_real(tol, "tol")
    if not tol > 0:
        raise ParameterError(f"tol must be > 0, got {tol!r}")
    return tol


def arc_length(curve, u0=None, u1=None, tol: float = ARC_LENGTH_RTOL):
    """Arc length between parameters ``u0`` and ``u1`` (default: the domain ends).

    ``u0`` and ``u1`` broadcast against each other; the result has their
    broadcast shape (a float for scalars) and is negative where ``u1 < u0``.
    Accurate to about ``tol`` relative to the curve's total length (see
    :class:`_ArcLengthTable`); agrees with ``curve.arc_length`` of splinekit curves.
    """
    table = _ArcLengthTable(curve, _tolerance(tol))
    a, b = table.a, table.b
    s = as_params(a if u0 is None else _params(u0, "u0"), (a, b), "u0")
    e = as_params(b if u1 is None else _params(u1, "u1"), (a, b), "u1")
    s, e = np.broadcast_arrays(s, e)
    out = table.length_at(e.ravel()) - table.length_at(s.ravel())
    # identical end points give exactly zero, not a difference of two roundings
    out[e.ravel() == s.ravel()] = 0.0
    out = out.reshape(s.shape)
    return float(out) if out.ndim == 0 else out


def arc_length_parameters(curve, s, tol: float = ARC_LENGTH_RTOL) -> np.ndarray:
    """Parameters ``s.shape`` at which the arc length from the domain start equals ``s``.

    ``s`` must lie in ``[0, L]`` (``L`` the total length; values within
    ``1e-10 L`` outside are clamped). The lengths at the returned parameters
    match ``s`` to about ``tol * L``. Where the curve stands still over an
    interval (zero speed), any parameter of that interval may be returned.
    """
    tol = _tolerance(tol)
    table = _ArcLengthTable(curve, tol)
    s = as_params(_params(s, "s"), (0.0, table.length), "s")
    return table.parameters_at(s.ravel(), tol).reshape(s.shape)


MAX_PARAMETERS = 10**7
"""Most parameters :func:`equal_arc_length_parameters` returns (each costs a Newton solve)."""


def equal_arc_length_parameters(curve, n: int, tol: float = ARC_LENGTH_RTOL) -> np.ndarray:
    """``n >= 2`` parameters ``(n,)`` cutting the curve into ``n - 1`` pieces of equal length,
    starting and ending at the domain ends; ``n <= 10**7``."""
    n = as_int(n, "n", minimum=2)
    if n > MAX_PARAMETERS:
        raise ParameterError(f"n = {n} exceeds the largest supported count {MAX_PARAMETERS}")
    table = _ArcLengthTable(curve, _tolerance(tol))
    u = table.parameters_at(np.linspace(0.0, table.length, n), tol)
    u[0], u[-1] = table.a, table.b
    return u


def reparametrize_by_arc_length(curve, tol: float = ARC_LENGTH_RTOL) -> ParametricCurve:
    """The same curve parametrized by arc length, as a :class:`ParametricCurve` on ``[0, L]``.

    Evaluation inverts the arc-length table (:func:`arc_length_parameters`,
    accurate to ``tol * L`` in the parameter's length); derivatives up to
    order 3 follow from the curve's own by the chain rule, with
    ``du/ds = 1 / |C'|``: the first derivative is the unit tangent and the
    second the curvature vector. Derivatives raise :class:`DomainError` where
    ``C'`` vanishes.
    """
    tol = _tolerance(tol)
    table = _ArcLengthTable(curve, tol)
    if not table.length > 0:
        raise DomainError("the curve has zero length; it has no arc-length parametrization")
    size, length = _scales(curve)

    def points(s):
        return _ders(curve, table.parameters_at(s, tol), 0)[0]

    def derivatives(s, order):
        if order > 3:
            raise ParameterError(f"order = {order}: an arc-length parametrization offers derivatives up to order 3")
        u = table.parameters_at(s, tol)
        d = _ders(curve, u, max(order, 1))
        out = np.empty((order + 1,) + d.shape[1:])
        out[0] = d[0]
        if order == 0:
            return out
        sigma = np.sqrt(_dot(d[1], d[1]))
        _require_regular(sigma > _ZERO_DERIVATIVE * size / length, u, "the arc-length derivative")
        u1 = 1.0 / sigma  # du/ds
        out[1] = d[1] * u1[:, None]
        if order >= 2:
            sigma_u = _dot(d[1], d[2]) / sigma  # d|C'|/du
            u2 = -sigma_u / sigma**3  # d2u/ds2
            out[2] = d[2] * (u1**2)[:, None] + d[1] * u2[:, None]
        if order >= 3:
            sigma_uu = (_dot(d[2], d[2]) + _dot(d[1], d[3]) - sigma_u**2) / sigma
            u3 = u1 * (-sigma_uu / sigma**3 + 3 * sigma_u**2 / sigma**4)
            out[3] = d[3] * (u1**3)[:, None] + 3 * d[2] * (u1 * u2)[:, None] + d[1] * u3[:, None]
        return out

    return ParametricCurve(points, derivatives, domain=(0.0, table.length))
