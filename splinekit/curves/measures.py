"""Measures of spline curves: arc length and closedness.

:class:`CurveMeasures` is a mixin of :class:`~splinekit.curves.bspline.SplineCurve`.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_positive
from ..tolerances import ARC_LENGTH_RTOL, geometric_tolerance

__all__ = ["CurveMeasures"]

# Gauss-Legendre rule used per knot span (and per sub-interval) for arc length.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


class CurveMeasures:
    """Arc length and closedness of a curve (a mixin: it needs ``domain``,
    ``bezier_breakpoints``, ``evaluate``, ``derivatives`` and ``control_points``)."""

    __slots__ = ()

    def arc_length(self, start=None, end=None, tol: float = ARC_LENGTH_RTOL) -> float:
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

