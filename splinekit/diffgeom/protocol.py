"""One surface protocol for every representation, and its adapters.

A *parametric surface* is anything with

* ``domain``: ``((u0, u1), (v0, v1))``;
* ``evaluate(u, v)``: points ``u.shape + (dim,)`` for ``u``, ``v`` of one shape;
* ``derivatives(u, v, order)``: ``(order + 1, order + 1) + u.shape + (dim,)``,
  entry ``[k, l]`` being ``d^(k+l) S / du^k dv^l``.

Spline and Bézier surfaces satisfy it as they are. The adapters here make the
other representations satisfy it: :class:`ParametricSurface` (a numpy function
``x(u, v)``), :class:`ExplicitSurface` (``z = f(x, y)``) and
:class:`SubdivisionPatch` (one face of a Catmull-Clark limit surface).
:class:`ImplicitSurface` (``F(x, y, z) = 0``) is the point-based counterpart:
callable on ``(n, 3)`` points, with ``gradient`` and ``hessian``; it lives in
:mod:`.implicit_surface`, the finite differences in :mod:`.differences`.

Numeric derivatives
-------------------
Where no analytic derivatives are given, they come from central finite
differences of fourth order on a 5 x 5 stencil of steps ``h = step * L``
(``L`` the domain length in that direction, 1 for unbounded domains; default
``step = 1e-3``): the function is sampled up to ``2h`` beyond the point, so it
must be defined (and smooth) in that band around the domain. The truncation
error is ``O(h^4)`` and rounding ``O(eps / h^k)`` for order ``k``: about
``1e-12`` relative for first and ``1e-10`` for second derivatives of a smooth
function whose features are of the size of the domain (tested against closed
forms). Orders above 2 need analytic
derivatives.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from .._validate import as_float_array, as_int, as_real
from ..errors import DomainError, ParameterError, SplineKitError
from ..tolerances import FD_STEP
from .differences import _call_points, numeric_derivatives
from .implicit_surface import ImplicitSurface, _nonzero_norm  # noqa: F401  (diffgeom.curvature and implicit.base import _nonzero_norm from here)

__all__ = [
    "ExplicitSurface",
    "ImplicitSurface",
    "ParametricSurface",
    "SubdivisionPatch",
    "Surface",
    "as_surface",
]

DEFAULT_STEP = FD_STEP
"""Finite-difference step relative to the domain's length in each direction (see above)."""


@runtime_checkable
class Surface(Protocol):
    """What :func:`splinekit.curvature` and the geodesic solvers need."""

    domain: tuple

    def evaluate(self, u, v) -> np.ndarray: ...

    def derivatives(self, u, v, order: int = 1) -> np.ndarray: ...


def as_surface(surface, what: str = "surface"):
    """``surface`` if it follows the parametric :class:`Surface` protocol, else
    a :class:`ParameterError` naming what is missing."""
    missing = [name for name in ("domain", "evaluate", "derivatives") if not hasattr(surface, name)]
    if missing:
        raise ParameterError(
            f"{what} must be a parametric surface (domain, evaluate(u, v), derivatives(u, v, order)); "
            f"{type(surface).__name__} lacks {', '.join(missing)}"
        )
    return surface


def _domain(domain, name="domain"):
    """``((u0, u1), (v0, v1))`` as floats; infinite bounds allowed."""
    try:
        (a, b), (c, d) = domain
        a, b, c, d = (float(x) for x in (a, b, c, d))
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be ((u0, u1), (v0, v1)), got {domain!r}") from None
    if any(np.isnan(x) for x in (a, b, c, d)) or not (a < b and c < d):
        raise ParameterError(f"{name} must have u0 < u1 and v0 < v1, got {domain!r}")
    return (a, b), (c, d)


def _steps(domain, step):
    """Finite-difference steps ``(hu, hv)`` scaled by the domain lengths."""
    (a, b), (c, d) = domain
    lu = b - a if np.isfinite(b - a) else 1.0
    lv = d - c if np.isfinite(d - c) else 1.0
    return step * lu, step * lv


