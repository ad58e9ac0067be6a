"""Bringing curves (and surfaces) onto one degree, domain and knot vector.

Skinning, ruled and Coons surfaces combine the control points of several
curves index by index, which is only meaningful when the curves share their
degree and knot vector. :func:`make_compatible` gets there without changing
any curve's geometry: degree elevation (A5.9), an affine reparametrization
onto a common domain, and knot refinement (A5.4) to the union of the knots.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array
from ..basis import algebra
from ..errors import ParameterError
from ..tolerances import DEFAULT
from ._checks import as_curve

__all__ = ["make_compatible", "merged_knots"]


def merged_knots(knot_vectors, rtol: float = DEFAULT.knot):
    """Union of clamped knot vectors of one degree over one domain.

    Each distinct value appears with the largest multiplicity it has in any
    input. Values closer than ``rtol`` times the domain length are one knot
    (the first of them), so reparametrization round-off does not create
    sliver spans. Returns ``(union, extras, snapped)``: ``snapped[k]`` is
    vector ``k`` with its values moved onto the representatives (see
    :func:`_snap`) and ``extras[k]`` the knots to insert into it.
    """
    values = np.unique(np.concatenate(knot_vectors))
    width = values[-1] - values[0]
    keep = np.concatenate([[True], np.diff(values) > rtol * width])
    reps = values[keep]
    snapped = [_snap(U, reps) for U in knot_vectors]
    counts = np.array([np.searchsorted(U, reps, "right") - np.searchsorted(U, reps, "left") for U in snapped])
    need = counts.max(axis=0)
    union = np.repeat(reps, need)
    extras = [np.repeat(reps, need - c) for c in counts]
    return union, extras, snapped


def _snap(U: np.ndarray, reps: np.ndarray) -> np.ndarray:
    """Each knot of ``U`` replaced by the nearest representative value."""
    idx = np.clip(np.searchsorted(reps, U), 1, reps.size - 1)
    lo, hi = reps[idx - 1], reps[idx]
    return np.where(np.abs(U - lo) <= np.abs(hi - U), lo, hi)


def make_compatible(curves, *, domain=None):
    """Curves with one degree, domain and knot vector, geometry unchanged.

    Parameters
    ----------
    curves : sequence of BSplineCurve / NurbsCurve
        At least one curve; all of the same dimension.
    domain : (start, end), optional
        Common parameter domain; default the first curve's domain.

    Returns a list of curves, in order, each clamped, of the largest input
    degree, on the same domain and the same knot vector (the union of the
    inputs' knots after the affine reparametrization), and all rational
    (:class:`~splinekit.NurbsCurve`) if any input is. Each output traces the
    same points as its input, at affinely mapped parameters.
    """
    try:
        items = list(curves)
    except TypeError:
        raise ParameterError(f"curves must be a sequence of curves, got {type(curves).__name__}") from None
    if not items:
        raise ParameterError("make_compatible needs at least one curve")
    items = [as_curve(c, f"curves[{i}]") for i, c in enumerate(items)]
    dims = [c.dim for c in items]
    if len(set(dims)) != 1:
        k = next(i for i, d in enumerate(dims) if d != dims[0])
        raise ParameterError(f"curves[{k}] has dimension {dims[k]}, curves[0] has {dims[0]}; all must match")
    if domain is None:
        a, b = items[0].domain
    else:
        pair = as_float_array(domain, "domain")
        if pair.shape != (2,) or not np.isfinite(pair).all() or not pair[0] < pair[1]:
            raise ParameterError(f"domain must be a pair (start, end) of finite numbers with start < end, got {domain!r}")
        a, b = float(pair[0]), float(pair[1])
    rational = any(c.is_rational for c in items)
    p = max(c.degree for c in items)
    out = []
    for c in items:
        c = c.clamp()
        if rational:
            c = c.to_nurbs()
        if c.degree < p:
            c = c.elevate_degree(p - c.degree)
        if c.domain != (a, b):
            c = c.reparametrize(a, b)
        out.append(c)
    union, extras, snapped = merged_knots([c.knots for c in out])
    result = []
    for c, extra, U in zip(out, extras, snapped):
        # U: the curve's knots moved onto the shared values (by at most a
        # rounding error, <= 1e-12 of the domain: invisible in the geometry);
        # refinement from U to the union (A5.4) keeps the curve. Calling the
        # algebra directly skips the per-knot lookups of SplineCurve.refine.
        coefs = algebra.refine(p, U, _coefs(c), union) if extra.size else _coefs(c)
        result.append(type(c)._trusted(p, union, coefs, c.is_rational))
    return result


def _coefs(obj) -> np.ndarray:
    """Homogeneous coefficients if rational, Cartesian control points otherwise."""
    return obj.homogeneous_points if obj.is_rational else obj.control_points


def make_surfaces_compatible(surfaces):
    """Surfaces with equal degrees and knot vectors in both directions.

    The surfaces must already share their domains; used to add control nets
    (Boolean sums). Rational if any input is.
    """
    rational = any(s.is_rational for s in surfaces)
    surfs = [s.clamp().to_nurbs() if rational else s.clamp() for s in surfaces]
    for direction, deg in (("u", "degree_u"), ("v", "degree_v")):
        p = max(getattr(s, deg) for s in surfs)
        surfs = [s.elevate_degree(p - getattr(s, deg), direction) if getattr(s, deg) < p else s for s in surfs]
        knots = [s.knots_u if direction == "u" else s.knots_v for s in surfs]
        union, extras, snapped = merged_knots(knots)
        surfs = [_refined_surface(s, direction, U, union) if extra.size else _with_knots(s, direction, union)
                 for s, extra, U in zip(surfs, extras, snapped)]
    return surfs


def _with_knots(s, direction, U, coefs=None):
    """``s`` with its knot vector in ``direction`` replaced (and its coefficients, if given)."""
    ku, kv = (U, s.knots_v) if direction == "u" else (s.knots_u, U)
    coefs = _coefs(s) if coefs is None else coefs
    return type(s)._trusted(s.degree_u, s.degree_v, ku, kv, coefs, s.is_rational)


def _refined_surface(s, direction, U, union):
    """``s`` refined in ``direction`` from its (snapped) knots ``U`` to ``union``."""
    C = _coefs(s)
    if direction == "u":
        return _with_knots(s, "u", union, algebra.refine(s.degree_u, U, C, union))
    Q = algebra.refine(s.degree_v, U, C.transpose(1, 0, 2), union)
    return _with_knots(s, "v", union, np.ascontiguousarray(Q.transpose(1, 0, 2)))
