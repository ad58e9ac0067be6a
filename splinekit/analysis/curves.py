"""Curve quality analysis: curvature combs, G0/G1/G2 between consecutive curves, inflections.

Built on :mod:`splinekit.diffgeom.curves` (curvature, signed curvature, tangents, Frenet frames).

Comb convention: a tooth is ``-kappa N * scale`` at each sample, ``kappa N`` being the curvature
vector (pointing toward the centre of curvature), so the teeth stand on the convex side of the
curve, away from the centre, as CAD curvature graphs draw them; their tips trace the comb's
outline. For a planar (2-D) curve ``kappa`` is the signed curvature and ``N`` the left normal
(the tangent turned +90 degrees), which gives the same teeth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import as_int
from ..curves import BezierCurve, BSplineCurve, SplineCurve
from ..diffgeom.curves import curvature, frenet_frame, signed_curvature, tangent
from ..errors import ParameterError
from ..tolerances import CONTINUITY_ANGLE, CONTINUITY_CURVATURE, CONTINUITY_GAP
from .compare import LEVELS, tolerance_value

__all__ = ["COMB_LENGTH", "CurvatureComb", "CurveContinuity", "curvature_comb", "curvature_combs", "curve_continuity",
           "inflections"]

COMB_LENGTH = 0.2
"""Default comb scale: the longest tooth is this fraction of the curve's bounding-box diagonal."""


def _as_curve(curve, what: str = "curve"):
    if isinstance(curve, BezierCurve):
        return curve.to_bspline()
    if isinstance(curve, SplineCurve):
        return curve
    if hasattr(curve, "derivatives") and hasattr(curve, "domain"):
        return curve
    raise ParameterError(f"{what} must be a curve (Bézier, B-spline, NURBS, or with derivatives and domain), "
                         f"got {type(curve).__name__}")


def _dim(curve) -> int:
    return int(np.asarray(curve.derivatives(np.array([curve.domain[0]]), 0)).shape[-1])


def _curvature_vectors(curve, u: np.ndarray):
    """``(kappa (n,), N (n, 3))``: curvature (signed for 2-D curves) and the normal it goes with
    (the left normal in 2-D, embedded at z = 0; the Frenet normal in 3-D); ``kappa N`` is the
    curvature vector."""
    dim = _dim(curve)
    if dim == 2:
        T = tangent(curve, u)
        return signed_curvature(curve, u), np.column_stack([-T[:, 1], T[:, 0], np.zeros(len(u))])
    if dim != 3:
        raise ParameterError(f"curve analysis needs a 2-D or 3-D curve, this one has dim={dim}")
    return curvature(curve, u), frenet_frame(curve, u)[1]


@dataclass(frozen=True)
class CurvatureComb:
    """Curvature comb of a curve at ``n`` samples: ``params`` ``(n,)``, ``points`` ``(n, dim)``,
    ``curvature`` ``(n,)`` (1 / length; signed for 2-D curves), ``comb`` ``(n, dim)`` the teeth
    ``-curvature * normal * scale`` (module docstring), ``tips`` = ``points + comb``, ``scale``
    (length^2: tooth length per unit curvature)."""

    params: np.ndarray
    points: np.ndarray
    curvature: np.ndarray
    comb: np.ndarray
    tips: np.ndarray
    scale: float


def curvature_comb(curve, samples: int = 200, *, scale=None) -> CurvatureComb:
    """The curvature comb of ``curve`` (2-D or 3-D) at ``samples`` equal parameter steps.

    ``scale``: tooth length per unit curvature (length^2); default: the longest tooth is
    :data:`COMB_LENGTH` of the curve's bounding-box diagonal (1 for a straight curve).
    """
    curve = _as_curve(curve)
    samples = as_int(samples, "samples", minimum=2)
    a, b = curve.domain
    u = np.linspace(a, b, samples)
    points = np.asarray(curve.derivatives(u, 0), dtype=np.float64)[0]
    if not np.isfinite(points).all():
        raise ParameterError("the curve evaluates to non-finite points")
    kappa, N = _curvature_vectors(curve, u)
    N = N[:, : points.shape[1]]
    if scale is None:
        diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
        largest = float(np.abs(kappa).max())
        scale = COMB_LENGTH * diagonal / largest if largest > 0 else 1.0
    else:
        scale = tolerance_value(scale, "scale", 1.0)
    comb = -kappa[:, None] * N * scale
    return CurvatureComb(u, points, kappa, comb, points + comb, float(scale))


