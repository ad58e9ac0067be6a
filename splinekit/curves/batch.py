"""Many spline curves evaluated in one batch: point ``i`` is curve ``index[i]`` at ``t[i]``.

A B-rep face has tens of edge uses, each a small curve sampled at tens of parameters; evaluated
one curve at a time, the per-call overhead (checks, span search, the degree loops of the basis)
costs far more than the arithmetic. :class:`CurveBatch` concatenates the curves' knot vectors and
coefficients once, grouped by (degree, rational), and evaluates any mix of (curve, parameter)
pairs with one pass of the same kernels the single-curve path uses
(:func:`~splinekit.basis.bspline.basis_funs_t`, :func:`~splinekit.basis.bspline.basis_ders_t`,
:func:`~splinekit.basis.bspline.combine`): the spans are indices into the concatenation, so
each point reads only its own curve's knots and control points, and the results are those of
``curve.evaluate`` / ``curve.derivatives`` (numpy path) to the last bit.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_order
from ..basis.bspline import basis_ders_t, basis_funs_t, combine
from ..basis.rational import rational_curve_derivatives
from ..errors import DomainError, ParameterError
from ..tolerances import DEFAULT
from .bspline import BezierCurve, SplineCurve

__all__ = ["CurveBatch"]


class _Group:
    """The curves of one (degree, rational) pair, concatenated.

    ``keys`` are the knots as complex numbers ``member + 1j * knot``: sorted lexicographically
    (members in order, each member's knots nondecreasing), so one ``searchsorted`` finds every
    point's span inside its own curve's knots."""

    def __init__(self, degree: int, rational: bool, curves):
        self.degree, self.rational = degree, rational
        knots = [c._knots for c in curves]
        coefs = [c._coefs for c in curves]
        n_knots = np.array([k.size for k in knots])
        self.knot_offset = np.concatenate([[0], np.cumsum(n_knots)[:-1]])
        self.coef_offset = np.concatenate([[0], np.cumsum([len(c) for c in coefs])[:-1]])
        self.knots = np.concatenate(knots)
        self.coefs = np.concatenate(coefs)
        self.keys = np.empty(self.knots.size, dtype=np.complex128)
        self.keys.real = np.repeat(np.arange(len(curves)), n_knots)
        self.keys.imag = self.knots
        # span_bounds of every member at once: its non-empty spans p <= i < n (local indices)
        member = np.repeat(np.arange(len(curves)), n_knots)
        local = np.arange(self.knots.size) - self.knot_offset[member]
        nonempty = np.zeros(self.knots.size, dtype=bool)
        nonempty[:-1] = self.knots[:-1] < self.knots[1:]
        nonempty &= (local >= degree) & (local < (n_knots - degree - 1)[member])
        big = np.iinfo(np.intp).max
        self.span_lo = np.minimum.reduceat(np.where(nonempty, local, big), self.knot_offset)
        self.span_hi = np.maximum.reduceat(np.where(nonempty, local, -1), self.knot_offset)

    def spans(self, member, t):
        """``(global knot span, global coefficient span)`` of each ``t`` on its ``member`` curve."""
        query = np.empty(t.size, dtype=np.complex128)
        query.real, query.imag = member, t
        local = np.searchsorted(self.keys, query, side="right") - 1 - self.knot_offset[member]
        local = np.clip(local, self.span_lo[member], self.span_hi[member])
        return self.knot_offset[member] + local, self.coef_offset[member] + local


class CurveBatch:
    """A fixed list of spline curves of one dimension, evaluated together.

    Parameters
    ----------
    curves : sequence of curves
        B-spline, NURBS or Bézier curves, all of the same dimension ``dim``.

    Attributes
    ----------
    domains : ndarray, shape (n, 2)
        Each curve's parameter domain.
    """

    def __init__(self, curves):
        curves = [c._spline if isinstance(c, BezierCurve) else c for c in curves]
        if not curves:
            raise ParameterError("CurveBatch needs at least one curve")
        bad = next((i for i, c in enumerate(curves) if not isinstance(c, SplineCurve)), None)
        if bad is not None:
            raise ParameterError(f"curves[{bad}] must be a Bézier, B-spline or NURBS curve, got {type(curves[bad]).__name__}")
        dims = {c.dim for c in curves}
        if len(dims) != 1:
            raise ParameterError(f"the curves of a batch must share one dimension, got {sorted(dims)}")
        self.dim = dims.pop()
        self.domains = np.array([c.domain for c in curves], dtype=np.float64)
        kinds = [(c.degree, c.is_rational) for c in curves]
        self._groups = []
        self._group_of = np.empty(len(curves), dtype=np.intp)
        self._member = np.empty(len(curves), dtype=np.intp)
        for g, kind in enumerate(sorted(set(kinds))):
            members = [i for i, k in enumerate(kinds) if k == kind]
            self._group_of[members] = g
            self._member[members] = np.arange(len(members))
            self._groups.append(_Group(kind[0], kind[1], [curves[i] for i in members]))

    def __len__(self) -> int:
        return self.domains.shape[0]

    def _checked(self, index, t):
        """``(index, t)`` as flat arrays, ``t`` clamped onto each curve's domain as
        :func:`splinekit._validate.as_params` does (DomainError beyond its slack)."""
        index = np.asarray(index, dtype=np.intp).ravel()
        t = np.asarray(t, dtype=np.float64).ravel()
        if index.shape != t.shape:
            raise ParameterError(f"index and t must have one entry per point, got {index.shape} and {t.shape}")
        if index.size and (index.min() < 0 or index.max() >= len(self)):
            raise ParameterError(f"curve indices must lie in [0, {len(self)}), got {int(index.min())}..{int(index.max())}")
        a, b = self.domains[index, 0], self.domains[index, 1]
        slack = DEFAULT.param * np.maximum(b - a, 1.0)
        ok = (t >= a - slack) & (t <= b + slack)  # False for NaN
        if not ok.all():
            i = int(np.flatnonzero(~ok)[0])
            raise DomainError(f"t = {float(t[i])!r} lies outside the parameter domain [{a[i]!r}, {b[i]!r}] "
                              f"of curve {int(index[i])}")
        return index, np.clip(t, a, b)

    def evaluate(self, index, t) -> np.ndarray:
        """Points ``(m, dim)``: curve ``index[i]`` at ``t[i]`` (``index``, ``t``: ``(m,)``)."""
        index, t = self._checked(index, t)
        out = np.empty((t.size, self.dim))
        for g, group in enumerate(self._groups):
            rows = np.flatnonzero(self._group_of[index] == g) if len(self._groups) > 1 else slice(None)
            tt = t[rows]
            kspan, cspan = group.spans(self._member[index[rows]], tt)
            with np.errstate(over="ignore", invalid="ignore"):
                pts = combine(group.coefs, group.degree, cspan, basis_funs_t(group.degree, group.knots, kspan, tt))
                out[rows] = pts[:, :-1] / pts[:, -1:] if group.rational else pts
        return out

    def derivatives(self, index, t, order: int = 1) -> np.ndarray:
        """``(order + 1, m, dim)``: ``C, C', ...`` of curve ``index[i]`` at ``t[i]``."""
        order = as_order(order)
        index, t = self._checked(index, t)
        out = np.empty((order + 1, t.size, self.dim))
        for g, group in enumerate(self._groups):
            rows = np.flatnonzero(self._group_of[index] == g) if len(self._groups) > 1 else slice(None)
            tt = t[rows]
            kspan, cspan = group.spans(self._member[index[rows]], tt)
            with np.errstate(over="ignore", invalid="ignore"):
                ders = combine(group.coefs, group.degree, cspan,
                               basis_ders_t(group.degree, group.knots, kspan, tt, order))
                out[:, rows] = rational_curve_derivatives(ders) if group.rational else ders
        return out
