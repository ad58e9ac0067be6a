"""Least-squares fits of a curve to parametrized points with both end points
interpolated (The NURBS Book 9.4.1, A9.7), and the parameter correction that
moves each data parameter toward its closest curve point between refits.

Data ``Q`` is ``(m, k)`` (any number of columns, fitted at once) at sorted
parameters ``t`` ``(m,)`` on a clamped knot vector ``U`` of degree ``p``.
"""

from __future__ import annotations

import numpy as np

from ..basis.bspline import basis_funs_t, combine, find_span
from ..basis.knots import domain
from ..curves import BSplineCurve
from ..errors import FittingError, ParameterError
from ..tolerances import DEFAULT
from ._solve import solve_banded_spd

__all__ = ["least_squares_fixed_ends", "local_basis"]

NEWTON_STEPS = 8
"""Newton iterations per parameter-correction pass (each step is vectorized over all points)."""


def local_basis(t: np.ndarray, p: int, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Knot spans ``(m,)`` and non-zero basis values ``(p + 1, m)`` at parameters inside the domain."""
    span = find_span(p, U, t)
    return span, basis_funs_t(p, U, span, t)


def least_squares_fixed_ends(
    t: np.ndarray, Q: np.ndarray, p: int, U: np.ndarray, what: str = "curve", basis=None
) -> np.ndarray:
    """Control points ``(n, k)`` of the least-squares fit of ``Q (m, k)`` at ``t`` on knots ``U``.

    The first and last control points are the first and last data points
    (``t`` must start and end at the domain ends of the clamped ``U``); the
    others minimise the sum of squared distances ``|C(t[i]) - Q[i]|^2`` over
    the inner points. The banded normal equations are accumulated straight
    from the local basis values (one ``np.bincount`` per band entry, loops over
    the degree only) and solved by banded Cholesky; every column of ``Q`` is
    fitted at once. ``basis`` optionally passes :func:`local_basis` of ``t``.
    """
    n = U.size - p - 1
    m = t.size
    if n > m:
        raise FittingError(f"{n} control points need at least {n} data points, got {m}")
    ctrl = np.empty((n, Q.shape[1]))
    ctrl[0], ctrl[-1] = Q[0], Q[-1]
    if n == 2:
        return ctrl
    span, N = local_basis(t, p, U) if basis is None else basis
    first, N, Qi = span[1:-1] - p, N[:, 1:-1], Q[1:-1]
    # upper band storage of M = N^T N: ab[p + i - j, j] = M[i, j], i <= j
    ab = np.zeros((p + 1, n))
    rhs = np.zeros((n, Q.shape[1]))
    for r in range(p + 1):
        np.add.at(rhs, first + r, N[r][:, None] * Qi)
        for s in range(r, p + 1):
            ab[p - (s - r)] += np.bincount(first + s, N[r] * N[s], minlength=n)
    # move the fixed end control points to the right-hand side: column 0 and column n - 1 of M
    k = np.arange(1, min(p, n - 1) + 1)
    col0 = np.zeros(n)
    col0[k] = ab[p - k, k]
    i = np.arange(max(0, n - 1 - p), n - 1)
    col_last = np.zeros(n)
    col_last[i] = ab[p + i - (n - 1), n - 1]
    rhs_in = rhs[1:-1] - np.outer(col0[1:-1], Q[0]) - np.outer(col_last[1:-1], Q[-1])
    ctrl[1:-1] = solve_banded_spd(np.ascontiguousarray(ab[:, 1:-1]), rhs_in, what)
    return ctrl


def _ends_at_domain(t, p, U, name, knots_name):
    """``t`` checked to start and end at the domain ends of ``U`` (to rounding), with exact ends."""
    a, b = domain(p, U)
    slack = DEFAULT.param * (b - a)
    if abs(t[0] - a) > slack or abs(t[-1] - b) > slack or t[1] <= a or t[-2] >= b:
        raise ParameterError(
            f"{name} must start and end at the domain ends [{a!r}, {b!r}] of {knots_name} (the end points "
            f"are interpolated there), got [{float(t[0])!r}, {float(t[-1])!r}]"
        )
    t = t.copy()
    t[0], t[-1] = a, b
    return t


def _distances(p, ctrl, basis, Q) -> np.ndarray:
    span, N = basis
    return np.linalg.norm(combine(ctrl, p, span, N) - Q, axis=1)


def _correct_parameters(p, U, ctrl, t, Q) -> np.ndarray:
    """Data parameters moved toward the closest curve points (Newton on ``C'(u) . (C(u) - Q) = 0``).

    End parameters stay fixed; a step is kept only where it brings the curve
    point closer, so the distance at the data parameter never grows.
    """
    curve = BSplineCurve(p, U, ctrl)
    a, b = domain(p, U)
    u = t[1:-1].copy()
    q = Q[1:-1]
    best = np.linalg.norm(curve.evaluate(u) - q, axis=1)
    for _ in range(NEWTON_STEPS):
        C, d1, d2 = curve.derivatives(u, 2)
        r = C - q
        f = np.einsum("ij,ij->i", d1, r)
        df = np.einsum("ij,ij->i", d2, r) + np.einsum("ij,ij->i", d1, d1)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(df > 0, f / df, 0.0)
        trial = np.clip(u - step, a, b)
        dist = np.linalg.norm(curve.evaluate(trial) - q, axis=1)
        better = dist < best
        u = np.where(better, trial, u)
        best = np.where(better, dist, best)
    out = t.copy()
    out[1:-1] = u
    return out


def _fit(t, Q, p, U, passes):
    """Least squares plus ``passes`` parameter corrections: ``(ctrl, t, Q, errors)``.

    ``t`` and ``Q`` come back sorted by (corrected) parameter.
    """
    basis = local_basis(t, p, U)
    ctrl = least_squares_fixed_ends(t, Q, p, U, basis=basis)
    for _ in range(passes):
        t_new = _correct_parameters(p, U, ctrl, t, Q)
        order = np.argsort(t_new, kind="stable")
        t_new, Q_new = (
            t_new[order],
            Q[order],
        )  # keep data sorted by parameter for the span bookkeeping
        basis_new = local_basis(t_new, p, U)
        try:
            ctrl_new = least_squares_fixed_ends(t_new, Q_new, p, U, basis=basis_new)
        except FittingError:
            break  # corrected parameters left a span without data: keep the last good fit
        t, Q, ctrl, basis = t_new, Q_new, ctrl_new, basis_new
    return ctrl, t, Q, _distances(p, ctrl, basis, Q)
