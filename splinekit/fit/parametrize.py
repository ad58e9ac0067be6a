"""Parameters for data points and knot vectors for fitting (The NURBS Book, 9.2.1 and 9.4.1).

All functions here are vectorized over the points; the only loops run over the
degree (window sums) or over nothing at all.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_degree, as_float_array, as_int, as_points
from ..errors import FittingError, ParameterError
from ..tolerances import SAMPLE_COINCIDENCE

__all__ = [
    "METHODS",
    "approximation_knots",
    "averaged_knots",
    "grid_parameters",
    "parametrize",
]

METHODS = ("uniform", "chord", "centripetal")
"""Accepted parametrization names."""

COINCIDENT = SAMPLE_COINCIDENCE
"""Consecutive points closer than this times the size of the point cloud count as coincident."""


def _method_exponent(method) -> float | None:
    """Exponent applied to the chord lengths: None (uniform), 1 (chord) or 1/2 (centripetal)."""
    if method == "uniform":
        return None
    if method in ("chord", "chord_length", "chord-length"):
        return 1.0
    if method == "centripetal":
        return 0.5
    raise ParameterError(f"parametrization must be one of {METHODS}, got {method!r}")


def cloud_size(points: np.ndarray) -> float:
    """Size of a point cloud ``(..., dim)``: the largest coordinate extent (0 for a single point)."""
    flat = points.reshape(-1, points.shape[-1])
    return float(np.ptp(flat, axis=0).max()) if flat.shape[0] else 0.0


def normalized(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """``(points - center) / half``, ``center`` ``(dim,)`` and ``half`` (> 0).

    ``center`` is the middle of the bounding box and ``half`` its largest
    half-extent, so the result lies in ``[-1, 1]``. Fitting is affine
    invariant, so working on normalized data changes nothing but rounding,
    and no squared distance can overflow or underflow, whatever the units.
    Every step halves first, so coordinates near the float limit are safe.
    """
    flat = points.reshape(-1, points.shape[-1])
    lo, hi = flat.min(axis=0), flat.max(axis=0)
    center = lo / 2 + hi / 2
    half = float((hi / 2 - lo / 2).max())
    if not half > 0:
        half = 1.0
    return (points / 2 - center / 2) / (half / 2), center, half


def denormalized(
    points: np.ndarray, center: np.ndarray, half: float, what: str
) -> np.ndarray:
    """Inverse of :func:`normalized`; raises :class:`FittingError` if the result overflows."""
    with np.errstate(over="ignore", invalid="ignore"):
        out = center + points * half
    if not np.isfinite(out).all():
        raise FittingError(
            f"the {what} has control points beyond the floating-point range"
        )
    return out


def parametrize(points, method: str = "centripetal") -> np.ndarray:
    """Parameters in ``[0, 1]`` for the data points ``(m, dim)``: an ``(m,)`` array.

    ``method`` is ``"uniform"`` (equally spaced), ``"chord"`` (proportional to
    the cumulative chord length, eq. 9.5) or ``"centripetal"`` (to the
    cumulative square roots of the chord lengths, eq. 9.6). The first
    parameter is exactly 0 and the last exactly 1.

    Raises :class:`FittingError` for fewer than two points and, for the chord
    and centripetal methods, for two consecutive coincident points (closer than
    ``1e-13`` times the size of the cloud), naming their indices.
    """
    P = as_points(points, "points")
    exponent = _method_exponent(method)
    m = P.shape[0]
    if m < 2:
        raise FittingError(f"parametrize needs at least 2 points, got {m}")
    if exponent is None:
        return np.linspace(0.0, 1.0, m)
    P = normalized(P)[0]
    gaps = np.linalg.norm(np.diff(P, axis=0), axis=1)
    _check_distinct(gaps, cloud_size(P))
    return _cumulative(gaps**exponent)


def _check_distinct(gaps: np.ndarray, size: float) -> None:
    """Raise naming the first pair of consecutive coincident points."""
    bad = np.flatnonzero(~(gaps > COINCIDENT * size))
    if bad.size:
        i = int(bad[0])
        raise FittingError(
            f"points[{i}] and points[{i + 1}] coincide (distance {float(gaps[i]):.3g} times the half-size "
            "of the point cloud); consecutive data points must be distinct"
        )


def _cumulative(steps: np.ndarray) -> np.ndarray:
    """``[0, s0, s0 + s1, ...] / total`` with exact ends 0 and 1."""
    t = np.concatenate([[0.0], np.cumsum(steps)])
    t /= t[-1]
    t[-1] = 1.0
    return t


def grid_parameters(grid, method: str = "centripetal") -> tuple[np.ndarray, np.ndarray]:
    """Parameters ``(nu,)`` and ``(nv,)`` in ``[0, 1]`` for a grid of points ``(nu, nv, dim)``.

    Each row (and column) of the grid is parametrized on its own and the
    results are averaged, as in The NURBS Book A9.3. Rows of zero length (a
    whole row collapsed to one point, as at the pole of a surface of
    revolution) are left out of the average. Raises :class:`FittingError` when
    the averaged parameters do not increase strictly.
    """
    G = normalized(as_points(grid, "grid", leading=2))[0]
    exponent = _method_exponent(method)
    return (
        _averaged_direction(G, exponent, "u"),
        _averaged_direction(G.transpose(1, 0, 2), exponent, "v"),
    )


def _averaged_direction(G: np.ndarray, exponent, name: str) -> np.ndarray:
    """Average over the columns of ``G (n, k, dim)`` of the per-column parameters along axis 0."""
    n = G.shape[0]
    if n < 2:
        raise FittingError(
            f"the grid needs at least 2 points in the {name} direction, got {n}"
        )
    if exponent is None:
        return np.linspace(0.0, 1.0, n)
    steps = np.linalg.norm(np.diff(G, axis=0), axis=2) ** exponent  # (n - 1, k)
    totals = steps.sum(axis=0)
    size = cloud_size(G)
    used = totals > COINCIDENT * size
    if not used.any():
        raise FittingError(
            f"every {name}-row of the grid has zero length; the points do not span the {name} direction"
        )
    t = (
        np.concatenate(
            [np.zeros((1, int(used.sum()))), np.cumsum(steps[:, used], axis=0)]
        )
        / totals[used]
    )
    t = t.mean(axis=1)
    t[0], t[-1] = 0.0, 1.0
    flat = np.flatnonzero(~(np.diff(t) > 0))
    if flat.size:
        i = int(flat[0])
        raise FittingError(
            f"grid rows {i} and {i + 1} coincide along {name} (averaged parameters {t[i]!r}, {t[i + 1]!r}); "
            "rows of a grid must be distinct"
        )
    return t


def as_parameters(parameters, count: int, name: str = "parameters") -> np.ndarray:
    """User-given data parameters: ``(count,)`` finite and strictly increasing."""
    t = as_float_array(parameters, name, ParameterError)
    if t.ndim != 1 or t.size != count:
        raise ParameterError(
            f"{name} must have shape ({count},) (one per data point), got {t.shape}"
        )
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise ParameterError(f"{name}[{bad[0]}] = {float(t[bad[0]])!r} is not finite")
    dec = np.flatnonzero(~(np.diff(t) > 0))
    if dec.size:
        i = int(dec[0])
        raise ParameterError(
            f"{name} must increase strictly, but {name}[{i + 1}] = {float(t[i + 1])!r} <= {name}[{i}] = {float(t[i])!r}"
        )
    return np.ascontiguousarray(t)


def _as_sorted_parameters(parameters) -> np.ndarray:
    """Any-length 1-D strictly increasing finite parameters (at least 2)."""
    t = as_float_array(parameters, "parameters", ParameterError)
    if t.ndim != 1 or t.size < 2:
        raise ParameterError(
            f"parameters must be a 1-D array of at least 2 values, got shape {t.shape}"
        )
    return as_parameters(t, t.size)


def as_control_count(value, name: str, degree: int) -> int:
    """A number of control points: an integer ``>= degree + 1``."""
    n = as_int(value, name, error=FittingError)
    if n < degree + 1:
        raise FittingError(
            f"{name} = {n} is too small: a degree-{degree} spline needs at least degree + 1 = {degree + 1}"
        )
    return n


def _window_means(t: np.ndarray, width: int) -> np.ndarray:
    """Means of every run of ``width`` consecutive values of ``t``."""
    c = np.concatenate([[0.0], np.cumsum(t)])
    # cumulative sums lose a few ulps; subtracting the running start keeps means inside their window
    means = (c[width:] - c[:-width]) / width
    return np.clip(means, t[: t.size - width + 1], t[width - 1 :])


def averaged_knots(
    parameters,
    degree: int,
    *,
    start_derivative: bool = False,
    end_derivative: bool = False,
) -> np.ndarray:
    """Clamped knot vector for interpolation by knot averaging (eq. 9.8).

    ``parameters`` ``(m,)`` strictly increasing; returns ``(m + k + degree + 1,)``
    knots on ``[parameters[0], parameters[-1]]`` where ``k`` is the number of
    end derivatives also imposed. Interior knots are means of ``degree``
    consecutive parameters: of the inner parameters only for plain
    interpolation (eq. 9.8), with the first (last) parameter included when the
    start (end) derivative is imposed (eq. 9.22 for both). Such knots satisfy
    the Schoenberg-Whitney condition, so the interpolation system is regular.
    """
    p = as_degree(degree)
    t = _as_sorted_parameters(parameters)
    extra = int(bool(start_derivative)) + int(bool(end_derivative))
    if extra and p == 1:
        raise FittingError(
            "end derivatives need degree >= 2 (a degree-1 interpolant has no free tangent)"
        )
    if t.size + extra < p + 1:
        raise FittingError(
            f"too few parameters for the degree: {t.size} parameters and {extra} end derivative(s) "
            f"cannot define a degree-{p} spline (needs at least {p + 1} conditions)"
        )
    lo = 0 if start_derivative else 1
    hi = t.size if end_derivative else t.size - 1
    inner_t = t[lo:hi]
    inner = _window_means(inner_t, p) if inner_t.size >= p else np.zeros(0)
    return np.concatenate([np.full(p + 1, t[0]), inner, np.full(p + 1, t[-1])])


def approximation_knots(
    parameters, degree: int, n_control: int, method: str = "auto"
) -> np.ndarray:
    """Clamped knot vector for least squares with ``n_control`` control points.

    ``parameters`` ``(m,)`` strictly increasing with ``degree + 1 <= n_control <= m``;
    returns ``(n_control + degree + 1,)`` knots on ``[parameters[0], parameters[-1]]``.

    ``method``:

    - ``"book"``: eqs. 9.68-9.69: interior knots interpolate the parameters at
      the fractional indices ``j * m / (n_control - degree)``, so every knot
      span holds at least one parameter. Well conditioned while
      ``n_control`` is well below ``m``; as it approaches ``m`` the normal
      equations become nearly singular (condition numbers of 1e11 and more
      measured at ``n_control = 0.8 m``).
    - ``"subsample"``: :func:`averaged_knots` of ``n_control`` parameters
      picked evenly by index (ends included). Those satisfy the
      Schoenberg-Whitney condition, so the least-squares matrix contains a
      regular interpolation matrix and has full rank at any ``n_control <= m``.
    - ``"auto"`` (default): ``"book"`` when ``m >= 2 n_control``, else ``"subsample"``.
    """
    p = as_degree(degree)
    t = _as_sorted_parameters(parameters)
    m = t.size
    n = as_control_count(n_control, "n_control", p)
    if n > m:
        raise FittingError(f"n_control = {n} exceeds the number of data points {m}")
    if method not in ("auto", "book", "subsample"):
        raise ParameterError(
            f"method must be 'auto', 'book' or 'subsample', got {method!r}"
        )
    if method == "auto":
        method = "book" if m >= 2 * n else "subsample"
    if method == "subsample" or n == m:
        picked = np.unique(np.round(np.linspace(0.0, m - 1, n)).astype(np.int64))
        return averaged_knots(t[picked], p)
    d = m / (n - p)
    jd = np.arange(1, n - p) * d
    i = np.floor(jd).astype(np.int64)
    alpha = jd - i
    inner = (1.0 - alpha) * t[i - 1] + alpha * t[i]
    return np.concatenate([np.full(p + 1, t[0]), inner, np.full(p + 1, t[-1])])
