"""Sweeping a profile along a path in the rotation-minimizing frame (skinning, The NURBS Book 10.4).

A swept surface ``S(u, v) = C(v) + R(v) p(u)`` (``C`` the path, ``R(v)`` the
rotation-minimizing frame, ``p`` the profile in local coordinates) is not a
NURBS surface in general. :func:`sweep` places copies of the profile at
stations along the path and skins through them; because every copy is a
rigid motion of the same curve, the copies share knots and weights and the
skin interpolates each control point's trajectory ``C(v) + R(v) p_j``.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_degree, as_int, as_params, as_real
from ..basis import design_matrix
from ..curves.frames import rotation_minimizing_frames
from ..errors import ConvergenceError, ParameterError
from ..fit import interpolate_curve
from ._checks import as_curve
from .surfaces import _size, _surface

__all__ = ["sweep", "sweep_deviation"]

_SUBSTEPS = 4  # frame steps per sample interval: the frames' own error is O(h**4) in the step
_CHECKS = 3  # deviation check points inside every station interval
_SAFETY = 0.5  # the measured deviation must be within this fraction of the tolerance
_MAX_STATIONS = 2049
_MAX_SECTIONS = 100_000  # explicit n_sections: each station is a placed profile in the skinning solve
_DEFAULT_RELATIVE_TOLERANCE = 1e-6


def _stations(path, per_span: int) -> np.ndarray:
    """``per_span`` equal steps in every knot span of the path (knots are stations)."""
    br = path.bezier_breakpoints()
    s = np.linspace(0.0, 1.0, per_span + 1)[:-1]
    inner = (br[:-1, None] + np.diff(br)[:, None] * s).ravel()
    return np.concatenate([inner, br[-1:]])


def _subdivided(params: np.ndarray, parts: int) -> np.ndarray:
    """``params`` with every interval cut into ``parts`` equal pieces."""
    s = np.linspace(0.0, 1.0, parts + 1)[:-1]
    return np.concatenate([(params[:-1, None] + np.diff(params)[:, None] * s).ravel(), params[-1:]])


def _frames(path, params, normal):
    """Rotation-minimizing frames ``(len(params), 3, 3)`` (rows T, N, B) at sorted ``params``,
    computed on ``_SUBSTEPS`` sub-steps per interval for accuracy."""
    fine = _subdivided(params, _SUBSTEPS) if params.size > 1 else params
    T, N, B = rotation_minimizing_frames(path, fine, normal)
    pick = np.arange(params.size) * _SUBSTEPS
    return np.stack([T[pick], N[pick], B[pick]], axis=1)


def _placed(path_points, frames, local):
    """Control points ``(k, n, 3)`` of the profile placed at ``k`` stations:
    ``C + l_T T + l_N N + l_B B`` for local coordinates ``local`` ``(n, 3)``."""
    return path_points[:, None, :] + np.einsum("nc,kcd->knd", local, frames)


def sweep(profile, path, *, n_sections=None, tolerance=None, normal=None, degree=3):
    """Sweep ``profile`` along ``path`` keeping it in the rotation-minimizing frame.

    Parameters
    ----------
    profile : curve, dim 2 or 3
        A 2-D profile gives local coordinates ``(x, y)`` in the normal plane
        of the path: the section at ``v`` is ``C(v) + x N(v) + y B(v)``. A 3-D
        profile is taken where it stands relative to the path start and moved
        rigidly with the frame: ``C(v) + R(v) R(v0)^T (p - C(v0))``.
    path : curve, dim 3
        Its parameter becomes ``v``; it must have a tangent everywhere.
    n_sections : int, optional
        Number of stations, spread equally over each knot span of the path:
        the path's knots are always stations and every span gets the same
        number ``k >= degree`` of intervals, so the count is rounded up to
        ``n_spans * k + 1``; at most 100000. Default: adaptive, see ``tolerance``.
    tolerance : float, optional
        Target distance (model units) between the skin and the exact sweep.
        Default ``1e-6`` times the largest absolute control-point coordinate
        of the path and profile (at least 1). Used only when ``n_sections`` is
        None: the stations per span (starting at ``degree``) double until the
        deviation measured at the quarter points of every station interval is
        within half of ``tolerance`` (ConvergenceError beyond 2049 stations).
    normal : (3,) array_like, optional
        Start normal ``N(v0)`` of the frame (see
        :func:`splinekit.curves.frames.rotation_minimizing_frames`); it sets
        the orientation of a 2-D profile.
    degree : int
        Degree in ``v`` (the skinning interpolation).

    Returns
    -------
    BSplineSurface or NurbsSurface with ``u`` along the profile (its knots and
    weights) and ``v`` on the path's domain; ``S(u, v_k)`` is exactly the
    placed profile at every station ``v_k``.

    Accuracy: every surface point is a convex combination (positive weights)
    of the interpolated control-point trajectories, so its distance to the
    exact sweep at the same ``v`` is at most the largest deviation of a
    control point from its exact trajectory ``C(v) + R(v) p_j``. That is what
    is measured, at three points inside every station interval, with a
    safety factor of 2 for the peaks between them; the error falls like
    ``h**4`` in the station spacing (the skin's ``v`` knots have multiplicity
    ``degree`` at the path's knots, so a path that is only C1 there, such as
    a circle, costs no order). The frames come from the double-reflection
    method (error ``O(h**4)``) with 16 steps per station interval and are the
    reference of the measurement. :func:`sweep_deviation` measures a result
    at any parameters.
    """
    profile = as_curve(profile, "profile")
    path = as_curve(path, "path")
    if path.dim != 3:
        raise ParameterError(f"sweep needs a 3-D path, this one has dim={path.dim}")
    if profile.dim not in (2, 3):
        raise ParameterError(f"the profile must be 2-D or 3-D, this one has dim={profile.dim}")
    q = as_degree(degree)
    n_spans = path.bezier_breakpoints().size - 1
    if tolerance is None:
        tol = _DEFAULT_RELATIVE_TOLERANCE * _size(path.control_points, profile.control_points)
    else:
        tol = as_real(tolerance, "tolerance")
        if not tol > 0:
            raise ParameterError(f"tolerance must be finite and > 0, got {tolerance!r}")
    if n_sections is not None:
        count = as_int(n_sections, "n_sections", minimum=2)
        if count > _MAX_SECTIONS:
            raise ParameterError(f"n_sections = {count} exceeds the largest supported count {_MAX_SECTIONS}")
        per_span = max(q, -(-(count - 1) // n_spans))
        surface, _ = _sweep_once(profile, path, per_span, normal, q)
        return surface
    per_span = q
    while True:
        surface, dev = _sweep_once(profile, path, per_span, normal, q)
        if dev <= _SAFETY * tol:
            return surface
        if n_spans * 2 * per_span + 1 > _MAX_STATIONS:
            raise ConvergenceError(
                f"sweep: {n_spans * per_span + 1} stations still deviate {dev:.3g} from the exact sweep, "
                f"more than half the tolerance {tol:.3g}"
            )
        per_span *= 2


def sweep_deviation(profile, path, surface, *, normal=None, samples=None):
    """Largest deviation of the swept ``surface``'s control-point trajectories from the exact
    ones at the parameters ``samples`` of the path (default: 257 equally spaced); see :func:`sweep`."""
    profile = as_curve(profile, "profile")
    path = as_curve(path, "path")
    a, b = path.domain
    v = np.linspace(a, b, 257) if samples is None else np.sort(as_params(samples, (a, b), "samples").ravel())
    if v.size == 0:
        raise ParameterError("samples is empty: sweep_deviation needs at least one parameter")
    local = _local_coordinates(profile, path, normal)
    # the frames propagate from the path start, whatever the samples
    frames = _frames(path, np.concatenate([[a], v]), normal)[1:]
    return _deviation(path, surface, local, v, normal, frames)


def _local_coordinates(profile, path, normal):
    """Profile control points in the start frame ``(n, 3)``: ``(l_T, l_N, l_B)``."""
    P = profile.control_points
    if profile.dim == 2:
        return np.column_stack([np.zeros(len(P)), P])
    a = path.domain[0]
    F0 = _frames(path, np.array([a, path.domain[1]]), normal)[0]
    return (P - path.evaluate(a)) @ F0.T


def _deviation(path, surface, local, v, normal, frames):
    """Largest distance between the skin's interpolated control points and the exact placed ones at ``v``."""
    exact = _placed(path.evaluate(v), frames, local)  # (m, n, 3)
    H = surface.homogeneous_points if surface.is_rational else surface.control_points
    n, K, k = H.shape
    A = design_matrix(surface.degree_v, surface.knots_v, v)
    traj = A @ H.transpose(1, 0, 2).reshape(K, n * k)
    traj = np.asarray(traj).reshape(v.size, n, k)
    if surface.is_rational:
        traj = traj[..., :-1] / traj[..., -1:]
    return float(np.linalg.norm(traj - exact, axis=-1).max())