@dataclass(frozen=True)
class CurveContinuity:
    """Continuity where two curves meet: ``gap`` (length), ``angle`` (radians between the tangents,
    both taken along the chain from the first curve to the second), ``curvature`` ``(2,)`` (the
    curvatures at the joint, >= 0), ``curvature_jump`` = ``|k0 - k1|``, ``curvature_vector_jump``
    = ``|k0 N0 - k1 N1|``, ``level`` ("G2", "G1", "G0", "none"), ``ends``: which ends meet
    (``("end", "start")`` for a chain in order; the others mean a curve runs the other way)."""

    gap: float
    angle: float
    curvature: np.ndarray
    curvature_jump: float
    curvature_vector_jump: float
    level: str
    ends: tuple


def _end_data(curve, at_end: bool):
    """Point, unit tangent (pointing along the curve), curvature and curvature vector at one end."""
    u = np.array([curve.domain[1] if at_end else curve.domain[0]])
    P = np.asarray(curve.derivatives(u, 0), dtype=np.float64)[0, 0]
    T = tangent(curve, u)[0]
    kappa, N = _curvature_vectors(curve, u)
    K = kappa[0] * N[0]
    pad = np.zeros(3)
    pad[: len(T)] = T
    return P, pad, float(abs(kappa[0])), K



def curvature_combs(curves, samples: int = 100, *, scale=None) -> list:
    """Curvature combs of several curves at one scale, so their teeth compare (a part's edges).

    ``scale`` as in :func:`curvature_comb`; default: the longest tooth of all is
    :data:`COMB_LENGTH` of the diagonal of all the curves' samples. Returns a list of
    :class:`CurvatureComb`, one per curve, in order."""
    combs = [curvature_comb(c, samples, scale=1.0) for c in curves]
    if not combs:
        raise ParameterError("curvature_combs got no curves")
    if scale is None:
        P = np.concatenate([c.points for c in combs])
        diagonal = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
        largest = max(float(np.abs(c.curvature).max()) for c in combs)
        scale = COMB_LENGTH * diagonal / largest if largest > 0 else 1.0
    else:
        scale = tolerance_value(scale, "scale", 1.0)
    return [CurvatureComb(c.params, c.points, c.curvature, c.comb * scale, c.points + c.comb * scale, float(scale))
            for c in combs]


def curve_continuity(c0, c1, *, gap_tol=None, angle_tol=None, curvature_tol=None) -> CurveContinuity:
    """G0/G1/G2 continuity where ``c0`` meets ``c1`` (2-D or 3-D curves of one dimension).

    The ends that meet are the closest pair of their end points, so a curve running the other
    way is handled. Tolerances: ``gap_tol`` (length; default ``CONTINUITY_GAP`` times the size,
    the largest absolute end-point coordinate, at least 1), ``angle_tol`` (radians; default
    ``CONTINUITY_ANGLE``), ``curvature_tol`` (relative to ``max(k0, k1, 1 / chord)``, ``chord``
    the larger end-to-end distance of the two curves; default ``CONTINUITY_CURVATURE``).
    """
    c0, c1 = _as_curve(c0, "c0"), _as_curve(c1, "c1")
    if _dim(c0) != _dim(c1):
        raise ParameterError(f"c0 and c1 must have one dimension, got {_dim(c0)} and {_dim(c1)}")
    ends = {(e0, e1): (_end_data(c0, e0), _end_data(c1, e1)) for e0 in (True, False) for e1 in (False, True)}
    for (p, _, _, _), (q, _, _, _) in ends.values():
        if not (np.isfinite(p).all() and np.isfinite(q).all()):
            raise ParameterError("c0 or c1 evaluates to non-finite points")
    key = min(ends, key=lambda k: float(np.linalg.norm(ends[k][0][0] - ends[k][1][0])))
    (P, T0, k0, K0), (Q, T1, k1, K1) = ends[key]
    # along the chain: into the joint on c0, out of it on c1
    T0 = T0 if key[0] else -T0
    T1 = -T1 if key[1] else T1
    gap = float(np.linalg.norm(P - Q))
    angle = float(np.arctan2(np.linalg.norm(np.cross(T0, T1)), T0 @ T1))
    jump = abs(k0 - k1)
    vector_jump = float(np.linalg.norm(K0 - K1))
    size = max(1.0, float(np.abs(P).max()), float(np.abs(Q).max()))
    chord = max(float(np.linalg.norm(ends[(True, True)][0][0] - ends[(False, False)][0][0])),
                float(np.linalg.norm(ends[(True, True)][1][0] - ends[(False, False)][1][0])))
    gap_tol = tolerance_value(gap_tol, "gap_tol", CONTINUITY_GAP * size)
    angle_tol = tolerance_value(angle_tol, "angle_tol", CONTINUITY_ANGLE)
    curvature_tol = tolerance_value(curvature_tol, "curvature_tol", CONTINUITY_CURVATURE)
    scale = max(k0, k1, 1.0 / chord if chord > 0 else 0.0)
    index = int(gap <= gap_tol)
    index += int(index == 1 and angle <= angle_tol)
    index += int(index == 2 and vector_jump <= curvature_tol * scale)
    return CurveContinuity(gap, angle, np.array([k0, k1]), jump, vector_jump, LEVELS[index],
                           ("end" if key[0] else "start", "end" if key[1] else "start"))


