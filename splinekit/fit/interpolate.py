"""Global interpolation of points by B-spline curves and grids by B-spline surfaces
(The NURBS Book, 9.2.1, 9.2.2 and 9.2.5).

Control points solve a banded system whose rows are basis functions evaluated
at the data parameters (and, for end derivatives, their first derivatives).
Points may have any number of coordinates: a grid is interpolated as a batch of
curves sharing one factorization.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._validate import as_degree, as_float_array, as_params, as_points
from ..basis.bspline import design_matrix
from ..basis.knots import domain, validate_knots
from ..curves import BSplineCurve
from ..errors import ControlPointError, FittingError, KnotVectorError
from ..surfaces import BSplineSurface
from ._solve import solve_banded_square
from .parametrize import (
    _method_exponent,
    as_parameters,
    averaged_knots,
    denormalized,
    grid_parameters,
    normalized,
    parametrize,
)

__all__ = ["interpolate_curve", "interpolate_surface"]

SCHOENBERG_WHITNEY = 1e-12
"""A data parameter whose own basis function is below this value there violates
(numerically) the Schoenberg-Whitney condition: the system would be singular."""


def _as_derivative(value, dim: int, name: str) -> np.ndarray | None:
    if value is None:
        return None
    d = as_float_array(value, name, ControlPointError)
    if d.shape != (dim,):
        raise ControlPointError(
            f"{name} must have shape ({dim},) like a data point, got {d.shape}"
        )
    if not np.isfinite(d).all():
        raise ControlPointError(f"{name} = {d.tolist()} is not finite")
    return d


def _check_count(m: int, p: int, extra: int, what: str = "points") -> None:
    if m < 2:
        raise FittingError(f"interpolation needs at least 2 {what}, got {m}")
    if m + extra < p + 1:
        needed = p + 1 - extra
        with_d = f" with {extra} end derivative(s)" if extra else ""
        raise FittingError(
            f"too few {what} for the degree: interpolating {m} {what}{with_d} by degree {p} needs at least "
            f"{needed} {what}; lower the degree to at most {m + extra - 1}"
        )


def _knots_for(knots, p: int, n: int, name: str) -> np.ndarray:
    U = as_float_array(knots, name, KnotVectorError)
    if U.ndim != 1 or U.size != n + p + 1:
        raise KnotVectorError(
            f"{name} must have shape ({n + p + 1},): the fit has {n} control points and degree {p}, "
            f"so it needs {n} + {p} + 1 knots; got shape {U.shape}"
        )
    return validate_knots(U, p, n, name)


def _map_to(t: np.ndarray, a: float, b: float) -> np.ndarray:
    """``t`` in [0, 1] mapped onto [a, b] with exact ends."""
    out = a + (b - a) * t
    out[0], out[-1] = a, b
    return out


def _check_schoenberg_whitney(
    A: sp.csr_matrix, rows: np.ndarray, cols: np.ndarray, t: np.ndarray, U, name: str
):
    """Raise when data parameter ``t[k]`` lies outside the support of its basis function."""
    diag = np.asarray(A[rows, cols]).ravel()
    bad = np.flatnonzero(~(np.abs(diag) > SCHOENBERG_WHITNEY))
    if bad.size:
        k = int(bad[0])
        j = int(cols[k])
        p = U.size - A.shape[1] - 1
        raise FittingError(
            f"{name}[{k}] = {float(t[k])!r} lies outside the support [knots[{j}], knots[{j + p + 1}]] = "
            f"[{float(U[j])!r}, {float(U[j + p + 1])!r}] of basis function {j}; the knots and parameters "
            "violate the Schoenberg-Whitney condition and the interpolation system is singular"
        )


def collocation_system(
    t: np.ndarray,
    p: int,
    U: np.ndarray,
    start: bool,
    end: bool,
    name: str = "parameters",
):
    """The interpolation matrix: rows for each data parameter and the imposed end derivatives.

    Returns ``(A (n, n) csr, point_rows (m,), derivative_rows)``: the row of ``A``
    that holds each data point and the rows of the start/end derivatives
    (``None`` when not imposed), in the A9.2 order ``Q0, D0, Q1, ..., D1, Q_{m-1}``
    that keeps the matrix banded.
    """
    m = t.size
    N = design_matrix(p, U, t)
    point_rows = np.arange(m) + int(start)
    if start or end:
        ends = np.array([t[0], t[-1]])
        D = design_matrix(p, U, ends, order=1)
        order = [N[:1]]
        if start:
            order.append(D[:1])
        order.append(N[1:-1])
        if end:
            order.append(D[1:])
        order.append(N[-1:])
        A = sp.vstack(order).tocsr()
        point_rows[0] = 0
        point_rows[-1] += int(end)
    else:
        A = N
    n = A.shape[0]
    d_start = 1 if start else None
    d_end = n - 2 if end else None
    # the data point in row r sits on the diagonal: its basis function must not vanish there
    _check_schoenberg_whitney(A, point_rows, point_rows, t, U, name)
    return A, point_rows, (d_start, d_end)


def interpolate_curve(
    points,
    degree: int = 3,
    parametrization: str = "centripetal",
    *,
    parameters=None,
    knots=None,
    start_tangent=None,
    end_tangent=None,
) -> BSplineCurve:
    """The B-spline curve of ``degree`` through every point (The NURBS Book A9.1, A9.2).

    Parameters
    ----------
    points : array_like, shape (m, dim)
        Data points, any ``dim >= 1`` (a flattened control net works too).
    degree : int
        Degree ``p``; needs ``m + k >= p + 1`` where ``k`` is the number of end
        derivatives given (the degree is never lowered silently).
    parametrization : {"centripetal", "chord", "uniform"}
        How data parameters are chosen when ``parameters`` is not given.
    parameters : array_like, shape (m,), optional
        Strictly increasing data parameters; the curve satisfies ``C(parameters[k]) = points[k]``.
        Default: :func:`parametrize` on [0, 1], or mapped onto the domain of ``knots``.
    knots : array_like, shape (m + k + p + 1,), optional
        Knot vector of the result. Default: :func:`averaged_knots` of the
        parameters (clamped, domain ``[parameters[0], parameters[-1]]``).
        Knots violating the Schoenberg-Whitney condition raise :class:`FittingError`.
    start_tangent, end_tangent : array_like, shape (dim,), optional
        First-derivative vectors ``C'(parameters[0])`` and ``C'(parameters[-1])``
        with respect to the curve parameter (their length matters: on the default
        domain [0, 1] a natural magnitude is the total chord length).

    Returns
    -------
    BSplineCurve with ``m + k`` control points ``(m + k, dim)``.
    """
    P = as_points(points, "points")
    p = as_degree(degree)
    m, dim = P.shape
    d0 = _as_derivative(start_tangent, dim, "start_tangent")
    d1 = _as_derivative(end_tangent, dim, "end_tangent")
    start, end = d0 is not None, d1 is not None
    extra = int(start) + int(end)
    _check_count(m, p, extra)
    if extra and p == 1:
        raise FittingError(
            "end tangents need degree >= 2: a degree-1 interpolant has no free tangent"
        )
    n = m + extra
    U = None if knots is None else _knots_for(knots, p, n, "knots")
    if parameters is not None:
        t = as_parameters(parameters, m)
        if U is not None:
            t = as_params(t, domain(p, U), "parameters")
    else:
        _method_exponent(parametrization)
        t = parametrize(P, parametrization)
        if U is not None:
            t = _map_to(t, *domain(p, U))
    if U is None:
        U = averaged_knots(t, p, start_derivative=start, end_derivative=end)
    A, point_rows, (r0, r1) = collocation_system(t, p, U, start, end)
    # solve on normalized data (affine invariance); derivatives only scale
    Ps, center, half = normalized(P)
    rhs = np.empty((n, dim))
    rhs[point_rows] = Ps
    if start:
        rhs[r0] = d0 / half
    if end:
        rhs[r1] = d1 / half
    ctrl = solve_banded_square(A, rhs, "curve interpolation")
    return BSplineCurve(p, U, denormalized(ctrl, center, half, "interpolating curve"))


def interpolate_surface(
    grid,
    degree_u: int = 3,
    degree_v: int = 3,
    parametrization: str = "centripetal",
    *,
    parameters_u=None,
    parameters_v=None,
    knots_u=None,
    knots_v=None,
) -> BSplineSurface:
    """The B-spline surface through every point of a grid (The NURBS Book A9.4).

    Parameters
    ----------
    grid : array_like, shape (nu, nv, dim)
        Data points ``Q[k, l]``; the surface satisfies ``S(parameters_u[k], parameters_v[l]) = Q[k, l]``.
    degree_u, degree_v : int
        Degrees; ``nu >= degree_u + 1`` and ``nv >= degree_v + 1``.
    parametrization : {"centripetal", "chord", "uniform"}
        Default parameters: each row (column) parametrized, then averaged (rows
        collapsed to a point are left out).
    parameters_u, parameters_v : array_like, shapes (nu,), (nv,), optional
        Strictly increasing data parameters.
    knots_u, knots_v : array_like, optional
        Knot vectors of lengths ``nu + degree_u + 1`` and ``nv + degree_v + 1``;
        default: averaged knots of the parameters.

    Returns
    -------
    BSplineSurface with control points ``(nu, nv, dim)``. Solved as two batched
    curve interpolations (first along u for every column, then along v).
    """
    G = as_points(grid, "grid", leading=2)
    pu, pv = as_degree(degree_u, "degree_u"), as_degree(degree_v, "degree_v")
    nu, nv, dim = G.shape
    _check_count(nu, pu, 0, "grid rows along u")
    _check_count(nv, pv, 0, "grid columns along v")
    Uu = None if knots_u is None else _knots_for(knots_u, pu, nu, "knots_u")
    Uv = None if knots_v is None else _knots_for(knots_v, pv, nv, "knots_v")
    if parameters_u is None or parameters_v is None:
        _method_exponent(parametrization)
        auto_u, auto_v = grid_parameters(G, parametrization)
    tu = _direction_parameters(
        parameters_u,
        auto_u if parameters_u is None else None,
        nu,
        pu,
        Uu,
        "parameters_u",
    )
    tv = _direction_parameters(
        parameters_v,
        auto_v if parameters_v is None else None,
        nv,
        pv,
        Uv,
        "parameters_v",
    )
    if Uu is None:
        Uu = averaged_knots(tu, pu)
    if Uv is None:
        Uv = averaged_knots(tv, pv)
    Au, _, _ = collocation_system(tu, pu, Uu, False, False, "parameters_u")
    Av, _, _ = collocation_system(tv, pv, Uv, False, False, "parameters_v")
    # along u for every (column, coordinate) at once, then along v; on normalized data
    Gs, center, half = normalized(G)
    R = solve_banded_square(Au, Gs.reshape(nu, nv * dim), "surface interpolation (u)")
    R = R.reshape(nu, nv, dim).transpose(1, 0, 2).reshape(nv, nu * dim)
    C = solve_banded_square(Av, R, "surface interpolation (v)")
    C = denormalized(
        C.reshape(nv, nu, dim).transpose(1, 0, 2), center, half, "interpolating surface"
    )
    return BSplineSurface(pu, pv, Uu, Uv, C)


def _direction_parameters(given, auto, count, p, U, name):
    if given is not None:
        t = as_parameters(given, count, name)
        return t if U is None else as_params(t, domain(p, U), name)
    return auto if U is None else _map_to(auto, *domain(p, U))