def _uv_arrays(u, v, domain):
    """``u, v`` broadcast to one shape and checked against ``domain``."""
    u = as_float_array(u, "u", DomainError)
    v = as_float_array(v, "v", DomainError)
    try:
        u, v = np.broadcast_arrays(u, v)
    except ValueError:
        raise ParameterError(f"u and v must have the same shape, got {u.shape} and {v.shape}") from None
    for name, x, (lo, hi) in (("u", u, domain[0]), ("v", v, domain[1])):
        ok = (x >= lo) & (x <= hi)
        if not ok.all():
            raise DomainError(f"{name} = {float(x[~ok].ravel()[0])!r} lies outside the domain [{lo!r}, {hi!r}]")
    return u, v



class ParametricSurface:
    """A surface given by a numpy function ``x(u, v)``.

    Parameters
    ----------
    f : callable
        ``f(u, v)`` with flat float arrays of length ``n`` returns ``(n, dim)``.
    derivatives : callable, optional
        ``derivatives(u, v, order)`` returns ``(order + 1, order + 1, n, dim)``
        (entry ``[k, l]`` = d^(k+l) x / du^k dv^l). Without it, derivatives up to
        order 2 are computed numerically (module docstring: scheme and accuracy).
    domain : ((u0, u1), (v0, v1)), default the unit square
    step : float
        Relative finite-difference step (ignored with analytic derivatives).
    """

    def __init__(self, f, derivatives=None, domain=((0.0, 1.0), (0.0, 1.0)), step: float = DEFAULT_STEP):
        if not callable(f):
            raise ParameterError(f"f must be callable, got {type(f).__name__}")
        if derivatives is not None and not callable(derivatives):
            raise ParameterError(f"derivatives must be callable or None, got {type(derivatives).__name__}")
        step = as_real(step, "step")
        if not 0 < step < 0.1:
            raise ParameterError(f"step must lie in (0, 0.1), got {step!r}")
        self._f, self._ders, self.domain, self.step = f, derivatives, _domain(domain), step

    def __repr__(self):
        kind = "analytic" if self._ders is not None else "numeric"
        return f"ParametricSurface({getattr(self._f, '__name__', 'f')}, {kind} derivatives, domain={self.domain})"

    def evaluate(self, u, v) -> np.ndarray:
        """Points ``u.shape + (dim,)``."""
        u, v = _uv_arrays(u, v, self.domain)
        out = _call_points(self._f, u.ravel(), v.ravel(), "the surface function")
        return out.reshape(u.shape + out.shape[-1:])

    def derivatives(self, u, v, order: int = 1) -> np.ndarray:
        """Partials ``(order + 1, order + 1) + u.shape + (dim,)``."""
        order = as_int(order, "order", minimum=0)
        u, v = _uv_arrays(u, v, self.domain)
        fu, fv = u.ravel(), v.ravel()
        if self._ders is not None:
            try:
                out = np.asarray(self._ders(fu, fv, order), dtype=np.float64)
            except SplineKitError:
                raise
            except Exception as exc:
                raise ParameterError(f"the derivatives function raised {type(exc).__name__}: {exc}") from exc
            if out.ndim != 4 or out.shape[:3] != (order + 1, order + 1, fu.size):
                raise ParameterError(
                    f"the derivatives function must return shape ({order + 1}, {order + 1}, {fu.size}, dim), got {out.shape}"
                )
            if not np.isfinite(out).all():
                raise DomainError("the derivatives function returned non-finite values")
        else:
            out = numeric_derivatives(self._f, fu, fv, order, *_steps(self.domain, self.step))
        return out.reshape(out.shape[:2] + u.shape + out.shape[-1:])


