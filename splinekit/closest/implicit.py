"""Projection onto implicit surfaces: a gradient iteration onto the zero set
``F = 0`` (one step for a true signed-distance function)."""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array
from ..errors import ConvergenceError, ParameterError
from ..tolerances import GEOMETRIC_CONFUSION
from .queries import Projection, _as_query_points, _positive_tolerance, _readonly

IMPLICIT_ITERATIONS = 100


class _Implicit:
    """Adapter for a callable implicit ``F`` with ``gradient``."""

    def __init__(self, f):
        self.f = f

    def _values(self, q, idx):
        F = np.asarray(as_float_array(self.f(q), "implicit values", ParameterError)).reshape(-1)
        if F.shape != (q.shape[0],):
            raise ParameterError(f"the implicit returned {F.size} values for {q.shape[0]} points; expected one per point")
        bad = ~np.isfinite(F)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ConvergenceError(f"the implicit is not finite ({F[i]!r}) at the iterate of point {int(idx[i])}")
        return F

    def project(self, points, tolerance):
        P = as_float_array(points, "points", ParameterError)
        if P.ndim == 0:
            raise ParameterError(f"points must have shape (n, dim), got a scalar {points!r}")
        lead, dim = P.shape[:-1], P.shape[-1]
        P, _ = _as_query_points(P, dim)
        if tolerance is None:
            tol = GEOMETRIC_CONFUSION * max(1.0, float(np.abs(P).max(initial=0.0)))
        else:
            tol = _positive_tolerance(tolerance)
        if callable(getattr(self.f, "closest_points", None)) and dim == 3:
            # splinekit.implicit objects know their own structure (CSG seams
            # need a crease step a plain gradient iteration lacks)
            q = np.asarray(self.f.closest_points(P, tol=tol), dtype=np.float64).reshape(P.shape)
            dist = np.linalg.norm(q - P, axis=1)
            return Projection(None, _readonly(q.reshape(lead + (dim,))), _readonly(dist.reshape(lead)))
        q = P.copy()
        active = np.arange(P.shape[0])
        for _ in range(IMPLICIT_ITERATIONS + 1):
            if active.size == 0:
                break
            qa = q[active]
            F = self._values(qa, active)
            done = np.abs(F) <= tol
            active, qa, F = active[~done], qa[~done], F[~done]
            if active.size == 0:
                break
            grad = as_float_array(self.f.gradient(qa), "implicit gradient", ParameterError)
            if grad.shape != qa.shape:
                raise ParameterError(f"the implicit's gradient has shape {grad.shape}, expected {qa.shape}")
            gg = np.einsum("md,md->m", grad, grad)
            zero = ~(np.isfinite(gg) & (gg > 0))
            if zero.any():
                i = int(np.flatnonzero(zero)[0])
                raise ConvergenceError(
                    f"the implicit's gradient vanishes (or is not finite) at the iterate {qa[i].tolist()} "
                    f"of point {int(active[i])}; the closest point is undefined there"
                )
            with np.errstate(over="ignore", invalid="ignore"):
                qn = qa - (F / gg)[:, None] * grad
            if not np.isfinite(qn).all():
                i = int(np.flatnonzero(~np.isfinite(qn).all(axis=1))[0])
                raise ConvergenceError(f"the projection of point {int(active[i])} onto the implicit diverged")
            q[active] = qn
        else:
            i = int(active[0])
            raise ConvergenceError(
                f"projection of point {i} onto the implicit did not reach |F| <= {tol:.3g} in "
                f"{IMPLICIT_ITERATIONS} steps (|F| = {float(abs(F[0])):.3g})"
            )
        dist = np.linalg.norm(q - P, axis=1)
        return Projection(None, _readonly(q.reshape(lead + (dim,))), _readonly(dist.reshape(lead)))
