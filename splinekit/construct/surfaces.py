"""Surface construction: extrusion, ruled, revolved and skinned (lofted) surfaces.

Every function returns a :class:`~splinekit.BSplineSurface`, or a
:class:`~splinekit.NurbsSurface` when a rational input (or a revolution)
needs weights. Control nets are built with whole-array operations on the
(homogeneous) control points of the inputs; no loop runs per control point.

Parameter conventions: for ``extrude``, ``ruled``, ``loft``, ``sweep`` and the
Coons/Gordon patches the input curves run along ``u`` and the construction
goes along ``v``; ``revolve`` follows The NURBS Book A8.1 and OpenCascade's
``Geom_SurfaceOfRevolution``: ``u`` goes around the axis, ``v`` along the
profile.

Sweeps are in :mod:`.sweep`, the patches that fill boundary curves (Coons,
bicubic Coons, Gordon) in :mod:`.patches`; both build on the helpers here.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_degree, as_real
from ..errors import ControlPointError, FittingError, ParameterError, WeightError
from ..fit import interpolate_curve
from ..fit.parametrize import grid_parameters
from ..surfaces import BSplineSurface
from ._checks import as_curve, as_unit, as_vector
from .compat import make_compatible, make_surfaces_compatible
from .curves import TWO_PI, unit_arc

__all__ = ["extrude", "ruled", "revolve", "loft"]


# -- helpers ----------------------------------------------------------------------------
def _coefs(curve) -> np.ndarray:
    """Homogeneous coefficients of a rational curve, Cartesian points otherwise."""
    return curve.homogeneous_points if curve.is_rational else curve.control_points


def _surface(pu, pv, ku, kv, coefs, rational):
    """A surface from (homogeneous if rational) coefficients ``(nu, nv, k)``."""
    if not np.isfinite(coefs).all():
        raise ControlPointError("the construction overflows: the control net is not finite")
    if rational and not (coefs[..., -1] > 0).all():
        i, j = (int(x) for x in np.argwhere(~(coefs[..., -1] > 0))[0])
        raise WeightError(f"the construction gives a non-positive weight at control point [{i}, {j}]")
    return BSplineSurface._trusted(pu, pv, np.asarray(ku, dtype=np.float64), np.asarray(kv, dtype=np.float64),
                                   np.ascontiguousarray(coefs), rational)


def _curves_list(curves, name, minimum):
    try:
        items = list(curves)
    except TypeError:
        raise ParameterError(f"{name} must be a sequence of curves, got {type(curves).__name__}") from None
    if len(items) < minimum:
        raise ParameterError(f"{name} needs at least {minimum} curves, got {len(items)}")
    return [as_curve(c, f"{name}[{i}]") for i, c in enumerate(items)]


def _size(*arrays) -> float:
    """Largest absolute coordinate over the arrays (at least 1): the scale of default tolerances."""
    return max([1.0] + [float(np.abs(a).max()) for a in arrays if np.size(a)])


def _sum_surfaces(terms):
    """``sum(sign * surface)`` over ``(sign, surface)`` pairs sharing their domains."""
    surfs = make_surfaces_compatible([s for _, s in terms])
    coefs = sum(sign * s.homogeneous_points if s.is_rational else sign * s.control_points
                for (sign, _), s in zip(terms, surfs))
    s0 = surfs[0]
    return _surface(s0.degree_u, s0.degree_v, s0.knots_u, s0.knots_v, coefs, s0.is_rational)


# -- extrusion and ruled surfaces -----------------------------------------------------------
def extrude(curve, vector):
    """The curve swept along a straight ``vector``: ``S(u, v) = C(u) + v * vector``.

    ``u`` keeps the curve's parametrization, ``v`` runs over ``[0, 1]`` (degree 1).
    Exact; rational if the curve is.
    """
    curve = as_curve(curve, "curve")
    d = as_vector(vector, "vector", (curve.dim,))
    if not np.any(d):
        raise ParameterError("vector has zero length; an extrusion needs a direction")
    C = _coefs(curve)
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused by _surface, naming it
        shift = np.concatenate([d, [0.0]]) * C[:, -1:] if curve.is_rational else d
        net = np.stack([C, C + shift], axis=1)
    return _surface(curve.degree, 1, curve.knots, [0.0, 0.0, 1.0, 1.0], net, curve.is_rational)


def ruled(c0, c1):
    """Ruled surface ``S(u, v)`` with ``S(u, 0) = c0(u)``, ``S(u, 1) = c1(u)``, straight in ``v``.

    The curves are made compatible first (:func:`make_compatible`; ``u`` runs
    over ``c0``'s domain, ``c1`` is mapped affinely onto it). For rational
    curves the rulings interpolate the homogeneous points, so every line
    ``v -> S(u, v)`` is still the segment from ``c0(u)`` to ``c1(u)``.
    """
    a, b = make_compatible([as_curve(c0, "c0"), as_curve(c1, "c1")])
    net = np.stack([_coefs(a), _coefs(b)], axis=1)
    return _surface(a.degree, 1, a.knots, [0.0, 0.0, 1.0, 1.0], net, a.is_rational)


# -- revolution -------------------------------------------------------------------------------
def revolve(profile, axis_origin, axis_direction, angle=TWO_PI):
    """Surface of revolution of a 3-D ``profile`` about an axis (The NURBS Book A8.1).

    Parameters
    ----------
    profile : BSplineCurve or NurbsCurve, dim 3
    axis_origin, axis_direction : (3,) array_like
        A point of the axis and its (non-zero) direction.
    angle : float
        Radians, ``0 < |angle| <= 2 pi``, counter-clockwise about ``axis_direction``.

    Returns a :class:`~splinekit.NurbsSurface`: ``u`` goes around the axis
    (degree 2 on ``[0, 1]``, ``2 * ceil(|angle| / 90 deg) + 1`` control points,
    ``S(0, v)`` is the profile), ``v`` follows the profile. Exact: every
    control point of the profile turns on its own circle, with the weights of
    :func:`~splinekit.construct.arc` times its own.
    """
    profile = as_curve(profile, "profile")
    if profile.dim != 3:
        raise ParameterError(f"revolve needs a 3-D profile, this one has dim={profile.dim}")
    O = as_vector(axis_origin, "axis_origin", (3,))
    a = as_unit(axis_direction, "axis_direction")
    theta = as_real(angle, "angle")
    knots, uv, wa = unit_arc(0.0, theta)
    P = profile.control_points
    w = profile.weights if profile.is_rational else np.ones(len(P))
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is reported by _surface, naming it
        foot = O + np.outer((P - O) @ a, a)  # projection of each control point on the axis
        X = P - foot
        X -= np.outer(X @ a, a)  # remove the rounding component along the axis
        Y = np.cross(a, X)
        pts = foot[None] + uv[:, 0, None, None] * X[None] + uv[:, 1, None, None] * Y[None]  # (nu, nv, 3)
        weights = wa[:, None] * w[None, :]
        net = np.concatenate([pts * weights[..., None], weights[..., None]], axis=-1)
    return _surface(2, profile.degree, knots, profile.knots, net, True)


# -- skinning -------------------------------------------------------------------------------------
def loft(curves, degree=3, *, parameters=None, parametrization="centripetal"):
    """Skinned surface through section curves (The NURBS Book section 10.3).

    Parameters
    ----------
    curves : sequence of curves, at least 2, of one dimension
        The sections ``C_k(u)``; made compatible first (:func:`make_compatible`).
    degree : int
        Degree in ``v``; lowered to ``len(curves) - 1`` when there are too few sections.
    parameters : (len(curves),) array_like, optional
        Strictly increasing ``v`` of the sections. Default: the parameters of
        ``parametrization`` (``"centripetal"``, ``"chord"`` or ``"uniform"``)
        of each column of the control nets, averaged over the columns (as in The
        NURBS Book section 10.3), on ``[0, 1]``.

    Returns a surface with ``S(u, parameters[k]) = C_k(u)`` exactly (up to
    rounding of the interpolation solve): the control points (homogeneous for
    rational sections) are interpolated across the sections by
    :func:`splinekit.fit.interpolate_curve` (rational sections first scaled
    to equal geometric-mean weights, which does not change them). Raises
    :class:`FittingError` when interpolating the weights of rational sections
    still gives a non-positive weight (sections whose weights differ a lot).
    """
    items = _curves_list(curves, "curves", 2)
    q = min(as_degree(degree), len(items) - 1)
    cs = make_compatible(items)
    rational = cs[0].is_rational
    C = np.stack([_coefs(c) for c in cs])  # (k, n, m)
    k, n, m = C.shape
    if rational:
        # scaling a section's homogeneous points leaves it unchanged; equal
        # geometric-mean weights keep the interpolated weights from overshooting
        C = C / np.exp(np.log(C[:, :, -1]).mean(axis=1))[:, None, None]
    if parameters is None:
        cart = np.stack([c.control_points for c in cs])
        parameters = grid_parameters(cart, parametrization)[0]
    across = interpolate_curve(C.reshape(k, n * m), q, parameters=parameters)
    Q = across.control_points.reshape(-1, n, m).transpose(1, 0, 2)
    if rational and not (Q[..., -1] > 0).all():
        i, j = (int(x) for x in np.argwhere(~(Q[..., -1] > 0))[0])
        raise FittingError(
            f"skinning these rational sections gives a non-positive weight at control point [{i}, {j}]; "
            "use sections with similar weights or a lower degree"
        )
    return _surface(cs[0].degree, q, cs[0].knots, across.knots, Q, rational)
