"""Knot vectors: validation, multiplicities and standard constructions.

A knot vector of a degree-``p`` spline with ``n`` control points has
``n + p + 1`` non-decreasing finite values ``U[0..n+p]``; the parameter domain is
``[U[p], U[n]]``. No value may appear more than ``p + 1`` times, and a value
strictly inside the domain no more than ``p`` times (the curve would fall apart).
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, as_real, frozen
from ..errors import DomainError, KnotVectorError

__all__ = [
    "validate_knots",
    "domain",
    "distinct",
    "multiplicity",
    "snapped_to_knots",
    "clamped_uniform",
    "is_clamped",
    "reparametrized",
]


MIN_GAP = 1e-290
"""Smallest positive gap between distinct knots: basis values and derivatives
divide by gaps, and 1 / 1e-290 leaves headroom below the float maximum."""


def validate_knots(knots, degree: int, n_ctrl: int, name: str = "knots") -> np.ndarray:
    """Check a knot vector against its degree and control-point count.

    Returns a read-only float64 copy. Raises :class:`KnotVectorError` naming
    the first offending index.
    """
    U = as_float_array(knots, name, KnotVectorError)
    if U.ndim != 1:
        raise KnotVectorError(f"{name} must be 1-D, got shape {U.shape}")
    expected = n_ctrl + degree + 1
    if U.size != expected:
        raise KnotVectorError(
            f"{name} has {U.size} values; a degree-{degree} spline with {n_ctrl} control "
            f"points needs len(control_points) + degree + 1 = {expected}"
        )
    bad = np.flatnonzero(~np.isfinite(U))
    if bad.size:
        raise KnotVectorError(f"{name}[{bad[0]}] = {float(U[bad[0]])!r} is not finite")
    with np.errstate(over="ignore", invalid="ignore"):
        width = U[-1] - U[0]
        gaps = np.diff(U)
    if not np.isfinite(width):
        raise KnotVectorError(f"{name} spans [{float(U[0])!r}, {float(U[-1])!r}], wider than floating point can represent")
    dec = np.flatnonzero(gaps < 0)
    if dec.size:
        i = dec[0]
        raise KnotVectorError(
            f"{name} must be non-decreasing, but {name}[{i + 1}] = {float(U[i + 1])!r} < {name}[{i}] = {float(U[i])!r}"
        )
    tiny = np.flatnonzero((gaps > 0) & (gaps < MIN_GAP))
    if tiny.size:
        i = tiny[0]
        raise KnotVectorError(
            f"{name}[{i}] = {float(U[i])!r} and {name}[{i + 1}] = {float(U[i + 1])!r} differ by less than "
            f"{MIN_GAP:g}; basis functions divide by knot gaps and would overflow"
        )
    a, b = U[degree], U[n_ctrl]
    if not a < b:
        raise KnotVectorError(
            f"{name} gives an empty domain [{name}[{degree}], {name}[{n_ctrl}]] = [{float(a)!r}, {float(b)!r}]"
        )
    # the distinct knots and their multiplicities, as runs of the (now known sorted) vector
    starts = np.flatnonzero(np.concatenate([[True], gaps != 0]))
    values, counts = U[starts], np.diff(np.append(starts, U.size))
    over = np.flatnonzero(counts > degree + 1)
    if over.size:
        v = float(values[over[0]])
        raise KnotVectorError(
            f"knot {v!r} appears {counts[over[0]]} times in {name}; at most degree + 1 = {degree + 1} allowed"
        )
    inner = (values > a) & (values < b) & (counts > degree)
    if inner.any():
        k = np.flatnonzero(inner)[0]
        raise KnotVectorError(
            f"interior knot {float(values[k])!r} has multiplicity {counts[k]} in {name}; "
            f"at most the degree {degree} keeps the spline connected"
        )
    return frozen(U)


def reparametrized(degree: int, knots: np.ndarray, start, end) -> np.ndarray:
    """``knots`` mapped affinely so that the domain becomes ``[start, end]`` (validated)."""
    start = as_real(start, "start", DomainError)
    end = as_real(end, "end", DomainError)
    if not start < end:
        raise DomainError(f"the new domain needs start < end, got [{start!r}, {end!r}]")
    n = knots.size - degree - 1
    a, b = domain(degree, knots)
    with np.errstate(over="ignore", invalid="ignore"):
        U = start + (knots - a) * ((end - start) / (b - a))
    # exact ends; rounding is monotone, so the mapped vector stays sorted
    U[knots == a] = start
    U[knots == b] = end
    return validate_knots(U, degree, n, "reparametrized knots")


def domain(degree: int, knots: np.ndarray) -> tuple[float, float]:
    """The parameter domain ``(U[p], U[n])``."""
    n = knots.size - degree - 1
    return float(knots[degree]), float(knots[n])


def distinct(knots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct knot values and their multiplicities (OCC's representation)."""
    values, counts = np.unique(knots, return_counts=True)
    return values, counts


def multiplicity(knots: np.ndarray, u: float, tol: float = 0.0) -> int:
    """How many knots lie within ``tol`` of ``u``."""
    return int(np.count_nonzero(np.abs(knots - u) <= tol))


def snapped_to_knots(knots: np.ndarray, u: np.ndarray, tol: float) -> np.ndarray:
    """``u`` (any shape) with every value that lies within ``tol`` of a knot replaced by the first
    such knot of the nondecreasing ``knots``; the others unchanged.

    The knots within ``tol`` of a value are consecutive, so the first is at the search position
    of ``u - tol`` or, where rounding in that subtraction puts the position one place late, just
    before it (the earlier candidate wins)."""
    u = np.asarray(u, dtype=np.float64)
    i = np.searchsorted(knots, u - tol, side="left")
    out = u.copy()
    for j in (np.minimum(i, knots.size - 1), np.maximum(i - 1, 0)):
        near = np.abs(knots[j] - u) <= tol
        out[near] = knots[j][near]
    return out


def is_clamped(degree: int, knots: np.ndarray) -> bool:
    """True when the first and the last ``degree + 1`` knots are equal."""
    return bool(knots[0] == knots[degree] and knots[-1] == knots[-degree - 1])


def clamped_uniform(degree: int, n_ctrl: int, start: float = 0.0, end: float = 1.0) -> np.ndarray:
    """Clamped knot vector with uniformly spaced interior knots on ``[start, end]``.

    Needs ``n_ctrl >= degree + 1``.
    """
    if n_ctrl < degree + 1:
        raise KnotVectorError(f"a degree-{degree} spline needs at least {degree + 1} control points, got {n_ctrl}")
    inner = np.linspace(start, end, n_ctrl - degree + 1)[1:-1]
    return np.concatenate([np.full(degree + 1, start), inner, np.full(degree + 1, end)])