def _plane_coordinates(curve) -> tuple:
    """A 3-D curve as the 2-D curve of its projection on the best-fitting plane of its control
    points (exact for a planar curve), keeping weights and knots."""
    P = np.asarray(curve.control_points, dtype=np.float64)
    centre = P.mean(axis=0)
    _, _, vt = np.linalg.svd(P - centre)
    Q = (P - centre) @ vt[:2].T
    if curve.weights is None:
        return BSplineCurve(curve.degree, curve.knots, Q)
    return type(curve)(curve.degree, curve.knots, Q, curve.weights)


def inflections(curve) -> np.ndarray:
    """Parameters ``(k,)`` (increasing) where the signed curvature of a planar curve changes sign.

    2-D curves: their signed curvature; 3-D curves: that of their projection on the plane that
    best fits their control points (the plane of a planar curve; for a twisted curve, its
    bending without the torsion). On each Bézier span, ``(x' y'' - y' x'') w^3`` (``w`` the
    weight function, 1 for a polynomial curve) is a polynomial of degree ``3p - 3`` (``2p - 3``
    without weights) whose sign is the curvature's: it is interpolated at Chebyshev nodes and
    its real roots of odd multiplicity in the span are the inflections (exact up to rounding);
    a sign change across a knot (a curve only G1 there) is an inflection at the knot. Straight
    spans (the polynomial vanishes) have none.
    """
    curve = _as_curve(curve)
    if not isinstance(curve, SplineCurve):
        raise ParameterError(f"inflections needs a Bézier, B-spline or NURBS curve, got {type(curve).__name__}")
    if curve.dim == 3:
        curve = _plane_coordinates(curve)
    elif curve.dim != 2:
        raise ParameterError(f"inflections needs a 2-D or 3-D curve, this one has dim={curve.dim}")
    p = curve.degree
    if p < 2:
        return np.zeros(0)
    a, b = curve.domain
    breaks = np.unique(np.clip(curve.knots, a, b))
    degree = 3 * p - 3 if curve.weights is not None else 2 * p - 3
    nodes = np.cos(np.pi * (np.arange(degree + 1) + 0.5) / (degree + 1))  # Chebyshev points in (-1, 1)
    lo, hi = breaks[:-1, None], breaks[1:, None]
    t = 0.5 * (lo + hi) + 0.5 * (hi - lo) * nodes[None, :]  # (S, D + 1)
    d = np.asarray(curve.derivatives(t.ravel(), 2), dtype=np.float64)
    f = d[1, :, 0] * d[2, :, 1] - d[1, :, 1] * d[2, :, 0]
    if curve.weights is not None:
        f = f * BSplineCurve(p, curve.knots, np.asarray(curve.weights)[:, None]).evaluate(t.ravel())[:, 0] ** 3
    F = f.reshape(t.shape)
    # Chebyshev coefficients of every span at once: the nodes are the same in (-1, 1)
    coeffs = np.linalg.solve(np.polynomial.chebyshev.chebvander(nodes, degree), F.T).T  # (S, D + 1)
    speed = np.linalg.norm(d[1], axis=1).max()
    size = max(1e-300, float(np.abs(curve.control_points).max()))
    negligible = 1e-11 * speed**3 / size * (float(np.abs(f).max()) > 0)
    out = []
    for s in range(len(coeffs)):  # root finding per span; the sampling above is one batch
        c = coeffs[s]
        if np.abs(c).max() <= negligible:
            continue
        roots = np.polynomial.chebyshev.chebroots(np.trim_zeros(np.where(np.abs(c) > 1e-14 * np.abs(c).max(), c, 0), "b"))
        real = roots[(np.abs(roots.imag) <= 1e-9) & (np.abs(roots.real) <= 1.0)].real
        step = 1e-6
        for r in real:
            left, right = np.polynomial.chebyshev.chebval([r - step, r + step], c)
            if left * right < 0:
                out.append(float(lo[s, 0] + 0.5 * (r + 1.0) * (hi[s, 0] - lo[s, 0])))
    # a sign change across a knot where the curvature jumps (the curve is only G1 there)
    ends = np.polynomial.chebyshev.chebval(np.array([-1.0, 1.0]), coeffs.T)  # (S, 2): start, end of each span
    flips = np.flatnonzero(ends[:-1, 1] * ends[1:, 0] < 0)
    out += breaks[1:-1][flips].tolist()
    out = np.sort(np.array(out, dtype=np.float64))
    if out.size:
        out = out[np.concatenate([[True], np.diff(out) > 1e-9 * (b - a)])]
    return out
