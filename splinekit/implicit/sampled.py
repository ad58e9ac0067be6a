"""Sampled signed-distance grids: :class:`SampledSDF` and :func:`sample` (from any implicit).

The narrow band (:class:`~splinekit.implicit.narrowband.NarrowBandSDF`) stores only the samples
near the surface; :func:`~splinekit.implicit.frommesh.from_mesh` builds either from a closed mesh.

Grid layout
-----------
A grid holds samples ``values[i, j, k]`` of a signed distance (negative
inside) at the points ``origin + (i, j, k) * spacing`` (``spacing`` is one
positive step per axis, model units), for ``i < nx``, ``j < ny``, ``k < nz``.

Interpolation
-------------
``"linear"``: trilinear, C0, exact for functions linear in each coordinate
(so for every affine function); error ``O(h^2)`` for smooth ``F``.
``"cubic"``: tricubic **Catmull-Rom** (the interpolating cubic whose end
slopes are central differences of the samples), C1, error ``O(h^3)``; at the
grid border the missing outer sample is extrapolated linearly from the two
border ones, so affine functions are reproduced exactly everywhere. Gradients are
the analytic derivatives of the interpolant (piecewise constant-in-one-axis
for trilinear, so discontinuous across cell faces). Outside the grid box the
value is ``F(c) + |p - c|`` with ``c`` the nearest point of the box, and the
gradient its derivative.
"""

from __future__ import annotations

import numpy as np

from .. import limits
from .._validate import as_float_array, as_int
from ..errors import ParameterError, SplineKitError
from ._checks import check_bounds, origin3, spacing3
from .base import Implicit
from .marching import grid_mesh
from .meshing import ImplicitMesh, deviation

__all__ = ["BYTES_PER_GRID_POINT", "MAX_GRID_POINTS", "SampledSDF", "sample"]

MAX_GRID_POINTS = 2**27
"""Largest number of samples a grid may hold (134 million: 1 GiB of float64).
Larger requests raise a ParameterError instead of exhausting memory."""

_CHUNK = 1 << 18  # points per evaluation block (bounds temporary memory)

_INTERPOLATIONS = ("linear", "cubic")

BYTES_PER_GRID_POINT = 64
"""Peak memory per grid sample charged to the memory budget (:mod:`splinekit.limits`):
the float64 values plus the distances, flags, signs and evaluation temporaries of
:func:`~splinekit.implicit.frommesh.from_mesh` (the costliest builder)."""


# -- input checks ---------------------------------------------------------------------------------
def _check_count(shape) -> None:
    count = int(np.prod([int(s) for s in shape], dtype=object))
    if count > MAX_GRID_POINTS:
        raise ParameterError(
            f"a grid of shape {tuple(int(s) for s in shape)} has {count} samples, more than "
            f"MAX_GRID_POINTS = {MAX_GRID_POINTS}; lower the resolution"
        )
    limits.check(count * BYTES_PER_GRID_POINT, f"a grid of shape {tuple(int(s) for s in shape)}")


def _interp_name(interpolation) -> str:
    if interpolation not in _INTERPOLATIONS:
        raise ParameterError(f"interpolation must be one of {_INTERPOLATIONS}, got {interpolation!r}")
    return interpolation


def _grid_layout(lo, hi, resolution):
    """``(shape (3,) ints, spacing (3,))`` covering the box ``lo..hi``.

    ``resolution`` is an int ``n >= 2`` (cubic voxels, ``n`` samples along
    the longest side) or three ints (``n_i`` samples along axis ``i``)."""
    with np.errstate(over="ignore"):
        extent = hi - lo
    if not np.isfinite(extent).all():
        raise ParameterError(f"the box lo={lo.tolist()}, hi={hi.tolist()} is wider than the float range")
    res = np.asarray(resolution, dtype=object) if not np.isscalar(resolution) else None
    if res is None or res.ndim == 0:
        n = as_int(resolution, "resolution", minimum=2)
        _check_count((n, 1, 1))
        longest = float(extent.max())
        if not longest > 0:
            raise ParameterError(f"the box lo={lo.tolist()}, hi={hi.tolist()} has no extent to sample")
        h = longest / (n - 1)
        shape = np.maximum(np.ceil(extent / h - 1e-9).astype(np.int64) + 1, 2)
        spacing = np.full(3, h)
    else:
        if res.shape != (3,):
            raise ParameterError(f"resolution must be an int or 3 ints, got {resolution!r}")
        shape = np.array([as_int(r, f"resolution[{i}]", minimum=2) for i, r in enumerate(res)], dtype=np.int64)
        flat = np.flatnonzero(~(extent > 0))
        if flat.size:
            raise ParameterError(f"the box has no extent along axis {int(flat[0])} (lo = hi = {lo[flat[0]]!r})")
        spacing = extent / (shape - 1)
    _check_count(shape)
    return shape, spacing