class ExplicitSurface:
    """The graph ``z = f(x, y)`` as the parametric surface ``(x, y, f(x, y))``.

    Parameters
    ----------
    f : callable
        ``f(x, y)`` on flat arrays returns ``(n,)`` heights.
    gradient, hessian : callable, optional
        ``gradient(x, y)`` -> ``(n, 2)`` (f_x, f_y); ``hessian(x, y)`` ->
        ``(n, 3)`` (f_xx, f_xy, f_yy). Missing ones are computed numerically
        (module docstring).
    domain : ((x0, x1), (y0, y1)), default unbounded

    Its normal ``(-f_x, -f_y, 1) / w`` (``w = sqrt(1 + f_x^2 + f_y^2)``) points
    up, and :meth:`gaussian_curvature` / :meth:`mean_curvature` are the closed
    forms ``(f_xx f_yy - f_xy^2) / w^4`` and
    ``((1 + f_y^2) f_xx - 2 f_x f_y f_xy + (1 + f_x^2) f_yy) / (2 w^3)``.
    """

    def __init__(self, f, gradient=None, hessian=None, domain=((-np.inf, np.inf), (-np.inf, np.inf)), step: float = DEFAULT_STEP):
        for name, g in (("f", f), ("gradient", gradient), ("hessian", hessian)):
            if g is not None and not callable(g):
                raise ParameterError(f"{name} must be callable, got {type(g).__name__}")
        if not callable(f):
            raise ParameterError("f must be callable")
        step = as_real(step, "step")
        if not 0 < step < 0.1:
            raise ParameterError(f"step must lie in (0, 0.1), got {step!r}")
        self._f, self._grad, self._hess, self.domain, self.step = f, gradient, hessian, _domain(domain), step

    def __repr__(self):
        return f"ExplicitSurface({getattr(self._f, '__name__', 'f')}, domain={self.domain})"

    def _height(self, x, y):
        return _call_points(lambda a, b: np.asarray(self._f(a, b), dtype=np.float64).reshape(-1, 1), x, y, "f")

    def height_derivatives(self, x, y) -> np.ndarray:
        """``(6,) + x.shape``: f, f_x, f_y, f_xx, f_xy, f_yy (analytic where given)."""
        x, y = _uv_arrays(x, y, self.domain)
        fx, fy = x.ravel(), y.ravel()
        need_num = self._grad is None or self._hess is None
        num = numeric_derivatives(self._height, fx, fy, 2, *_steps(self.domain, self.step))[..., 0] if need_num else None
        out = np.empty((6, fx.size))
        out[0] = self._height(fx, fy)[:, 0]
        if self._grad is not None:
            out[1:3] = self._user(self._grad, fx, fy, 2, "gradient").T
        else:
            out[1], out[2] = num[1, 0], num[0, 1]
        if self._hess is not None:
            out[3:6] = self._user(self._hess, fx, fy, 3, "hessian").T
        else:
            out[3], out[4], out[5] = num[2, 0], num[1, 1], num[0, 2]
        return out.reshape((6,) + x.shape)

    @staticmethod
    def _user(g, x, y, width, name):
        out = _call_points(lambda a, b: np.asarray(g(a, b), dtype=np.float64).reshape(a.size, -1), x, y, name)
        if out.shape[1] != width:
            raise ParameterError(f"{name}(x, y) must return ({x.size}, {width}), got {out.shape}")
        return out

    def evaluate(self, x, y) -> np.ndarray:
        """Points ``(x, y, f(x, y))``: ``x.shape + (3,)``."""
        x, y = _uv_arrays(x, y, self.domain)
        z = self._height(x.ravel(), y.ravel())[:, 0].reshape(x.shape)
        return np.stack([x, y, z], axis=-1)

    def derivatives(self, x, y, order: int = 1) -> np.ndarray:
        """Partials of ``(x, y, f)``: ``(order + 1, order + 1) + x.shape + (3,)`` (order <= 2
        unless ``f`` is numeric-free, which it is not: orders above 2 are refused)."""
        order = as_int(order, "order", minimum=0)
        if order > 2:
            raise ParameterError(f"ExplicitSurface gives derivatives up to order 2, got {order}")
        x, y = _uv_arrays(x, y, self.domain)
        h = self.height_derivatives(x, y)
        out = np.zeros((order + 1, order + 1) + x.shape + (3,))
        out[0, 0] = np.stack([x, y, h[0]], axis=-1)
        if order >= 1:
            out[1, 0, ..., 0] = 1.0
            out[1, 0, ..., 2] = h[1]
            out[0, 1, ..., 1] = 1.0
            out[0, 1, ..., 2] = h[2]
        if order >= 2:
            out[2, 0, ..., 2] = h[3]
            out[1, 1, ..., 2] = h[4]
            out[0, 2, ..., 2] = h[5]
        return out

    def gaussian_curvature(self, x, y) -> np.ndarray:
        """Closed form ``(f_xx f_yy - f_xy^2) / (1 + f_x^2 + f_y^2)^2``: ``x.shape``."""
        _, fx, fy, fxx, fxy, fyy = self.height_derivatives(x, y)
        return (fxx * fyy - fxy**2) / (1.0 + fx**2 + fy**2) ** 2

    def mean_curvature(self, x, y) -> np.ndarray:
        """Closed form, relative to the upward normal: ``x.shape``."""
        _, fx, fy, fxx, fxy, fyy = self.height_derivatives(x, y)
        w2 = 1.0 + fx**2 + fy**2
        return ((1.0 + fy**2) * fxx - 2.0 * fx * fy * fxy + (1.0 + fx**2) * fyy) / (2.0 * w2**1.5)

    def to_implicit(self) -> ImplicitSurface:
        """The same surface as ``F(x, y, z) = f(x, y) - z = 0`` (negative above
        the graph, so its gradient points down: the opposite side to this
        surface's upward normal)."""

        def F(p):
            return np.asarray(self._f(p[:, 0], p[:, 1]), dtype=np.float64).reshape(-1) - p[:, 2]

        gradient = hessian = None
        if self._grad is not None:

            def gradient(p):
                g = np.asarray(self._grad(p[:, 0], p[:, 1]), dtype=np.float64).reshape(-1, 2)
                return np.column_stack([g, -np.ones(len(p))])

        if self._hess is not None:

            def hessian(p):
                h = np.asarray(self._hess(p[:, 0], p[:, 1]), dtype=np.float64).reshape(-1, 3)
                out = np.zeros((len(p), 3, 3))
                out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = h[:, 0], h[:, 1], h[:, 1], h[:, 2]
                return out

        return ImplicitSurface(F, gradient, hessian)


