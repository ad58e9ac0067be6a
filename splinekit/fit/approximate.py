"""Least-squares approximation of points by B-spline curves and of grids by
B-spline surfaces, with the end points interpolated (The NURBS Book 9.4.1,
A9.7; 9.4.3 for surfaces), and a tolerance-driven variant that adds knots where
the error is largest. The least-squares solve with fixed ends and the
parameter correction are in :mod:`.least_squares`.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_degree, as_int, as_points, as_real
from ..basis.bspline import find_span
from ..basis.knots import domain, is_clamped
from ..curves import BSplineCurve
from ..errors import ConvergenceError, FittingError, KnotVectorError, ParameterError
from ..surfaces import BSplineSurface
from .interpolate import _knots_for, _map_to
from .least_squares import _ends_at_domain, _fit, least_squares_fixed_ends
from .parametrize import (
    _method_exponent,
    approximation_knots,
    as_control_count,
    as_parameters,
    denormalized,
    grid_parameters,
    normalized,
    parametrize,
)

__all__ = ["approximate_curve", "approximate_surface"]

ROUNDING = 1e-13
"""Errors below this (relative to the half-size of the data) are rounding: they meet any tolerance."""

MAX_CORRECTIONS = 100
"""Most parameter-correction passes accepted (each is a full refit; more never helps)."""

def _split_knots(t, err, p, U, tol, budget) -> np.ndarray:
    """New knots: one per knot span whose worst error exceeds ``tol``, largest errors first.

    A span is split between its two middle data parameters, so both halves
    keep data; spans with fewer than two data points are not split.
    """
    span = find_span(p, U, t)  # non-decreasing, as t is sorted
    starts = np.flatnonzero(np.concatenate([[True], span[1:] != span[:-1]]))
    counts = np.diff(np.concatenate([starts, [t.size]]))
    worst = np.maximum.reduceat(err, starts)
    half = counts // 2
    ok = (worst > tol) & (counts >= 2)
    candidates = np.flatnonzero(ok)
    candidates = candidates[np.argsort(-worst[candidates], kind="stable")][:budget]
    s, h = starts[candidates], half[candidates]
    return np.sort(0.5 * (t[s + h - 1] + t[s + h]))


def approximate_curve(
    points,
    n_control: int | None = None,
    degree: int = 3,
    parametrization: str = "centripetal",
    *,
    tolerance: float | None = None,
    parameters=None,
    knots=None,
    max_control: int | None = None,
    correct_parameters: int = 0,
) -> BSplineCurve:
    """A B-spline curve approximating ``points`` in the least-squares sense (The NURBS Book A9.7).

    The first and last points are interpolated; the other control points
    minimise ``sum_k |C(t_k) - Q_k|^2`` over the inner data points, solved by
    banded Cholesky of the normal equations.

    Parameters
    ----------
    points : array_like, shape (m, dim)
        Data points, any ``dim >= 1``.
    n_control : int, optional
        Number of control points, ``degree + 1 <= n_control <= m``; knots are
        placed by :func:`approximation_knots` (eqs. 9.68-9.69 while
        ``m >= 2 n_control``, else averaged knots of evenly picked parameters,
        which keep the system regular up to ``n_control = m``). With
        ``tolerance`` it is the starting count (default ``degree + 1``, a
        single Bezier span).
    degree : int
        Degree ``p``; needs ``m >= p + 1``.
    parametrization : {"centripetal", "chord", "uniform"}
        Data parameters when ``parameters`` is not given (see :func:`parametrize`).
    tolerance : float, optional
        Maximum allowed error, in the units of the points. Knots are added, one
        per knot span whose worst error exceeds it (splitting the span's data
        in half), and the fit is redone until every error is within the
        tolerance; the count is then lowered again as far as the tolerance
        allows (binary search over knots resampled from the refined spacing
        and over :func:`approximation_knots`). The error of a point is its distance ``|C(t_k) - Q_k|`` to
        the curve point at its data parameter, an upper bound on its distance
        to the curve; ``correct_parameters`` makes the bound tighter. Errors
        within rounding (``1e-13`` times the half-size of the data) count as
        met, so ``tolerance=0`` returns an interpolant when ``max_control``
        allows one control point per point.
    parameters : array_like, shape (m,), optional
        Strictly increasing data parameters; with ``knots`` they must start and
        end at the domain ends.
    knots : array_like, optional
        Clamped knot vector of the result (or the starting knots with ``tolerance``).
    max_control : int, optional
        Largest number of control points the tolerance loop may use (default
        ``m``); :class:`ConvergenceError` if the tolerance is still not met.
    correct_parameters : int
        Number of parameter-correction passes after each fit: every data
        parameter moves to (a local) closest curve point by Newton steps, then
        the fit is redone (The NURBS Book 9.4.1, "parameter correction"); at most 100.

    Returns
    -------
    BSplineCurve with control points ``(n, dim)``.
    """
    Q = as_points(points, "points")
    p = as_degree(degree)
    m = Q.shape[0]
    if m < p + 1:
        raise FittingError(
            f"too few points for the degree: a degree-{p} fit needs at least {p + 1} points, got {m}; lower the degree"
        )
    passes = as_int(correct_parameters, "correct_parameters", minimum=0)
    if passes > MAX_CORRECTIONS:
        raise ParameterError(
            f"correct_parameters = {passes} exceeds {MAX_CORRECTIONS}; parameter correction converges in a few passes"
        )
    tol = None
    if tolerance is not None:
        tol = as_real(tolerance, "tolerance")
        if tol < 0:
            raise ParameterError(f"tolerance must be >= 0, got {tol!r}")
    if n_control is None and knots is None and tol is None:
        raise ParameterError("approximate_curve needs n_control, knots or tolerance")
    n = None
    if n_control is not None:
        n = as_control_count(n_control, "n_control", p)
        if n > m:
            raise FittingError(
                f"n_control = {n} exceeds the number of points {m}; a least-squares fit needs n_control <= m"
            )
    U = None
    if knots is not None:
        n_k = np.asarray(knots).size - p - 1
        if n is not None and n_k != n:
            raise KnotVectorError(
                f"knots give {n_k} control points for degree {p}, but n_control = {n}"
            )
        n = n_k
        if n < p + 1 or n > m:
            raise KnotVectorError(
                f"knots give {n} control points for degree {p}; a fit of {m} points needs between {p + 1} and {m}"
            )
        U = _knots_for(knots, p, n, "knots")
        if not is_clamped(p, U):
            raise KnotVectorError(
                f"knots must be clamped (first and last {p + 1} values equal): the ends are interpolated"
            )
    if parameters is not None:
        t = as_parameters(parameters, m)
        if U is not None:
            t = _ends_at_domain(t, p, U, "parameters", "knots")
    else:
        _method_exponent(parametrization)
        t = parametrize(Q, parametrization)
        if U is not None:
            t = _map_to(t, *domain(p, U))
    if U is None:
        U = approximation_knots(t, p, p + 1 if n is None else n)

    # fit normalized data (affine invariance): no overflow whatever the units
    Q, center, half = normalized(Q)
    if tol is None:
        ctrl, *_ = _fit(t, Q, p, U, passes)
        return BSplineCurve(p, U, denormalized(ctrl, center, half, "fitted curve"))

    limit = (
        m if max_control is None else as_int(max_control, "max_control", minimum=p + 1)
    )
    limit = min(limit, m)
    if U.size - p - 1 > limit:
        raise ParameterError(
            f"max_control = {limit} is below the starting number of control points {U.size - p - 1}"
        )
    # errors within rounding of the normalized data count as meeting the tolerance (tolerance=0 interpolates)
    tol_n = tol / half + ROUNDING
    U, ctrl = _adaptive_fit(t, Q, p, U, tol_n, limit, passes, tol, half)
    return BSplineCurve(p, U, denormalized(ctrl, center, half, "fitted curve"))


def _try_fit(t, Q, p, U, passes):
    try:
        return _fit(t, Q, p, U, passes)
    except FittingError:
        return None


def _adaptive_fit(t, Q, p, U, tol, limit, passes, requested, half):
    """Knots and control points of a fit within ``tol``: refine where the error is, then even out.

    Refinement: each round splits the knot spans whose worst error exceeds
    ``tol`` (at the middle of their data, or at the span middle for spans
    holding a single point). Splitting halves spans, so the result can carry
    up to twice the knots it needs; the knot spacing it found is then
    resampled to fewer knots (binary search on the count) while the
    tolerance still holds.
    """
    fit = _fit(t, Q, p, U, passes)
    while fit[3].max() > tol:
        _, t_fit, Q_fit, err = fit
        count = U.size - p - 1
        refined = None
        if count < limit:
            for new in _candidate_knots(t_fit, err, p, U, tol, limit - count):
                trial = np.sort(np.concatenate([U, new]))
                refined = _try_fit(t_fit, Q_fit, p, trial, passes)
                if refined is not None:
                    U = trial
                    break
        if refined is None:
            # last resort: the full budget on knots that keep the system regular (at limit == m an interpolation)
            trial = approximation_knots(t, p, limit, method="subsample")
            last = _try_fit(t, Q, p, trial, passes)
            if last is None or last[3].max() > tol:
                best = float(
                    err.max() if last is None else min(err.max(), last[3].max())
                )
                raise ConvergenceError(
                    f"approximate_curve could not reach tolerance {requested!r}: max error "
                    f"{best * half!r} with up to {limit} control points (max_control)"
                )
            U, refined = trial, last
        fit = refined
    return _even_out(t, Q, p, U, fit[0], tol, passes)


def _candidate_knots(t, err, p, U, tol, budget):
    """New-knot batches to try in turn: split at data middles, then the worst span only, then span middles."""
    new = _split_knots(t, err, p, U, tol, budget)
    if new.size:
        yield new
        if new.size > 1:
            yield new[np.argsort(-_span_worst(t, err, p, U, new), kind="stable")][:1]
    worst = _span_worst(t, err, p, U, np.unique(U)[:-1])
    lefts = np.unique(U)[:-1]
    rights = np.unique(U)[1:]
    bad = np.flatnonzero(worst > tol)
    bad = bad[np.argsort(-worst[bad], kind="stable")][:budget]
    if bad.size:
        yield np.sort(0.5 * (lefts[bad] + rights[bad]))


def _resampled_knots(U, p, n_new):
    """Clamped knots with ``n_new`` control points whose spacing follows the interior knots of ``U``."""
    br = np.unique(U)
    spans = br.size - 1
    x = np.linspace(0.0, spans, n_new - p + 1)[1:-1]
    inner = np.interp(x, np.arange(spans + 1), br)
    return np.concatenate([np.full(p + 1, br[0]), inner, np.full(p + 1, br[-1])])


def _even_out(t, Q, p, U, ctrl, tol, passes):
    """Fewest control points meeting ``tol`` on knots resampled from ``U`` or placed by eq. 9.69.

    A binary search on the count for each of the two knot families; the
    smaller result wins (``U`` itself if neither does better).
    """
    best_U, best_ctrl = U, ctrl
    n_best = U.size - p - 1
    families = [lambda n: approximation_knots(t, p, n)]
    # with simple interior knots the spacing the refinement found can be resampled
    if np.unique(U).size - 1 == n_best - p:
        families.append(lambda n: _resampled_knots(U, p, n))
    for knots_for in families:
        n_lo, n_hi = p, n_best  # n_lo fails (too few), n_hi meets tol
        while n_hi - n_lo > 1:
            mid = (n_lo + n_hi) // 2
            trial = knots_for(mid)
            fit = _try_fit(t, Q, p, trial, passes)
            if fit is not None and fit[3].max() <= tol:
                n_hi, n_best, best_U, best_ctrl = mid, mid, trial, fit[0]
            else:
                n_lo = mid
    return best_U, best_ctrl


def _span_worst(t, err, p, U, new_knots) -> np.ndarray:
    """Worst error in the knot span that contains each new knot."""
    span = find_span(p, U, t)
    worst = np.zeros(U.size)
    np.maximum.at(worst, span, err)
    return worst[find_span(p, U, new_knots)]


def approximate_surface(
    grid,
    n_control_u: int,
    n_control_v: int,
    degree_u: int = 3,
    degree_v: int = 3,
    parametrization: str = "centripetal",
    *,
    parameters_u=None,
    parameters_v=None,
    knots_u=None,
    knots_v=None,
) -> BSplineSurface:
    """A B-spline surface approximating a grid of points in the least-squares sense (The NURBS Book 9.4.3).

    Parameters
    ----------
    grid : array_like, shape (nu, nv, dim)
        Data points ``Q[k, l]`` at ``(parameters_u[k], parameters_v[l])``.
    n_control_u, n_control_v : int
        Numbers of control points, ``degree + 1 <= n_control <= grid rows`` in each direction.
    degree_u, degree_v : int
    parametrization : {"centripetal", "chord", "uniform"}
        Default parameters, averaged over rows and columns as for interpolation.
    parameters_u, parameters_v : array_like, optional
        Strictly increasing parameters; with knots they must span the knots' domain.
    knots_u, knots_v : array_like, optional
        Clamped knot vectors; default: eqs. 9.68-9.69.

    Returns
    -------
    BSplineSurface with control points ``(n_control_u, n_control_v, dim)``. The
    four corner points are interpolated and the boundary rows are fitted as
    curves. Every row is fitted along u with one factorization, then every
    column of the result along v; for a grid this two-stage fit is the
    tensor-product least-squares solution.
    """
    G = as_points(grid, "grid", leading=2)
    pu, pv = as_degree(degree_u, "degree_u"), as_degree(degree_v, "degree_v")
    nu, nv, dim = G.shape
    specs = []
    for count, p, n_ctrl, given_t, given_U, d in (
        (nu, pu, n_control_u, parameters_u, knots_u, "u"),
        (nv, pv, n_control_v, parameters_v, knots_v, "v"),
    ):
        if count < p + 1:
            raise FittingError(
                f"too few grid points along {d}: degree {p} needs at least {p + 1}, got {count}"
            )
        n = as_control_count(n_ctrl, f"n_control_{d}", p)
        if n > count:
            raise FittingError(
                f"n_control_{d} = {n} exceeds the {count} grid points along {d}"
            )
        U = None
        if given_U is not None:
            U = _knots_for(given_U, p, n, f"knots_{d}")
            if not is_clamped(p, U):
                raise KnotVectorError(
                    f"knots_{d} must be clamped: the boundary is interpolated at the corners"
                )
        specs.append([count, p, n, given_t, U, d])
    if parameters_u is None or parameters_v is None:
        _method_exponent(parametrization)
        auto = grid_parameters(G, parametrization)
    for k, spec in enumerate(specs):
        count, p, n, given_t, U, d = spec
        if given_t is not None:
            t = as_parameters(given_t, count, f"parameters_{d}")
            if U is not None:
                t = _ends_at_domain(t, p, U, f"parameters_{d}", f"knots_{d}")
        else:
            t = auto[k] if U is None else _map_to(auto[k], *domain(p, U))
        if U is None:
            U = approximation_knots(t, p, n)
        spec[3], spec[4] = t, U
    (_, _, n_u, tu, Uu, _), (_, _, n_v, tv, Uv, _) = specs
    Gs, center, half = normalized(G)
    R = least_squares_fixed_ends(tu, Gs.reshape(nu, nv * dim), pu, Uu, "surface (u)")
    R = R.reshape(n_u, nv, dim).transpose(1, 0, 2).reshape(nv, n_u * dim)
    C = least_squares_fixed_ends(tv, R, pv, Uv, "surface (v)")
    C = denormalized(
        C.reshape(n_v, n_u, dim).transpose(1, 0, 2), center, half, "fitted surface"
    )
    return BSplineSurface(pu, pv, Uu, Uv, C)
