"""Evaluation of tensor-product spline surfaces on parameter grids.

:class:`SurfaceGrids` is a mixin of :class:`~splinekit.surfaces.bspline.SplineSurface`:
points and partial derivatives on a grid ``us x vs`` are two banded
contractions ``Nu @ C @ Nv^T``, never a loop over points.
"""

from __future__ import annotations

import numpy as np

from .. import limits
from .._validate import as_order, as_params, overflow_safe
from ..basis.bspline import basis_ders_t, combine, find_span
from .. import _kernels
from ..basis.rational import rational_surface_derivatives

__all__ = ["SurfaceGrids"]


class SurfaceGrids:
    """Grid evaluation (a mixin: it needs the surface's degrees, knots,
    ``_coefs``, ``_rational``, ``_cache``, ``shape`` and ``domain``)."""

    __slots__ = ()

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