class SubdivisionPatch:
    """One quad face of a Catmull-Clark limit surface as a parametric surface on
    ``[0, 1]^2`` (the parametrization of ``SubdivisionSurface.evaluate``).

    Points and first derivatives are exact limit values; second derivatives
    are second-order central differences of the exact first derivatives with
    step ``1e-4``, accurate to about ``1e-8`` relative on smooth patches; within
    a step of the face's border the stencil is shifted inside, which costs an
    ``O(1e-4)`` relative error there. Near an extraordinary vertex the
    limit surface's curvature is not bounded, and neither are these values.
    """

    domain = ((0.0, 1.0), (0.0, 1.0))
    _H = 1e-4

    def __init__(self, surface, face: int):
        if not hasattr(surface, "evaluate") or not hasattr(surface, "refinement"):
            raise ParameterError(f"surface must be a SubdivisionSurface, got {type(surface).__name__}")
        self.surface, self.face = surface, as_int(face, "face", minimum=0)
        surface.evaluate([self.face], [0.5], [0.5])  # checks the scheme and the face index now

    def __repr__(self):
        return f"SubdivisionPatch(face={self.face})"

    def _first(self, u, v):
        P, Du, Dv, _ = self.surface.evaluate(np.full(u.size, self.face), u, v)
        return P, Du, Dv

    def evaluate(self, u, v) -> np.ndarray:
        u, v = _uv_arrays(u, v, self.domain)
        P = self._first(u.ravel(), v.ravel())[0]
        return P.reshape(u.shape + P.shape[-1:])

    def derivatives(self, u, v, order: int = 1) -> np.ndarray:
        """``(order + 1, order + 1) + u.shape + (dim,)``, order at most 2."""
        order = as_int(order, "order", minimum=0)
        if order > 2:
            raise ParameterError(f"SubdivisionPatch gives derivatives up to order 2, got {order}")
        u, v = _uv_arrays(u, v, self.domain)
        fu, fv = u.ravel(), v.ravel()
        P, Du, Dv = self._first(fu, fv)
        out = np.zeros((order + 1, order + 1, fu.size, P.shape[-1]))
        out[0, 0] = P
        if order >= 1:
            out[1, 0], out[0, 1] = Du, Dv
        if order >= 2:
            h = self._H
            # centred where the stencil fits in [0, 1], else shifted inside: the
            # difference quotient then estimates the derivative a step away
            # (an O(h) error, 1e-4 relative at the face border)
            cu = np.clip(fu, h, 1.0 - h)
            cv = np.clip(fv, h, 1.0 - h)
            _, Dup, Dvp = self._first(cu + h, fv)
            _, Dum, Dvm = self._first(cu - h, fv)
            out[2, 0] = (Dup - Dum) / (2 * h)
            out[1, 1] = (Dvp - Dvm) / (2 * h)
            _, _, Dvq = self._first(fu, cv + h)
            _, _, Dvr = self._first(fu, cv - h)
            out[0, 2] = (Dvq - Dvr) / (2 * h)
        return out.reshape(out.shape[:2] + u.shape + out.shape[-1:])
