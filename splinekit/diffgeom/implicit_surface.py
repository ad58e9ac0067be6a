"""Implicit surfaces ``F(x, y, z) = 0``: the point-based counterpart of the
parametric-surface protocol (:mod:`.protocol`), callable on ``(n, 3)`` points,
with ``gradient``, ``hessian`` and unit normals."""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, as_real
from ..errors import DomainError, ParameterError, SplineKitError
from ..tolerances import FD_STEP
from .differences import _D1, _OFFSETS

__all__ = ["ImplicitSurface"]


class ImplicitSurface:
    """The zero set of ``F(x, y, z)``.

    Parameters
    ----------
    F : callable
        ``F(points)`` with ``points`` ``(n, 3)`` returns ``(n,)``.
    gradient : callable, optional
        ``(n, 3)`` -> ``(n, 3)``; otherwise fourth-order central differences
        with step ``step * scale`` (scale 1: coordinates are in model units).
    hessian : callable, optional
        ``(n, 3)`` -> ``(n, 3, 3)``; otherwise differences of the gradient.

    The unit normal is ``grad F / |grad F|``: outward for a signed distance
    function (negative inside).
    """

    def __init__(self, F, gradient=None, hessian=None, step: float = FD_STEP):
        for name, g in (("F", F), ("gradient", gradient), ("hessian", hessian)):
            if g is not None and not callable(g):
                raise ParameterError(f"{name} must be callable, got {type(g).__name__}")
        if not callable(F):
            raise ParameterError("F must be callable")
        step = as_real(step, "step")
        if not step > 0:
            raise ParameterError(f"step must be positive, got {step!r}")
        self._F, self._grad, self._hess, self.step = F, gradient, hessian, step

    def __repr__(self):
        return f"ImplicitSurface({getattr(self._F, '__name__', 'F')})"

    @staticmethod
    def _points(points) -> np.ndarray:
        p = as_float_array(points, "points")
        if p.ndim == 1 and p.shape[0] == 3:
            p = p[None, :]
        if p.ndim != 2 or p.shape[1] != 3:
            raise ParameterError(f"points must be an (n, 3) array, got shape {p.shape}")
        if not np.isfinite(p).all():
            raise ParameterError(f"point {int(np.argwhere(~np.isfinite(p))[0, 0])} has non-finite coordinates")
        return p

    def _call(self, g, p, shape, name):
        try:
            out = np.asarray(g(p), dtype=np.float64)
        except SplineKitError:
            raise
        except Exception as exc:
            raise ParameterError(f"{name} raised {type(exc).__name__}: {exc}") from exc
        if out.shape != (len(p),) + shape:
            raise ParameterError(f"{name} must return shape {(len(p),) + shape}, got {out.shape}")
        if not np.isfinite(out).all():
            bad = int(np.argwhere(~np.isfinite(out.reshape(len(p), -1)))[0, 0])
            raise DomainError(f"{name} is not finite at point {bad} {p[bad].tolist()}")
        return out

    def __call__(self, points) -> np.ndarray:
        """``F`` at ``(n, 3)`` points: ``(n,)``."""
        return self._call(self._F, self._points(points), (), "F")

    def gradient(self, points) -> np.ndarray:
        """``grad F`` at ``(n, 3)`` points: ``(n, 3)``."""
        p = self._points(points)
        if self._grad is not None:
            return self._call(self._grad, p, (3,), "gradient")
        return self._central(lambda q: self._call(self._F, q, (), "F")[:, None], p)[..., 0]

    def hessian(self, points) -> np.ndarray:
        """The Hessian of ``F`` at ``(n, 3)`` points: ``(n, 3, 3)`` (symmetrized)."""
        p = self._points(points)
        if self._hess is not None:
            H = self._call(self._hess, p, (3, 3), "hessian")
        else:
            H = self._central(self.gradient, p)  # [n, axis j, component i] = d(grad_i)/dx_j
        return 0.5 * (H + np.swapaxes(H, 1, 2))

    def normal(self, points) -> np.ndarray:
        """Unit normals ``grad F / |grad F|``: ``(n, 3)``; a vanishing gradient
        raises :class:`~splinekit.errors.DomainError` naming the point."""
        p = self._points(points)
        g = self.gradient(p)
        return g / _nonzero_norm(g, p, "gradient")[:, None]

    def _central(self, g, p):
        """Fourth-order central differences of ``g`` along x, y, z: ``(n, 3, k)``."""
        h = self.step
        n = len(p)
        shifts = _OFFSETS[None, :, None] * h * np.eye(3)[:, None, :]  # (3 axes, 5 offsets, 3)
        q = (p[:, None, None, :] + shifts[None]).reshape(-1, 3)
        vals = np.asarray(g(q))
        vals = vals.reshape(n, 3, 5, vals.shape[-1])  # [point, axis, offset, component]
        return np.einsum("j,najk->nak", _D1, vals) / h


def _nonzero_norm(g, p, what):
    """``|g|`` per row, refusing zeros (they would make the normal undefined)."""
    length = np.linalg.norm(g, axis=-1)
    scale = max(1.0, float(np.max(np.abs(g)))) if g.size else 1.0
    bad = ~(length > 1e-14 * scale)
    if bad.any():
        i = int(np.argmax(bad))
        raise DomainError(f"the {what} vanishes at point {i} {p[i].tolist()}: the normal is undefined there")
    return length
