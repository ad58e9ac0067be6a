"""Fourth-order central finite differences on a 5-point stencil, for the
surface adapters of :mod:`.protocol` and :class:`~.implicit_surface.ImplicitSurface`
(the error model is in :mod:`.protocol`)."""

from __future__ import annotations

import numpy as np

from ..errors import DomainError, ParameterError, SplineKitError

__all__ = ["numeric_derivatives"]

# fourth-order central first difference on offsets -2..2 (divide by h)
_D1 = np.array([1.0, -8.0, 0.0, 8.0, -1.0]) / 12.0
# fourth-order central second difference on offsets -2..2 (divide by h^2)
_D2 = np.array([-1.0, 16.0, -30.0, 16.0, -1.0]) / 12.0
_OFFSETS = np.arange(-2, 3, dtype=np.float64)


def _call_points(f, u, v, what):
    """``f(u, v)`` for flat arrays, checked to return finite ``(n, dim)``."""
    try:
        out = np.asarray(f(u, v), dtype=np.float64)
    except SplineKitError:
        raise
    except Exception as exc:  # a user function failing is reported, not re-raised raw
        raise ParameterError(f"{what} raised {type(exc).__name__}: {exc}") from exc
    if out.ndim != 2 or out.shape[0] != u.size:
        raise ParameterError(f"{what} must return an (n, dim) array for n = {u.size} parameter pairs, got shape {out.shape}")
    if not np.isfinite(out).all():
        bad = int(np.argwhere(~np.isfinite(out))[0, 0])
        raise DomainError(f"{what} is not finite at (u, v) = ({u[bad]!r}, {v[bad]!r})")
    return out


def numeric_derivatives(f, u, v, order: int, hu: float, hv: float) -> np.ndarray:
    """Partials of ``f`` up to ``order`` (at most 2) by fourth-order central
    differences: ``(order + 1, order + 1, n, dim)`` for flat ``u``, ``v`` of
    length ``n``. One vectorized call of ``f`` on all stencil points."""
    n = u.size
    if order > 2:
        raise ParameterError(f"numeric derivatives go up to order 2, got order={order}; pass analytic derivatives")
    # sample the 5 x 5 stencil (only the cross is needed for order <= 1)
    iu, iv = np.meshgrid(np.arange(5), np.arange(5), indexing="ij")
    if order < 2:
        keep = (iu == 2) | (iv == 2)
        iu, iv = iu[keep], iv[keep]
    iu, iv = iu.ravel(), iv.ravel()
    uu = u[:, None] + _OFFSETS[iu][None, :] * hu
    vv = v[:, None] + _OFFSETS[iv][None, :] * hv
    vals = _call_points(f, uu.ravel(), vv.ravel(), "the surface function").reshape(n, iu.size, -1)
    grid = np.zeros((n, 5, 5, vals.shape[-1]))
    grid[:, iu, iv] = vals
    out = np.zeros((order + 1, order + 1, n, vals.shape[-1]))
    out[0, 0] = grid[:, 2, 2]
    if order >= 1:
        out[1, 0] = np.einsum("k,nkd->nd", _D1, grid[:, :, 2]) / hu
        out[0, 1] = np.einsum("k,nkd->nd", _D1, grid[:, 2, :]) / hv
    if order >= 2:
        out[2, 0] = np.einsum("k,nkd->nd", _D2, grid[:, :, 2]) / hu**2
        out[0, 2] = np.einsum("k,nkd->nd", _D2, grid[:, 2, :]) / hv**2
        out[1, 1] = np.einsum("k,l,nkld->nd", _D1, _D1, grid) / (hu * hv)
    return out
