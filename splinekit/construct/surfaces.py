"""Surface construction: extrusion, ruled, revolved, skinned, swept, Coons and Gordon surfaces.

Every function returns a :class:`~splinekit.BSplineSurface`, or a
:class:`~splinekit.NurbsSurface` when a rational input (or a revolution)
needs weights. Control nets are built with whole-array operations on the
(homogeneous) control points of the inputs; no loop runs per control point.

Parameter conventions: for ``extrude``, ``ruled``, ``loft``, ``sweep`` and the
Coons/Gordon patches the input curves run along ``u`` and the construction
goes along ``v``; ``revolve`` follows The NURBS Book A8.1 and OpenCascade's
``Geom_SurfaceOfRevolution``: ``u`` goes around the axis, ``v`` along the
profile.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_degree, as_float_array, as_real
from ..errors import ControlPointError, FittingError, ParameterError, WeightError
from ..surfaces import BSplineSurface
from ..tolerances import geometric_tolerance
from ._checks import as_curve, as_unit, as_vector
from .compat import make_compatible, make_surfaces_compatible
from .curves import TWO_PI, unit_arc

__all__ = ["extrude", "ruled", "revolve", "loft", "coons", "bicubic_coons", "gordon"]


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
    from ..fit import interpolate_curve
    from ..fit.parametrize import grid_parameters

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


# -- Coons patches ----------------------------------------------------------------------------------
def _boundary_pairs(c0, c1, d0, d1):
    """The four boundaries as two compatible pairs (all rational if any is)."""
    items = [as_curve(c, name) for c, name in ((c0, "c0"), (c1, "c1"), (d0, "d0"), (d1, "d1"))]
    dims = {c.dim for c in items}
    if len(dims) != 1:
        raise ParameterError(f"c0, c1, d0, d1 must have one dimension, got {[c.dim for c in items]}")
    if any(c.is_rational for c in items):
        items = [c.to_nurbs() for c in items]
    cu = make_compatible(items[:2])
    dv = make_compatible(items[2:])
    return cu, dv


def _check_corners(cu, dv, tol):
    """Raise unless the boundary curves meet at the four corners within ``tol``."""
    (a, b), (c, d) = cu[0].domain, dv[0].domain
    ends_c = np.stack([cu[0].evaluate(np.array([a, b])), cu[1].evaluate(np.array([a, b]))])  # [v side, u end]
    ends_d = np.stack([dv[0].evaluate(np.array([c, d])), dv[1].evaluate(np.array([c, d]))])  # [u side, v end]
    tol = geometric_tolerance(tol, np.concatenate([ends_c.reshape(-1, ends_c.shape[-1]), ends_d.reshape(-1, ends_d.shape[-1])]))
    names = {(0, 0): ("c0 start", "d0 start"), (1, 0): ("c0 end", "d1 start"),
             (0, 1): ("c1 start", "d0 end"), (1, 1): ("c1 end", "d1 end")}
    for (i, j), (nc, nd) in names.items():
        gap = float(np.linalg.norm(ends_c[j, i] - ends_d[i, j]))
        if not gap <= tol:
            raise ParameterError(
                f"the boundary curves do not meet at corner (u={'ab'[i]}, v={'cd'[j]}): {nc} = "
                f"{ends_c[j, i].tolist()} but {nd} = {ends_d[i, j].tolist()} (distance {gap:.3g} > tolerance {tol:.3g})"
            )


def _consistent_weights(cu, dv):
    """Rational boundaries rescaled (each curve's weights times a constant) so that
    curves meeting at a corner carry the same weight there.

    Raises when no such scaling exists (the four corner weight ratios do not
    multiply to one).
    """
    def w(crv, end):
        return float(crv.weights[0 if end == 0 else -1])

    alpha = 1.0
    gamma = alpha * w(cu[0], 0) / w(dv[0], 0)
    delta = alpha * w(cu[0], 1) / w(dv[1], 0)
    beta = gamma * w(dv[0], 1) / w(cu[1], 0)
    lhs, rhs = beta * w(cu[1], 1), delta * w(dv[1], 1)
    if abs(lhs - rhs) > 1e-10 * max(lhs, rhs):
        raise ParameterError(
            "the end weights of these rational boundary curves cannot be made to agree at all four corners by "
            f"scaling each curve (mismatch {lhs!r} vs {rhs!r} at corner (u=b, v=d)); "
            "reparametrize a boundary so that its end weights are 1"
        )
    scaled = []
    for crv, s in zip((*cu, *dv), (alpha, beta, gamma, delta)):
        scaled.append(type(crv)._trusted(crv.degree, crv.knots, crv.homogeneous_points * s, True))
    return scaled[:2], scaled[2:]


def coons(c0, c1, d0, d1, *, tol=None):
    """Bilinearly blended Coons patch, exactly as a B-spline (or NURBS) surface.

    Parameters
    ----------
    c0, c1 : curves
        The ``u``-boundaries: ``S(u, v0) = c0(u)``, ``S(u, v1) = c1(u)``
        (``c1`` is mapped affinely onto ``c0``'s domain, which becomes the ``u`` domain).
    d0, d1 : curves
        The ``v``-boundaries: ``S(u0, v) = d0(v)``, ``S(u1, v) = d1(v)`` (the ``v``
        domain is ``d0``'s).
    tol : float, optional
        Distance within which the curves must meet at the four corners
        (default ``1e-9`` times the size of the corner coordinates, at least 1).

    The surface is ``ruled(c0, c1) + ruled(d0, d1) - bilinear(corners)``, each
    term brought to common degrees and knots and the control nets added. It
    reproduces ``c0`` and ``c1`` exactly and ``d0``, ``d1`` to within the
    corner mismatch. For polynomial curves this is the Coons formula
    ``(1-v) c0 + v c1 + (1-u) d0 + u d1 - bilinear`` (with ``u``, ``v`` scaled
    to [0, 1]) exactly. Rational boundaries are blended in homogeneous space
    (so the interior is the projection of the homogeneous Coons patch, not
    the Cartesian formula; the boundaries are exact), which needs the weights
    of the curves meeting at a corner to agree after scaling each curve by a
    constant; otherwise a ParameterError is raised.
    """
    cu, dv = _boundary_pairs(c0, c1, d0, d1)
    _check_corners(cu, dv, tol)
    rational = cu[0].is_rational
    if rational:
        cu, dv = _consistent_weights(cu, dv)
    (a, b), (c, d) = cu[0].domain, dv[0].domain
    lin_u, lin_v = [a, a, b, b], [c, c, d, d]
    Rc = _surface(cu[0].degree, 1, cu[0].knots, lin_v, np.stack([_coefs(cu[0]), _coefs(cu[1])], axis=1), rational)
    Rd = _surface(1, dv[0].degree, lin_u, dv[0].knots, np.stack([_coefs(dv[0]), _coefs(dv[1])], axis=0), rational)
    # the corners of the v-boundaries: then S(u, v0) = c0(u) and S(u, v1) = c1(u) exactly
    corners = np.array([[_coefs(dv[0])[0], _coefs(dv[0])[-1]], [_coefs(dv[1])[0], _coefs(dv[1])[-1]]])
    T = _surface(1, 1, lin_u, lin_v, corners, rational)
    return _sum_surfaces([(1.0, Rc), (1.0, Rd), (-1.0, T)])


# Cubic Hermite data -> Bernstein coefficients on an interval of length h:
# [P0, P1, h T0, h T1] -> [P0, P0 + h T0 / 3, P1 - h T1 / 3, P1].
_HERMITE_TO_BEZIER = np.array([[1.0, 0.0, 0.0, 0.0], [1.0, 0.0, 1.0 / 3.0, 0.0], [0.0, 1.0, 0.0, -1.0 / 3.0], [0.0, 1.0, 0.0, 0.0]])


def _bezier3(lo, hi):
    """Knot vector of one cubic Bézier span on ``[lo, hi]``."""
    return [lo] * 4 + [hi] * 4


def _hermite_loft(curves, crosses, length):
    """Control nets ``(4, n, dim)`` of ``H0 c0 + H1 c1 + H2 g0 + H3 g1`` (zero g when None)."""
    P0, P1 = curves[0].control_points, curves[1].control_points
    G0 = crosses[0].control_points if crosses is not None else np.zeros_like(P0)
    G1 = crosses[1].control_points if crosses is not None else np.zeros_like(P0)
    data = np.stack([P0, P1, length * G0, length * G1])
    return np.tensordot(_HERMITE_TO_BEZIER, data, axes=(1, 0))


def bicubic_coons(c0, c1, d0, d1, *, c0_cross=None, c1_cross=None, d0_cross=None, d1_cross=None, tol=None, derivative_tol=None):
    """Coons patch with cubic Hermite blending, as a polynomial B-spline surface.

    Same boundaries as :func:`coons` (``c0``/``c1`` at ``v = v0, v1``,
    ``d0``/``d1`` at ``u = u0, u1``). The blending functions are the cubic
    Hermite polynomials ``H0 = 1 - 3t^2 + 2t^3``, ``H1 = 3t^2 - 2t^3``.

    Without cross-boundary derivative curves the derivative terms are zero
    (and so are the corner twists): this is the classic bicubically blended
    Coons patch, whose cross-boundary derivative along ``v = v0`` is the
    Hermite blend ``H0(u) d0'(v0) + H1(u) d1'(v0)`` of the side curves' end tangents.

    Optional cross-boundary derivatives, given in pairs:

    * ``c0_cross``, ``c1_cross``: curves in ``u`` giving ``dS/dv`` along
      ``v = v0`` and ``v = v1``; at the corners they must equal the
      derivatives of ``d0`` and ``d1`` there.
    * ``d0_cross``, ``d1_cross``: curves in ``v`` giving ``dS/du`` along
      ``u = u0`` and ``u = u1``; at the corners they must equal the
      derivatives of ``c0`` and ``c1`` there.
    * With both pairs, the twists must agree: ``c*_cross'`` = ``d*_cross'`` at each corner.

    Derivatives are with respect to the patch parameters (``u`` on ``c0``'s
    domain, ``v`` on ``d0``'s). The result interpolates ``c0``, ``c1`` exactly,
    ``d0``, ``d1`` within the corner mismatch, and the given cross
    derivatives. ``tol`` bounds the corner mismatch of positions (as in
    :func:`coons`), ``derivative_tol`` (default ``1e-7`` times the size of the
    derivatives, at least 1) that of the corner derivatives. Rational
    boundaries are not supported (ParameterError).
    """
    cu, dv = _boundary_pairs(c0, c1, d0, d1)
    if cu[0].is_rational:
        raise ParameterError("bicubic_coons takes polynomial (non-rational) boundary curves; use coons for rational ones")
    _check_corners(cu, dv, tol)
    (a, b), (c, d) = cu[0].domain, dv[0].domain
    gu = _cross_pair(c0_cross, c1_cross, "c0_cross", "c1_cross", cu[0].dim)
    fv = _cross_pair(d0_cross, d1_cross, "d0_cross", "d1_cross", cu[0].dim)
    if gu is not None:
        both = make_compatible([*cu, *gu])
        cu, gu = both[:2], both[2:]
    if fv is not None:
        both = make_compatible([*dv, *fv])
        dv, fv = both[:2], both[2:]
    ends_u, ends_v = np.array([a, b]), np.array([c, d])
    dd = np.stack([crv.derivatives(ends_v, 1) for crv in dv])  # [side u, order, v end]
    dc = np.stack([crv.derivatives(ends_u, 1) for crv in cu])  # [side v, order, u end]
    scale = _size(dd[:, 1], dc[:, 1])
    dtol = 1e-7 * scale if derivative_tol is None else _nonnegative(derivative_tol, "derivative_tol")
    M = np.zeros((4, 4, cu[0].dim))
    M[:2, :2] = dd[:, 0]  # corner positions S(u_i, v_j) from the side curves
    if gu is not None:
        M[:2, 2:] = dd[:, 1]  # dS/dv at the corners
        g = np.stack([crv.evaluate(ends_u) for crv in gu])  # [v side, u end]
        _match(g.transpose(1, 0, 2), dd[:, 1], dtol, "c{j}_cross at u end {i}", "the derivative of d{i} at v end {j}")
    if fv is not None:
        f = np.stack([crv.derivatives(ends_v, 1) for crv in fv])  # [u side, order, v end]
        M[2:, :2] = f[:, 0]  # dS/du at the corners
        _match(f[:, 0], dc[:, 1].transpose(1, 0, 2), dtol, "d{i}_cross at v end {j}", "the derivative of c{j} at u end {i}")
        if gu is not None:
            M[2:, 2:] = f[:, 1]  # twists
            gd = np.stack([crv.derivatives(ends_u, 1)[1] for crv in gu])  # [v side, u end]
            twist_tol = 1e-7 * _size(f[:, 1], gd) if derivative_tol is None else dtol
            _match(f[:, 1], gd.transpose(1, 0, 2), twist_tol, "the v-derivative of d{i}_cross at v end {j}",
                   "the u-derivative of c{j}_cross at u end {i} (twist)")
    hu, hv = b - a, d - c
    M[2:] *= hu
    M[:, 2:] *= hv
    K = _HERMITE_TO_BEZIER
    corner_net = np.einsum("ik,jl,kl...->ij...", K, K, M)
    Pc = _surface(cu[0].degree, 3, cu[0].knots, _bezier3(c, d), _hermite_loft(cu, gu, hv).transpose(1, 0, 2), False)
    Pd = _surface(3, dv[0].degree, _bezier3(a, b), dv[0].knots, _hermite_loft(dv, fv, hu), False)
    B = _surface(3, 3, _bezier3(a, b), _bezier3(c, d), corner_net, False)
    return _sum_surfaces([(1.0, Pc), (1.0, Pd), (-1.0, B)])


def _nonnegative(value, name):
    x = as_real(value, name)
    if not x >= 0:
        raise ParameterError(f"{name} must be >= 0, got {x!r}")
    return x


def _cross_pair(g0, g1, n0, n1, dim):
    if g0 is None and g1 is None:
        return None
    if g0 is None or g1 is None:
        raise ParameterError(f"give {n0} and {n1} together (or neither)")
    out = [as_curve(g0, n0), as_curve(g1, n1)]
    for crv, name in zip(out, (n0, n1)):
        if crv.is_rational:
            raise ParameterError(f"{name} must be a polynomial curve")
        if crv.dim != dim:
            raise ParameterError(f"{name} has dimension {crv.dim}, the boundaries {dim}")
    return out


def _match(got, want, tol, got_name, want_name):
    """Raise naming the first corner ``[i, j]`` where ``got`` and ``want`` differ by more than ``tol``."""
    gap = np.linalg.norm(got - want, axis=-1)
    bad = np.argwhere(~(gap <= tol))
    if bad.size:
        i, j = (int(x) for x in bad[0])
        raise ParameterError(
            f"{got_name.format(i=i, j=j)} = {got[i, j].tolist()} differs from {want_name.format(i=i, j=j)} = "
            f"{want[i, j].tolist()} by {float(gap[i, j]):.3g} (tolerance {tol:.3g}); the Boolean sum would not "
            "interpolate the boundary data"
        )


# -- Gordon surfaces -------------------------------------------------------------------------------
def _network_parameters(given, first_curve, others_start, name, domain):
    """Parameters where the crossing curves meet ``first_curve``: given (validated) or estimated."""
    k = len(others_start)
    lo, hi = domain
    if given is None:
        from ..closest import project

        t = np.array(project(first_curve, others_start).parameters, dtype=np.float64).reshape(k)
        t[0], t[-1] = lo, hi
    else:
        t = as_float_array(given, name)
        if t.shape != (k,) or not np.isfinite(t).all():
            raise ParameterError(f"{name} must be {k} finite numbers (one per crossing curve), got {given!r}")
        t = t.copy()
    if not (np.diff(t) > 0).all():
        i = int(np.flatnonzero(~(np.diff(t) > 0))[0])
        raise ParameterError(f"{name} must increase strictly, but {name}[{i + 1}] = {t[i + 1]!r} <= {name}[{i}] = {t[i]!r}")
    slack = 1e-9 * (hi - lo)
    if abs(t[0] - lo) > slack or abs(t[-1] - hi) > slack:
        raise ParameterError(
            f"{name} must start and end at the ends of the domain [{lo!r}, {hi!r}] (the first and last crossing "
            f"curves are boundaries of the network), got [{t[0]!r}, {t[-1]!r}]"
        )
    t[0], t[-1] = lo, hi
    return t


def gordon(u_curves, v_curves, *, u_parameters=None, v_parameters=None, degree=3, tol=None):
    """Gordon surface through a network of curves (Boolean sum of two skins).

    Parameters
    ----------
    u_curves : sequence of m >= 2 polynomial curves
        ``S(u, v_i) = u_curves[i](u)``; made compatible (``u`` domain of the first one).
    v_curves : sequence of n >= 2 polynomial curves
        ``S(u_j, v) = v_curves[j](v)``; made compatible (``v`` domain of the first one).
    u_parameters : (n,) array_like, optional
        ``u_j`` where ``v_curves[j]`` crosses the ``u_curves``; strictly
        increasing, from the start to the end of the ``u`` domain (the first and
        last ``v_curves`` are boundaries). Default: the closest points on
        ``u_curves[0]`` of the ``v_curves``' start points.
    v_parameters : (m,) array_like, optional
        ``v_i`` likewise on ``v_curves[0]``.
    degree : int
        Degree of the interpolation across the curves (lowered to the count - 1).
    tol : float, optional
        The network must intersect: ``|u_curves[i](u_j) - v_curves[j](v_i)| <= tol``
        (default ``1e-9`` times the size of the network, at least 1), else ParameterError.

    Returns ``loft(u_curves) + loft(v_curves) - T`` with ``T`` the tensor-product
    interpolant of the intersection points, all on shared knot vectors so that
    the result passes through every network curve (exactly for the
    ``u_curves``, within the intersection mismatch for the ``v_curves``).
    """
    from ..fit import interpolate_surface

    U = _curves_list(u_curves, "u_curves", 2)
    V = _curves_list(v_curves, "v_curves", 2)
    dims = {c.dim for c in U + V}
    if len(dims) != 1:
        raise ParameterError(f"all network curves must have one dimension, got {sorted(dims)}")
    if any(c.is_rational for c in U + V):
        raise ParameterError("gordon takes polynomial (non-rational) network curves")
    q = as_degree(degree)
    U = make_compatible(U)
    V = make_compatible(V)
    dom_u, dom_v = U[0].domain, V[0].domain
    starts_v = np.stack([c.evaluate(dom_v[0]) for c in V])
    starts_u = np.stack([c.evaluate(dom_u[0]) for c in U])
    uj = _network_parameters(u_parameters, U[0], starts_v, "u_parameters", dom_u)
    vi = _network_parameters(v_parameters, V[0], starts_u, "v_parameters", dom_v)
    on_u = np.stack([c.evaluate(uj) for c in U])  # (m, n, dim): u_curves[i](u_j)
    on_v = np.stack([c.evaluate(vi) for c in V]).transpose(1, 0, 2)  # (m, n, dim): v_curves[j](v_i)
    tol = geometric_tolerance(tol, np.concatenate([on_u.reshape(-1, on_u.shape[-1]), on_v.reshape(-1, on_u.shape[-1])]))
    gap = np.linalg.norm(on_u - on_v, axis=-1)
    if not (gap <= tol).all():
        i, j = (int(x) for x in np.argwhere(~(gap <= tol))[0])
        raise ParameterError(
            f"the curve network does not intersect: u_curves[{i}](u={uj[j]!r}) = {on_u[i, j].tolist()} but "
            f"v_curves[{j}](v={vi[i]!r}) = {on_v[i, j].tolist()} (distance {float(gap[i, j]):.3g} > tolerance {tol:.3g})"
        )
    L1 = loft(U, q, parameters=vi)  # u along the u_curves, v across
    L2 = loft(V, q, parameters=uj).transpose()  # u across, v along the v_curves
    T = interpolate_surface(
        0.5 * (on_u + on_v).transpose(1, 0, 2),  # (n, m, dim): rows u_j, columns v_i
        L2.degree_u,
        L1.degree_v,
        parameters_u=uj,
        parameters_v=vi,
        knots_u=L2.knots_u,
        knots_v=L1.knots_v,
    )
    return _sum_surfaces([(1.0, L1), (1.0, L2), (-1.0, T)])
