"""A second, independent way to integrate area and volume over untrimmed patches, for
cross-checking :mod:`.integrate` where OpenCascade's GProp is not reliable.

:func:`scipy_integrals` runs scipy's own adaptive cubature (``scipy.integrate.cubature``, the
Gauss-Kronrod 21-point product rule with its own subdivision; ``dblquad`` on older scipy) on
every Bézier span of every patch: no code is shared with :mod:`.integrate` except the surface
evaluator. :func:`singular_patches` finds the patches on which GProp drifts (collapsed edges,
poles, corners where ``Su x Sv`` vanishes).
"""

from __future__ import annotations

import numpy as np

from .face import as_surface

__all__ = ["singular_patches", "scipy_integrals"]


def singular_patches(surfaces, samples: int = 9, rel: float = 1e-8) -> list[tuple[int, str]]:
    """``(index, reason)`` of every surface whose area element ``|Su x Sv|`` vanishes somewhere
    on a ``samples x samples`` grid that includes the boundary and the knots' corners: a side
    collapsed to a point (a pole, a sphere's or a teapot lid's apex) or a corner where the two
    partial derivatives are parallel. ``rel``: threshold on ``|Su x Sv| / (|Su| |Sv|)`` (or on
    ``|Su|``, ``|Sv|`` against the patch size)."""
    found = []
    for index, surface in enumerate(surfaces):
        s = as_surface(surface)
        bu, bv = s.bezier_breakpoints()
        us = np.unique(np.concatenate([np.linspace(bu[0], bu[-1], samples), bu]))
        vs = np.unique(np.concatenate([np.linspace(bv[0], bv[-1], samples), bv]))
        d = s.derivatives_grid(us, vs, 1)
        su, sv = np.linalg.norm(d[1, 0], axis=-1), np.linalg.norm(d[0, 1], axis=-1)
        n = np.linalg.norm(np.cross(d[1, 0], d[0, 1]), axis=-1)
        size = float(np.ptp(np.asarray(s.control_points).reshape(-1, 3), axis=0).max())
        scale_u, scale_v = size / max(bu[-1] - bu[0], 1e-300), size / max(bv[-1] - bv[0], 1e-300)
        if (su <= rel * scale_u).any() or (sv <= rel * scale_v).any():
            found.append((index, "collapsed edge or pole"))
        elif (n <= rel * su * sv).any():
            found.append((index, "singular corner (Su parallel to Sv)"))
    return found


def _integrand(surface, center):
    def f(u, v):
        d = surface.derivatives(u, v, 1)
        N = np.cross(d[1, 0], d[0, 1])
        return np.stack([np.linalg.norm(N, axis=-1), np.einsum("...i,...i->...", d[0, 0] - center, N) / 3.0], axis=-1)

    return f


def scipy_integrals(surfaces, tol: float = 1e-11) -> tuple[float, float, float]:
    """``(area, flux volume, error estimate)`` of a patch set by scipy's adaptive cubature on
    every Bézier span; the volume is ``1/3 sum of integrals of (S - c) . (Su x Sv)`` about the
    centre ``c`` of the control points' box (the enclosed volume for a closed, outward set).

    ``tol``: relative tolerance asked of scipy per span. Slow next to :mod:`.integrate` (one
    scipy call per span); meant for checks, not for production.
    """
    from scipy import integrate as si

    surfaces = [as_surface(s) for s in surfaces]
    pts = np.concatenate([np.asarray(s.control_points).reshape(-1, 3) for s in surfaces])
    center = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
    cubature = getattr(si, "cubature", None)
    area = volume = error = 0.0
    for s in surfaces:
        f = _integrand(s, center)
        bu, bv = s.bezier_breakpoints()
        for u0, u1 in zip(bu[:-1], bu[1:]):
            for v0, v1 in zip(bv[:-1], bv[1:]):
                # absolute floor for the flux, which may be near zero on a span: tol x a rough
                # area (midpoint rule on a 4 x 4 grid) x the span's distance from the centre
                mu, mv = np.meshgrid(u0 + (u1 - u0) * (np.arange(4) + 0.5) / 4, v0 + (v1 - v0) * (np.arange(4) + 0.5) / 4)
                rough = f(mu.ravel(), mv.ravel())
                reach = float(np.abs(s.evaluate(mu.ravel(), mv.ravel()) - center).max())
                floor = tol * float(rough[:, 0].mean()) * (u1 - u0) * (v1 - v0) * max(reach, 1e-300)
                if cubature is not None:
                    res = cubature(lambda x: f(x[:, 0], x[:, 1]), [u0, v0], [u1, v1], rtol=tol, atol=floor)
                    a, v = res.estimate
                    error += float(np.abs(res.error).max())
                else:  # scipy < 1.15: nested adaptive quadrature, one point at a time
                    a, ea = si.dblquad(lambda y, x: float(f(np.array([x]), np.array([y]))[0, 0]), u0, u1, v0, v1,
                                       epsabs=floor, epsrel=tol)
                    v, ev = si.dblquad(lambda y, x: float(f(np.array([x]), np.array([y]))[0, 1]), u0, u1, v0, v1,
                                       epsabs=floor, epsrel=tol)
                    error += max(ea, ev)
                area += float(a)
                volume += float(v)
    return area, volume, error
