"""Surfaces that fill a network of boundary curves: Coons patches (bilinear and
bicubic, with given cross-boundary derivatives) and Gordon surfaces.

Each is a Boolean sum of skins (:func:`~splinekit.construct.surfaces.loft`,
ruled surfaces) minus a tensor-product correction, all on shared knot
vectors; the inputs run along ``u`` and the construction goes along ``v`` as
in :mod:`.surfaces`.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_degree, as_float_array, as_real
from ..closest import project
from ..errors import ParameterError
from ..fit import interpolate_surface
from ..tolerances import geometric_tolerance
from .compat import make_compatible
from ._checks import as_curve
from .surfaces import _coefs, _curves_list, _size, _sum_surfaces, _surface, loft

__all__ = ["coons", "bicubic_coons", "gordon"]


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