# -- Catmull-Rom weights ------------------------------------------------------------------------------
def _cr_weights(t):
    """Catmull-Rom weights ``(n, 4)`` of samples -1, 0, 1, 2 at ``t`` in [0, 1], and their t-derivatives."""
    t2, t3 = t * t, t * t * t
    w = np.stack([(-t3 + 2 * t2 - t), (3 * t3 - 5 * t2 + 2), (-3 * t3 + 4 * t2 + t), (t3 - t2)], axis=1) * 0.5
    dw = np.stack([(-3 * t2 + 4 * t - 1), (9 * t2 - 10 * t), (-9 * t2 + 8 * t + 1), (3 * t2 - 2 * t)], axis=1) * 0.5
    return w, dw


# -- the dense grid -----------------------------------------------------------------------------------
class SampledSDF(Implicit):
    """A signed distance sampled on a regular grid, interpolated between samples.

    Parameters
    ----------
    values : (nx, ny, nz) array
        Samples (model units, negative inside), each axis at least 2 long, finite.
    origin : (3,)
        Position of sample ``[0, 0, 0]``.
    spacing : float or (3,)
        Sample step along x, y, z (> 0).
    interpolation : "linear" or "cubic"
        Trilinear or tricubic Catmull-Rom (module notes).

    ``bounds`` is the grid box. The object is immutable; ``values`` is read-only.
    """

    def __init__(self, values, origin, spacing, interpolation: str = "linear"):
        vals = as_float_array(values, "values")
        if vals.ndim != 3 or min(vals.shape) < 2:
            raise ParameterError(f"values must be an (nx, ny, nz) array with every axis >= 2, got shape {vals.shape}")
        _check_count(vals.shape)
        finite = np.isfinite(vals)
        if not finite.all():
            idx = tuple(int(i) for i in np.argwhere(~finite)[0])
            raise ParameterError(f"values{list(idx)} = {vals[idx]!r} is not finite")
        self._grid_setup(np.array(vals, dtype=np.float64, order="C"), vals.shape, origin, spacing, interpolation)

    def _grid_setup(self, values, shape, origin, spacing, interpolation):
        self._origin = origin3(origin)
        self._spacing = spacing3(spacing)
        self._shape = tuple(int(s) for s in shape)
        self._interp = _interp_name(interpolation)
        if values is not None:
            values.setflags(write=False)
        self._values = values
        with np.errstate(over="ignore"):
            hi = self._origin + (np.array(self._shape) - 1) * self._spacing
        if not np.isfinite(hi).all():
            raise ParameterError(
                f"the grid of shape {self._shape} with spacing {self._spacing.tolist()} from origin "
                f"{self._origin.tolist()} reaches beyond the float range"
            )
        super().__init__(bounds=(self._origin, hi), exact=False)
        for a in (self._origin, self._spacing):
            a.setflags(write=False)

    # -- properties ---------------------------------------------------------------------------
    @property
    def values(self) -> np.ndarray:
        """The samples ``(nx, ny, nz)`` (read-only)."""
        return self._values

    @property
    def origin(self) -> np.ndarray:
        return self._origin

    @property
    def spacing(self) -> np.ndarray:
        """``(3,)`` sample steps in model units."""
        return self._spacing

    @property
    def shape(self) -> tuple:
        return self._shape

    @property
    def interpolation(self) -> str:
        return self._interp

    def points(self) -> np.ndarray:
        """The sample positions ``(nx, ny, nz, 3)``."""
        axes = [self._origin[i] + np.arange(self._shape[i]) * self._spacing[i] for i in range(3)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    def with_interpolation(self, interpolation: str) -> SampledSDF:
        """The same samples with another interpolation."""
        return SampledSDF(self._values, self._origin, self._spacing, interpolation)

    def __repr__(self):
        return (
            f"{type(self).__name__}(shape={self._shape}, origin={self._origin.tolist()}, "
            f"spacing={self._spacing.tolist()}, interpolation={self._interp!r})"
        )

    # -- sample access (overridden by the narrow band) -------------------------------------------------------
    def _grid_gather(self, i, j, k):
        return self._values[i, j, k]

    # -- evaluation -----------------------------------------------------------------------------
    def _grid_split(self, p):
        """Grid coordinates clamped into the box, and the outside offset ``p - c`` (model units)."""
        n = np.asarray(self._shape, dtype=np.float64)
        u = (p - self._origin) / self._spacing
        uc = np.clip(u, 0.0, n - 1.0)
        out = (u - uc) * self._spacing
        return uc, out

    def _grid_eval(self, p, want_grad):
        values = np.empty(len(p))
        grads = np.empty((len(p), 3)) if want_grad else None
        for s in range(0, len(p), _CHUNK):
            sl = slice(s, s + _CHUNK)
            uc, out = self._grid_split(p[sl])
            f, g = (self._grid_linear if self._interp == "linear" else self._grid_cubic)(uc, want_grad)
            dist = np.sqrt(np.einsum("ij,ij->i", out, out))
            values[sl] = f + dist
            if want_grad:
                g = g / self._spacing
                outside = dist > 0
                if outside.any():
                    # along a clamped axis the interpolant is constant and |p - c| grows
                    o = out[outside] / dist[outside, None]
                    g[outside] = np.where(out[outside] != 0, o, g[outside])
                grads[sl] = g
        return values, grads

    def _grid_cells(self, uc):
        n = np.asarray(self._shape)
        i0 = np.minimum(np.floor(uc).astype(np.int64), n - 2)
        return i0, uc - i0

    def _grid_linear(self, uc, want_grad):
        i0, t = self._grid_cells(uc)
        c = np.empty((len(uc), 2, 2, 2))
        for a in (0, 1):
            for b in (0, 1):
                for d in (0, 1):
                    c[:, a, b, d] = self._grid_gather(i0[:, 0] + a, i0[:, 1] + b, i0[:, 2] + d)
        w = [np.stack([1 - t[:, ax], t[:, ax]], axis=1) for ax in range(3)]
        f = np.einsum("nabc,na,nb,nc->n", c, w[0], w[1], w[2])
        if not want_grad:
            return f, None
        dw = np.array([-1.0, 1.0])
        g = np.stack(
            [
                np.einsum("nabc,a,nb,nc->n", c, dw, w[1], w[2]),
                np.einsum("nabc,na,b,nc->n", c, w[0], dw, w[2]),
                np.einsum("nabc,na,nb,c->n", c, w[0], w[1], dw),
            ],
            axis=1,
        )
        return f, g

    def _grid_cubic(self, uc, want_grad):
        i0, t = self._grid_cells(uc)
        n = np.asarray(self._shape)
        off = np.arange(-1, 3)
        idx = [np.clip(i0[:, ax, None] + off, 0, n[ax] - 1) for ax in range(3)]  # (m, 4) each
        c = self._grid_gather(idx[0][:, :, None, None], idx[1][:, None, :, None], idx[2][:, None, None, :])
        # beyond the border the missing sample is extrapolated linearly (a tensor
        # product, so one axis after the other), which keeps affine functions exact
        for ax in range(3):
            cm = np.moveaxis(c, ax + 1, 1)  # a view: writes go to c
            lo = i0[:, ax] == 0
            if lo.any():
                cm[lo, 0] = 2.0 * cm[lo, 1] - cm[lo, 2]
            hi = i0[:, ax] == n[ax] - 2
            if hi.any():
                cm[hi, 3] = 2.0 * cm[hi, 2] - cm[hi, 1]
        ws = [_cr_weights(t[:, ax]) for ax in range(3)]
        (w0, d0), (w1, d1), (w2, d2) = ws
        f = np.einsum("nabc,na,nb,nc->n", c, w0, w1, w2)
        if not want_grad:
            return f, None
        g = np.stack(
            [
                np.einsum("nabc,na,nb,nc->n", c, d0, w1, w2),
                np.einsum("nabc,na,nb,nc->n", c, w0, d1, w2),
                np.einsum("nabc,na,nb,nc->n", c, w0, w1, d2),
            ],
            axis=1,
        )
        return f, g

    def _value(self, p):
        return self._grid_eval(p, False)[0]

    def _gradient(self, p):
        return self._grid_eval(p, True)[1]

    def _value_gradient(self, p):
        return self._grid_eval(p, True)

    # -- meshing ----------------------------------------------------------------------------------
    def _grid_dense(self) -> np.ndarray:
        return self._values

    def to_mesh(self, edge_length=None, bounds=None):
        """The zero set as a closed, outward-oriented triangle mesh.

        With ``edge_length`` and ``bounds`` None (the default) the mesh comes
        straight from the samples (:func:`~splinekit.implicit.marching.grid_mesh`:
        marching tetrahedra on the grid, the zero set of the piecewise-linear
        interpolant on the Kuhn triangulation of each cell; no resampling).
        With an ``edge_length`` (or ``bounds``) it is the base class's
        meshing of the interpolant resampled for that edge length
        (:func:`~splinekit.implicit.meshing.mesh_implicit`). Either way the result is an
        :class:`~splinekit.implicit.meshing.ImplicitMesh` whose ``deviation``
        is measured against this grid's interpolant.
        """
        if edge_length is None and bounds is None:
            mesh = grid_mesh(self._grid_dense(), self._origin, self._spacing)
            V = np.asarray(mesh.vertices)
            dev = deviation(self, V, np.asarray(mesh.faces).reshape(-1, 3))
            return ImplicitMesh.of_topology(V, mesh.topology, dev, float(self._spacing.max()))
        if edge_length is None:
            edge_length = float(self._spacing.min())
        return super().to_mesh(edge_length, bounds)


# -- sampling any implicit --------------------------------------------------------------------------------
def _evaluate(F, pts):
    try:
        out = np.asarray(F(pts), dtype=np.float64)
    except SplineKitError:
        raise
    except Exception as exc:  # a user function failing is reported, not re-raised raw
        raise ParameterError(f"the implicit raised {type(exc).__name__}: {exc}") from exc
    if out.shape != (len(pts),):
        raise ParameterError(f"the implicit must return shape ({len(pts)},) for {len(pts)} points, got {out.shape}")
    if not np.isfinite(out).all():
        i = int(np.argmax(~np.isfinite(out)))
        raise ParameterError(f"the implicit is not finite at {pts[i].tolist()}")
    return out


def sample(implicit, bounds, resolution, *, interpolation: str = "linear") -> SampledSDF:
    """Sample ``implicit`` on a regular grid over ``bounds``.

    Parameters
    ----------
    implicit : Implicit or callable
        Called once per block of up to 262144 points ``(n, 3)`` -> ``(n,)``.
    bounds : (lo (3,), hi (3,))
        The box to cover (model units).
    resolution : int or (3,) ints
        An int ``n >= 2``: cubic voxels with ``n`` samples along the longest
        side (the grid may overhang ``hi`` by less than a voxel on the other
        axes); three ints: that many samples per axis spanning the box exactly.
    interpolation : "linear" or "cubic"

    Returns
    -------
    SampledSDF
    """
    if not callable(implicit):
        raise ParameterError(f"implicit must be callable on (n, 3) points, got {type(implicit).__name__}")
    box = check_bounds(bounds)
    if box is None:
        raise ParameterError("bounds are required to sample an implicit")
    _interp_name(interpolation)
    shape, spacing = _grid_layout(box[0], box[1], resolution)
    origin = np.asarray(box[0], dtype=np.float64)
    total = int(np.prod(shape))
    out = np.empty(total)
    ny, nz = int(shape[1]), int(shape[2])
    for s in range(0, total, _CHUNK):
        flat = np.arange(s, min(s + _CHUNK, total))
        ijk = np.stack([flat // (ny * nz), (flat // nz) % ny, flat % nz], axis=1)
        out[s : s + len(flat)] = _evaluate(implicit, origin + ijk * spacing)
    return SampledSDF(out.reshape(tuple(shape)), origin, spacing, interpolation)