def _skin_knots(stations: np.ndarray, n_spans: int, q: int) -> np.ndarray:
    """Knots of the skin in ``v``: averaged knots (eq. 9.8) inside each path span,
    multiplicity ``q`` at the path's breakpoints.

    The exact sweep is only as smooth as the path at its knots (a circle's
    double knots leave it C1 there); a C2 interpolant across such a point
    would converge like ``h**2`` instead of ``h**4``. With multiplicity ``q``
    the interpolation splits into independent pieces per span, and the
    surface follows the path's own breaks.
    """
    per = (stations.size - 1) // n_spans
    # row k: the stations of path span k, both ends included
    spans = np.concatenate([stations[:-1].reshape(n_spans, per), stations[per::per, None]], axis=1)
    windows = np.lib.stride_tricks.sliding_window_view(spans, q, axis=1)[:, 1 : per - q + 1]
    inner = windows.mean(axis=-1)  # (n_spans, per - q)
    breaks = spans[:, -1]
    pieces = np.concatenate([inner, np.repeat(breaks[:, None], q, axis=1)], axis=1).ravel()[: -q]
    a, b = stations[0], stations[-1]
    return np.concatenate([np.full(q + 1, a), pieces, np.full(q + 1, b)])


def _sweep_once(profile, path, per_span, normal, q):
    """The skin through ``per_span`` stations per path span, and its deviation at the midpoints."""
    n_spans = path.bezier_breakpoints().size - 1
    stations = _stations(path, per_span)
    # check points: the interior quarter points of every station interval
    fine = _subdivided(stations, _CHECKS + 1)
    checks = np.ones(fine.size, dtype=bool)
    checks[:: _CHECKS + 1] = False
    F = _frames(path, fine, normal)
    local = _local_coordinates(profile, path, normal)
    placed = _placed(path.evaluate(stations), F[:: _CHECKS + 1], local)  # (k, n, 3)
    if profile.is_rational:
        w = np.broadcast_to(profile.weights[None, :, None], placed.shape[:2] + (1,))
        coefs = np.concatenate([placed * w, w], axis=-1)
    else:
        coefs = placed
    K, n, k = coefs.shape
    across = interpolate_curve(coefs.reshape(K, n * k), q, parameters=stations, knots=_skin_knots(stations, n_spans, q))
    Q = across.control_points.reshape(K, n, k).transpose(1, 0, 2)
    surface = _surface(profile.degree, q, profile.knots, across.knots, Q, profile.is_rational)
    return surface, _deviation(path, surface, local, fine[checks], normal, F[checks])
