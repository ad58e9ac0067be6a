"""``project`` and ``distance``: closest points of many points on a curve,
surface or implicit, chunk by chunk (the method is described in
:mod:`splinekit.closest`)."""

from __future__ import annotations

import numpy as np

from ..curves import BezierCurve, SplineCurve
from ..errors import ConvergenceError, ParameterError
from ..surfaces import BezierSurface, SplineSurface
from .implicit import _Implicit
from . import newton
from .newton import _search, nearest_per_point
from .parametric import _Curve, _Surface
from .queries import Projection, _as_query_points, _readonly

__all__ = ["distance", "project"]

CHUNK = 32768
"""Points projected together; bounds the memory of the batch arrays."""


def project(geometry, points, *, tolerance=None, seeds=None) -> Projection:
    """Closest points of ``geometry`` to each of ``points``.

    Parameters
    ----------
    geometry
        A curve (``BezierCurve``, ``BSplineCurve``, ``NurbsCurve``, or any object
        with ``evaluate(u)``, ``derivatives(u, order)`` and ``domain = (a, b)``),
        a surface (``BezierSurface``, ``BSplineSurface``, ``NurbsSurface``, or
        any object with ``evaluate(u, v)``, ``derivatives(u, v, order)`` and
        ``domain = ((u0, u1), (v0, v1))`` or ``domain_u`` / ``domain_v``), or an
        implicit surface (callable on ``(n, dim)`` points, with ``gradient``).
    points : array_like, shape (n, dim) or (dim,)
        Finite points of the geometry's dimension, coordinates at most
        ``MAX_COORDINATE`` (1e150) in size, or that times the geometry's
        size for geometry larger than 1e60 or smaller than 1e-60.
    tolerance : float, optional
        Distance in model units. Newton stops once a step moves the closest
        point by less than this; an implicit's iteration stops once
        ``|F| <= tolerance``. Default: 1e-9 times the size of the geometry (its
        largest absolute sample coordinate, at least 1 unless it is below
        1e-60; for an implicit, of the points).
    seeds : array_like, optional
        Starting parameters replacing the sampled seeds (a local search, e.g.
        to track points that move a little): curves ``(n,)`` or ``(n, k)``
        (``k`` seeds per point), surfaces ``(n, 2)`` or ``(n, k, 2)``. Not
        accepted for implicit surfaces.

    Returns
    -------
    Projection
        ``parameters``, ``points`` and ``distances``; see :class:`Projection`.

    Raises
    ------
    ParameterError
        Non-finite or too large points, a dimension that does not match the geometry, a
        geometry of unknown kind, malformed seeds or tolerance.
    DomainError
        Seeds outside the parameter domain.
    ConvergenceError
        Newton stalled away from a stationary point for some point and its best
        seed is farther than ``tolerance`` (the message names the point), or an
        implicit's gradient vanishes or its iteration does not converge.
    """
    target = _target(geometry)
    if isinstance(target, _Implicit):
        if seeds is not None:
            raise ParameterError("seeds are parameters of a curve or surface; an implicit surface takes none")
        return target.project(points, tolerance)
    P, lead = _as_query_points(points, target.dim, target.unit)
    tol = target.tolerance(tolerance)
    k = target.n_params
    if P.shape[0] == 0:
        params = np.zeros(lead + ((k,) if k == 2 else ()))
        return Projection(_readonly(params), _readonly(np.zeros(lead + (target.dim,))), _readonly(np.zeros(lead)))
    if seeds is None:
        owner, x0 = None, None
    else:
        owner, x0 = target.user_seeds(seeds, P.shape[0], lead)
    params = np.empty((P.shape[0], k))
    points = np.empty_like(P)
    dists = np.empty(P.shape[0])
    # chunks of points bound the memory of the (points x seeds x derivatives) arrays
    for start in range(0, P.shape[0], CHUNK):
        stop = min(start + CHUNK, P.shape[0])
        if owner is None:
            own, xs = target.seeds(P[start:stop])
        else:
            sel = (owner >= start) & (owner < stop)
            own, xs = owner[sel] - start, x0[sel]
        own, x, S, dist, converged, stationary = _search(target, P[start:stop][own], own, xs, tol)
        best = nearest_per_point(own, dist, stop - start)
        bad = ~(converged[best] | stationary[best]) & (dist[best] > tol)
        if bad.any():
            i = start + int(np.flatnonzero(bad)[0])
            index = [int(j) for j in np.unravel_index(i, lead)] if lead else []
            raise ConvergenceError(
                f"Newton did not converge for points{index} = {(P[i] * target.unit).tolist()}: after {newton.MAX_ITERATIONS} "
                f"iterations the best candidate is at distance {float(dist[best[i - start]]) * target.unit:.6g} "
                f"and not stationary (tolerance {tol * target.unit:.3g})"
            )
        params[start:stop], points[start:stop], dists[start:stop] = x[best], S[best], dist[best]
    points *= target.unit
    dists *= target.unit
    params = params[:, 0] if k == 1 else params
    return Projection(
        _readonly(params.reshape(lead + params.shape[1:])),
        _readonly(points.reshape(lead + (target.dim,))),
        _readonly(dists.reshape(lead)),
    )


def distance(geometry, points, *, tolerance=None) -> np.ndarray:
    """Distances ``(n,)`` from each of ``points`` ``(n, dim)`` to ``geometry``
    (model units); see :func:`project` for the accepted geometry and errors."""
    return project(geometry, points, tolerance=tolerance).distances


def _target(geometry):
    """Wrap ``geometry`` in the adapter the projection works on."""
    if isinstance(geometry, (SplineSurface, BezierSurface)):
        return _Surface(geometry, geometry.domain)
    if isinstance(geometry, (SplineCurve, BezierCurve)):
        return _Curve(geometry, geometry.domain)
    if hasattr(geometry, "derivatives") and hasattr(geometry, "evaluate"):
        if hasattr(geometry, "domain_u") and hasattr(geometry, "domain_v"):
            return _Surface(geometry, (geometry.domain_u, geometry.domain_v))
        if hasattr(geometry, "domain"):
            dom = np.asarray(geometry.domain, dtype=object)
            if dom.shape == (2, 2):
                return _Surface(geometry, geometry.domain)
            if dom.shape == (2,):
                return _Curve(geometry, geometry.domain)
    if callable(geometry) and hasattr(geometry, "gradient"):
        return _Implicit(geometry)
    raise ParameterError(
        f"cannot project onto a {type(geometry).__name__}: expected a curve or surface (evaluate, derivatives, "
        "domain) or an implicit surface (callable on (n, 3) points, with gradient)"
    )
