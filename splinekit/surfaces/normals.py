"""Unit normals of spline surfaces in 3-D, pointwise and on grids, including
the limit normals at collapsed edges (poles) where ``Su x Sv`` vanishes.

:class:`SurfaceNormals` is a mixin of :class:`~splinekit.surfaces.bspline.SplineSurface`.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_params
from .. import _kernels
from ..errors import ParameterError

__all__ = ["SurfaceNormals"]


class SurfaceNormals:
    """Normals (a mixin: it needs ``derivatives``, the grid helpers of
    :class:`~splinekit.surfaces.grid.SurfaceGrids`, ``domain`` and ``dim``)."""

    __slots__ = ()

    @staticmethod
    def _cross(a, b):
        """Row-wise cross product of ``(..., 3)`` arrays (cheaper than np.cross here)."""
        out = np.empty(np.broadcast_shapes(a.shape, b.shape))
        out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
        out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
        out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
        return out

    def _partial_noise(self) -> float:
        """Length below which a first partial derivative is round-off, not geometry (model units
        per parameter unit): a partial sums (degree / span) times control-point differences, each
        rounded to about ``eps`` of the net's size, so a partial that vanishes exactly (along a
        collapsed edge, or an iso-line whose control points coincide) comes out at that size."""
        coefs = self._coefs
        size = float(np.abs(coefs).max())
        if self._rational:
            size /= float(coefs[..., -1].min())
        rate = max(self._pu / float(np.diff(np.unique(self._ku)).min()),
                   self._pv / float(np.diff(np.unique(self._kv)).min()))
        return 64.0 * np.finfo(float).eps * size * rate

    def _normalize(self, n, Su, Sv, u, v, w=1.0):
        """Unit normals from ``n = Su x Sv`` (any positive multiple of it); ``Su`` and ``Sv``
        may be scaled by a common positive factor ``w`` per point (the homogeneous weight).

        Where ``Su x Sv`` (nearly) vanishes, at a collapsed edge such as the
        pole of a revolved sphere, or where a partial is round-off (:meth:`_partial_noise`),
        the limit direction ``Su x Suv + Suv x Sv`` is used, oriented like the normal at a
        point just inside the domain.
        """
        length = np.sqrt(np.einsum("...i,...i->...", n, n))
        lu = np.sqrt(np.einsum("...i,...i->...", Su, Su))
        lv = np.sqrt(np.einsum("...i,...i->...", Sv, Sv))
        weak = (length <= 1e-10 * (lu + lv) ** 2) | (np.minimum(lu, lv) <= self._partial_noise() * w)
        if weak.any():
            n = n.copy()
            n[weak] = self._limit_normals(u[weak], v[weak])
            length = np.sqrt(np.einsum("...i,...i->...", n, n))
        return np.divide(n, length[..., None], out=np.zeros_like(n), where=length[..., None] > 0)

    def _limit_normals(self, u, v):
        """Normals at degenerate points (``Su x Sv = 0``): see :meth:`_normalize`."""
        d = self.derivatives(u, v, 1)
        Su, Sv, Suv = d[1, 0], d[0, 1], d[1, 1]
        alt = self._cross(Su, Suv) + self._cross(Suv, Sv)
        (a, b), (c, e) = self.domain
        du, dv = 1e-7 * (b - a), 1e-7 * (e - c)
        un = np.where(u + du <= b, u + du, u - du)
        vn = np.where(v + dv <= e, v + dv, v - dv)
        near = self.derivatives(un, vn, 1)
        ref = self._cross(near[1, 0], near[0, 1])
        flip = np.einsum("...i,...i->...", alt, ref) < 0
        alt[flip] *= -1.0
        tiny = np.linalg.norm(alt, axis=-1) <= 1e-14 * (np.linalg.norm(ref, axis=-1) + 1e-300)
        alt[tiny] = ref[tiny]
        return alt

    def _require_3d(self):
        if self.dim != 3:
            raise ParameterError(f"normals need a surface in 3-D space, this one has dim={self.dim}")

    def normal(self, u, v) -> np.ndarray:
        """Unit normals ``(Su x Sv) / |Su x Sv|`` at the pairs ``(u, v)``: ``u.shape + (3,)``."""
        self._require_3d()
        u, v = self._uv(u, v)
        s = self._unit_sized()
        d = s.derivatives(u, v, 1)
        return s._normalize(s._cross(d[1, 0], d[0, 1]), d[1, 0], d[0, 1], u, v)

    def _unit_sized(self):
        """This surface, or for coordinates beyond ``2**300`` a copy scaled by a power of two
        to size about 1: normals do not depend on the scale, and ``Su x Sv`` of a huge
        surface would overflow."""
        big = float(np.abs(self.control_points).max())
        return self if big < 2.0**300 else self._scaled(-int(np.frexp(big)[1]))

    def normal_grid(self, us, vs) -> np.ndarray:
        """Unit normals on the grid ``us x vs``: ``(len(us), len(vs), 3)``.

        Uses only the homogeneous value and first partials; for a rational
        surface ``Su x Sv`` is a positive multiple of
        ``(Au - wu C) x (Av - wv C)``, so no full quotient rule is needed.
        """
        self._require_3d()
        if self._unit_sized() is not self:
            return self._unit_sized().normal_grid(us, vs)
        (su, Nu), (sv, Nv) = self._grid_basis(us, vs, 1)
        jit = _kernels.load("splinekit.basis._numba_kernels", work=su.size * sv.size // 2)  # a grid normal: half a curve point
        if jit is not None:
            out = np.empty((su.size, sv.size, 3))
            weak = np.empty((su.size, sv.size), dtype=np.bool_)
            jit.grid_normals4(self._coefs4(), su, np.ascontiguousarray(Nu), self._pu, sv, np.ascontiguousarray(Nv),
                              self._pv, self._rational, self._partial_noise(), out, weak)
            if weak.any():
                (du, dv) = self.domain
                U, V = np.meshgrid(as_params(us, du, "us").ravel(), as_params(vs, dv, "vs").ravel(), indexing="ij")
                n = self._limit_normals(U[weak], V[weak])
                out[weak] = n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
            return out
        Hu = self._grid_contract(su, Nu[1], sv, Nv[0], False)
        Hv = self._grid_contract(su, Nu[0], sv, Nv[1], False)
        w = 1.0
        if self._rational:
            H = self._grid_contract(su, Nu[0], sv, Nv[0], False)
            w = H[..., 3]
            C = H[..., :3] / H[..., 3:]
            Su = Hu[..., :3] - Hu[..., 3:] * C  # w Su
            Sv = Hv[..., :3] - Hv[..., 3:] * C  # w Sv
        else:
            Su, Sv = Hu, Hv
        (du, dv) = self.domain
        U, V = np.meshgrid(as_params(us, du, "us").ravel(), as_params(vs, dv, "vs").ravel(), indexing="ij", sparse=True)
        U, V = np.broadcast_arrays(U, V)
        return self._normalize(self._cross(Su, Sv), Su, Sv, U, V, w)
