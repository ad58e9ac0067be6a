"""Curves given by plain numpy functions, with analytic or finite-difference derivatives.

A :class:`ParametricCurve` is a *curve object* for every function of
:mod:`splinekit.diffgeom.curves`.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import as_float_array, as_order, as_params
from ..curves.differential import _require_finite
from ..errors import ParameterError

__all__ = ["ParametricCurve"]

_EPS = np.finfo(np.float64).eps


# ----------------------------------------------------------------------------------------
# ParametricCurve
# ----------------------------------------------------------------------------------------
class ParametricCurve:
    """A curve given by a numpy function ``x(u)``, usable by every function here.

    Parameters
    ----------
    f : callable
        ``f(u)`` with ``u`` a 1-D float array ``(n,)`` returns the points ``(n, dim)``.
        It is only called with parameters inside ``domain``.
    derivatives : callable, optional
        ``derivatives(u, order)`` returns ``(order + 1, n, dim)``: ``x, x', ...,
        x^(order)``. Without it, derivatives up to order 4 are computed numerically
        (see below).
    domain : (float, float)
        Parameter interval ``[a, b]``, ``a < b``.

    Numeric derivatives
    -------------------
    The ``k``-th derivative (``1 <= k <= 4``) is a finite difference on the
    ``2 r + 1`` equally spaced nodes ``u + (j + s) h``, ``j = -r..r``, with
    ``r = 2 + ceil(k / 2)`` (``r = 3, 3, 4, 4``); the shift ``s`` is 0 (a central difference) unless
    that would leave the domain, in which case the stencil is shifted inside it.
    The step is ``h = 0.3 (b - a) eps**(1 / (2 r + 1))``, which balances the
    truncation error ``O(h**(2 r + 1 - k))`` of the (possibly shifted) stencil
    against the rounding error ``O(eps / h**k)``. Measured against analytic
    derivatives (tests): on one turn of a helix over ``[0, 2 pi]`` the
    relative errors are about 3e-13, 1e-10, 3e-9 and 2e-7 for ``k = 1..4``
    (shifted stencils at the ends included); on two turns over ``[0, 4 pi]``
    2e-11, 4e-9, 2e-7 and 7e-6. The step follows the domain's length, so a
    function that oscillates many times over its domain is differentiated less
    accurately (the truncation error grows like the number of oscillations to
    the power ``2 r + 1``); pass analytic derivatives for such functions.
    """

    MAX_NUMERIC_ORDER = 4

    __slots__ = ("_ders", "_dim", "_domain", "_f")

    def __init__(self, f, derivatives=None, domain=(0.0, 1.0)):
        if not callable(f):
            raise ParameterError(f"f must be callable, got {type(f).__name__}")
        if derivatives is not None and not callable(derivatives):
            raise ParameterError(f"derivatives must be callable or None, got {type(derivatives).__name__}")
        dom = as_float_array(domain, "domain")
        if dom.shape != (2,) or not np.isfinite(dom).all() or not dom[0] < dom[1]:
            raise ParameterError(f"domain must be two finite numbers a < b, got {np.asarray(domain).tolist()!r}")
        for name, value in (("_f", f), ("_ders", derivatives), ("_domain", (float(dom[0]), float(dom[1])))):
            object.__setattr__(self, name, value)
        probe = self._call_f(np.array(self._domain))
        object.__setattr__(self, "_dim", probe.shape[1])

    def __setattr__(self, name, value):
        raise AttributeError("ParametricCurve is immutable")

    @property
    def domain(self) -> tuple[float, float]:
        """Parameter interval ``(a, b)``."""
        return self._domain

    @property
    def dim(self) -> int:
        """Number of coordinates of a point."""
        return self._dim

    def __repr__(self):
        kind = "analytic" if self._ders is not None else "numeric"
        a, b = self._domain
        return f"ParametricCurve(dim={self._dim}, domain=[{a:g}, {b:g}], {kind} derivatives)"

    def _call_f(self, flat: np.ndarray) -> np.ndarray:
        out = as_float_array(self._f(flat), "f(u)")
        if out.ndim != 2 or out.shape[0] != flat.size or out.shape[1] < 1:
            raise ParameterError(f"f(u) must return shape ({flat.size}, dim) for u of shape {flat.shape}, got {out.shape}")
        _require_finite(out, flat, "f(u)")
        return out

    def evaluate(self, u) -> np.ndarray:
        """Points ``u.shape + (dim,)``."""
        u = as_params(u, self._domain)
        return self._call_f(u.ravel()).reshape(u.shape + (-1,))

    __call__ = evaluate

    def derivatives(self, u, order: int = 1) -> np.ndarray:
        """``x, x', ..., x^(order)``: ``(order + 1,) + u.shape + (dim,)``."""
        order = as_order(order)
        u = as_params(u, self._domain)
        flat = u.ravel()
        if self._ders is not None:
            out = as_float_array(self._ders(flat, order), "derivatives(u, order)")
            want = (order + 1, flat.size, self._dim)
            if out.shape != want:
                raise ParameterError(f"derivatives(u, {order}) must return shape {want}, got {out.shape}")
            _require_finite(out, flat, "derivatives(u, order)")
        else:
            if order > self.MAX_NUMERIC_ORDER:
                raise ParameterError(
                    f"order = {order}: numeric derivatives are offered up to order {self.MAX_NUMERIC_ORDER}; "
                    "pass analytic derivatives for more"
                )
            out = np.empty((order + 1, flat.size, self._dim))
            out[0] = self._call_f(flat)
            for k in range(1, order + 1):
                out[k] = self._finite_difference(flat, k)
        return out.reshape((order + 1,) + u.shape + (self._dim,))

    def _finite_difference(self, flat: np.ndarray, k: int) -> np.ndarray:
        """The ``k``-th derivative ``(n, dim)`` by the stencil described in the class docstring."""
        a, b = self._domain
        r = 2 + (k + 1) // 2
        h = 0.3 * (b - a) * _EPS ** (1.0 / (2 * r + 1))
        # shift each stencil just enough to keep its nodes inside [a, b]
        shift = np.maximum(0, np.ceil(r - (flat - a) / h)) - np.maximum(0, np.ceil(r - (b - flat) / h))
        shift = shift.astype(np.int64)
        offsets = np.arange(-r, r + 1)
        out = np.empty((flat.size, self._dim))
        for s in np.unique(shift):
            sel = shift == s
            nodes = offsets + s
            w = _difference_weights(nodes, k) / h**k
            x = np.clip(flat[sel, None] + nodes * h, a, b)
            values = self._call_f(x.ravel()).reshape(x.shape + (self._dim,))
            out[sel] = np.einsum("j,njd->nd", w, values)
        return out


def _difference_weights(nodes: np.ndarray, k: int) -> np.ndarray:
    """Weights ``w`` with ``sum_j w_j f(x + nodes_j) = f^(k)(x) + O(h^(len - k))`` for unit spacing:
    the moment conditions ``sum_j w_j nodes_j**m / m! = [m == k]``, ``m < len(nodes)``."""
    m = np.arange(nodes.size)
    V = nodes[None, :].astype(np.float64) ** m[:, None] / np.array([math.factorial(i) for i in m])[:, None]
    rhs = (m == k).astype(np.float64)
    return np.linalg.solve(V, rhs)
