"""Curves and surfaces as the projection sees them: a parameter box, the smooth
pieces between creases, samples about evenly spaced in space, Newton seeds from
a k-d tree of the samples, and derivatives in search units.

Any object with ``evaluate``, ``derivatives`` and a domain works; knots,
degrees and ``bezier_breakpoints`` are used when the geometry has them.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import as_float_array, as_params
from ..basis.knots import distinct
from ..errors import ParameterError
from ..tolerances import GEOMETRIC_CONFUSION
from .queries import _positive_tolerance

SEEDS_PER_POINT = 3
"""Newton seeds kept per point: the nearest samples that are local minima of the sampled distance."""

EXTRA_SEEDS = 1
"""Further seeds per point: the nearest samples not already chosen."""

NEIGHBOURS_QUERIED = 12
"""Nearest samples fetched from the k-d tree per point, among which seeds are chosen."""

SURFACE_SAMPLES = 2
"""Samples per Bézier span and direction of a surface, per unit of degree."""

CURVE_SAMPLES = 1000
"""Target number of (about equally spaced in space) samples along a curve."""

SURFACE_SPACING = 150
"""Target number of sample intervals along each direction of a surface, spaced evenly in space."""

MAX_SAMPLES_PER_DIRECTION = 600
"""Cap on the sample count along one parameter direction (many-span geometry)."""

LARGE = 1e60
"""Geometry larger than this, or smaller than its inverse (largest sample
coordinate), is searched in scaled units."""


def _domain_pair(value, name: str):
    pair = as_float_array(value, name, ParameterError)
    if pair.shape != (2,) or not np.isfinite(pair).all() or not pair[0] < pair[1]:
        raise ParameterError(f"{name} must be a finite interval (a, b) with a < b, got {value!r}")
    return float(pair[0]), float(pair[1])


def _span_samples(breaks: np.ndarray, per_span: int) -> np.ndarray:
    """Increasing parameters: ``per_span`` equal steps in every span between ``breaks``."""
    per_span = max(2, min(per_span, MAX_SAMPLES_PER_DIRECTION // max(1, breaks.size - 1)))
    t = np.linspace(0.0, 1.0, per_span + 1)[:-1]
    inner = (breaks[:-1, None] + np.diff(breaks)[:, None] * t[None, :]).ravel()
    return np.append(inner, breaks[-1])


def _refined(params: np.ndarray, lengths: np.ndarray, target: int) -> np.ndarray:
    """``params`` with every interval split into equal pieces so that each piece
    spans about ``sum(lengths) / target`` in space (``lengths`` are the chord
    lengths of the intervals). Existing parameters are kept exactly."""
    total = float(lengths.sum())
    if not np.isfinite(total) or total <= 0:
        return params
    pieces = np.clip(np.ceil(lengths * (target / total)), 1, target).astype(np.intp)
    start = np.repeat(params[:-1], pieces)
    step = np.repeat(np.diff(params) / pieces, pieces)
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    k = np.arange(start.size) - first
    return np.append(start + k * step, params[-1])


def _breakpoints(knots, lo: float, hi: float) -> np.ndarray:
    """Distinct span ends in ``[lo, hi]``; 16 equal pieces when the geometry has no knots."""
    if knots is None:
        return np.linspace(lo, hi, 17)
    b = np.asarray(knots, dtype=np.float64)
    b = b[(b >= lo) & (b <= hi)]
    return np.unique(np.concatenate([[lo, hi], b]))


def _crease_breaks(knots, degree: int, lo: float, hi: float) -> np.ndarray:
    """``[lo, c_1, ..., hi]``: the domain ends and the interior knots of multiplicity
    >= ``degree``, where the geometry may be only C0."""
    if knots is None:
        return np.array([lo, hi])
    values, counts = distinct(np.asarray(knots, dtype=np.float64))
    inner = values[(values > lo) & (values < hi) & (counts >= degree)]
    return np.concatenate([[lo], inner, [hi]])


class _Parametric:
    """Shared seeding logic of :class:`_Curve` and :class:`_Surface`."""

    n_params: int
    lo: np.ndarray
    hi: np.ndarray
    grid_shape: tuple
    sample_params: np.ndarray  # (S, k)
    sample_points: np.ndarray  # (S, dim)

    def _finish_samples(self, params, pts):
        pts = np.asarray(pts, dtype=np.float64).reshape(params.shape[0], -1)
        if not np.isfinite(pts).all():
            raise ParameterError(f"the {type(self.geometry).__name__} evaluates to non-finite points")
        extent = float(np.abs(pts).max())
        # very large or very small geometry is searched in units of a power of two
        # (exact): the Newton system multiplies squared lengths, which would
        # overflow, or underflow to zero distances
        far_scale = extent > LARGE or 0.0 < extent < 1.0 / LARGE
        self.unit = 2.0 ** math.floor(math.log2(extent)) if far_scale else 1.0
        self.sample_params = params
        self.sample_points = pts / self.unit
        self.dim = pts.shape[1]
        self.size = max(1.0, extent / self.unit)

    def boxes(self, piece):
        """Lower and upper bounds ``(m, k)`` of the smooth pieces ``piece`` ``(m, k)``."""
        lo = np.column_stack([br[piece[:, j]] for j, br in enumerate(self.breaks)])
        hi = np.column_stack([br[piece[:, j] + 1] for j, br in enumerate(self.breaks)])
        return lo, hi

    def tolerance(self, tolerance) -> float:
        """The stopping distance in search units (model units / ``unit``)."""
        if tolerance is None:
            return GEOMETRIC_CONFUSION * self.size
        return _positive_tolerance(tolerance) / self.unit

    def _neighbour_offsets(self):
        """Flat-index offsets of the grid neighbours and a validity test per offset."""
        if self.n_params == 1:
            return [(-1, None), (1, None)]
        nv = self.grid_shape[1]
        return [(-nv, None), (nv, None), (-1, 0), (1, nv - 1)]

    def seeds(self, P: np.ndarray):
        """``(owner (m,), x0 (m, k))``: the Newton seeds of every point.

        The k-d tree yields each point's nearest samples; those that are local
        minima of the sampled distance over the parameter grid (no grid
        neighbour is nearer) are kept, nearest first, at most
        :data:`SEEDS_PER_POINT` per point; the nearest sample is always kept.
        :data:`EXTRA_SEEDS` more of the nearest samples are added, since two
        local minima of the distance can share a sample cell and a neighbour of
        the better one may be its only seed.
        """
        from scipy.spatial import cKDTree

        if not hasattr(self, "_tree"):
            self._tree = cKDTree(self.sample_points)
        X = self.sample_points
        S = X.shape[0]
        kq = min(NEIGHBOURS_QUERIED, S)
        d, idx = self._tree.query(P, k=kq)
        d = d.reshape(P.shape[0], kq)
        idx = idx.reshape(P.shape[0], kq)
        keep = np.ones(idx.shape, dtype=bool)
        nv = self.grid_shape[-1]
        for off, edge in self._neighbour_offsets():
            nb = idx + off
            valid = (nb >= 0) & (nb < S)
            if edge is not None:  # neighbours along v must stay in the same grid row
                valid &= (idx % nv) != edge
            nbc = np.where(valid, nb, idx)
            dn = np.sqrt(np.einsum("mkd,mkd->mk", X[nbc] - P[:, None], X[nbc] - P[:, None]))
            keep &= ~valid | (d <= dn)
        keep[:, 0] = True
        keep &= np.cumsum(keep, axis=1) <= SEEDS_PER_POINT
        extra = ~keep & (np.cumsum(~keep, axis=1) <= EXTRA_SEEDS)
        keep |= extra
        owner, col = np.nonzero(keep)
        return owner, self.sample_params[idx[owner, col]].copy()

    def user_seeds(self, seeds, n: int, lead: tuple):
        k = self.n_params
        arr = as_float_array(seeds, "seeds", ParameterError)
        flat_lead = int(np.prod(lead, dtype=np.int64)) if lead else 1
        core = arr.shape[: len(lead)]
        rest = arr.shape[len(lead):]
        expected = "(n,) or (n, k)" if k == 1 else "(n, 2) or (n, k, 2)"
        ok = core == lead and (
            (k == 1 and len(rest) <= 1) or (k == 2 and len(rest) in (1, 2) and rest[-1] == 2)
        )
        if not ok or arr.size == 0:
            raise ParameterError(f"seeds must have shape {expected} for {n} points, got {arr.shape}")
        arr = arr.reshape(flat_lead, -1, k)
        cols = []
        for j in range(k):
            a, b = self.lo[j], self.hi[j]
            cols.append(as_params(arr[..., j], (a, b), "seeds" if k == 1 else f"seeds[..., {j}]"))
        x0 = np.stack(cols, axis=-1)
        owner = np.repeat(np.arange(flat_lead), x0.shape[1])
        return owner, x0.reshape(-1, k)


class _Curve(_Parametric):
    n_params = 1

    def __init__(self, geometry, dom):
        self.geometry = geometry
        a, b = _domain_pair(dom, "domain")
        self.lo, self.hi = np.array([a]), np.array([b])
        bp = getattr(geometry, "bezier_breakpoints", None)
        breaks = _breakpoints(bp() if callable(bp) else None, a, b)
        p = int(getattr(geometry, "degree", 3))
        us = _span_samples(breaks, max(8, 4 * p))
        # a second pass evens out the spacing in space (short spans, high weights)
        pts = np.asarray(geometry.evaluate(us), dtype=np.float64).reshape(us.size, -1)
        with np.errstate(invalid="ignore", over="ignore"):
            us = _refined(us, np.linalg.norm(np.diff(pts, axis=0), axis=1), CURVE_SAMPLES)
        self.grid_shape = (us.size,)
        self.breaks = [_crease_breaks(getattr(geometry, "knots", None), p, a, b)]
        self._finish_samples(us[:, None], geometry.evaluate(us))

    def derivs(self, x):
        """``S (m, dim)``, ``J (m, dim, 1)``, second derivatives ``(m, dim, 1, 1)`` at ``x (m, 1)``."""
        d = np.asarray(self.geometry.derivatives(x[:, 0], 2), dtype=np.float64) / self.unit
        return d[0], d[1][..., None], d[2][..., None, None]

    def evaluate(self, x):
        """Points ``(m, dim)`` at ``x (m, 1)``."""
        return np.asarray(self.geometry.evaluate(x[:, 0]), dtype=np.float64).reshape(x.shape[0], -1) / self.unit


class _Surface(_Parametric):
    n_params = 2

    def __init__(self, geometry, dom):
        self.geometry = geometry
        dom = list(dom)
        if len(dom) != 2:
            raise ParameterError(f"a surface domain is ((u0, u1), (v0, v1)), got {dom!r}")
        (a, b), (c, e) = _domain_pair(dom[0], "domain_u"), _domain_pair(dom[1], "domain_v")
        self.lo, self.hi = np.array([a, c]), np.array([b, e])
        bp = getattr(geometry, "bezier_breakpoints", None)
        bu, bv = bp() if callable(bp) else (None, None)
        bu, bv = _breakpoints(bu, a, b), _breakpoints(bv, c, e)
        pu = int(getattr(geometry, "degree_u", 3))
        pv = int(getattr(geometry, "degree_v", 3))
        us = _span_samples(bu, max(4, SURFACE_SAMPLES * pu))
        vs = _span_samples(bv, max(4, SURFACE_SAMPLES * pv))
        # a second pass evens out the spacing in space: each parameter interval gets pieces
        # in proportion to the longest chord it spans across the grid
        pts = self._grid(geometry, us, vs)
        with np.errstate(invalid="ignore", over="ignore"):
            lu = np.linalg.norm(np.diff(pts, axis=0), axis=-1).max(axis=1)
            lv = np.linalg.norm(np.diff(pts, axis=1), axis=-1).max(axis=0)
        us = _refined(us, lu, SURFACE_SPACING)
        vs = _refined(vs, lv, SURFACE_SPACING)
        self.grid_shape = (us.size, vs.size)
        self.breaks = [
            _crease_breaks(getattr(geometry, "knots_u", None), pu, a, b),
            _crease_breaks(getattr(geometry, "knots_v", None), pv, c, e),
        ]
        U, V = np.meshgrid(us, vs, indexing="ij")
        params = np.column_stack([U.ravel(), V.ravel()])
        self._finish_samples(params, self._grid(geometry, us, vs))

    @staticmethod
    def _grid(geometry, us, vs):
        """Points ``(len(us), len(vs), dim)`` on the tensor grid."""
        if hasattr(geometry, "evaluate_grid"):
            pts = geometry.evaluate_grid(us, vs)
        else:
            U, V = np.meshgrid(us, vs, indexing="ij")
            pts = geometry.evaluate(U.ravel(), V.ravel())
        return np.asarray(pts, dtype=np.float64).reshape(us.size, vs.size, -1)

    def derivs(self, x):
        """``S (m, dim)``, ``J (m, dim, 2)``, second derivatives ``(m, dim, 2, 2)`` at ``x (m, 2)``."""
        d = np.asarray(self.geometry.derivatives(x[:, 0], x[:, 1], 2), dtype=np.float64) / self.unit
        J = np.stack([d[1, 0], d[0, 1]], axis=-1)
        H = np.stack([np.stack([d[2, 0], d[1, 1]], axis=-1), np.stack([d[1, 1], d[0, 2]], axis=-1)], axis=-2)
        return d[0, 0], J, H

    def evaluate(self, x):
        """Points ``(m, dim)`` at ``x (m, 2)``."""
        return np.asarray(self.geometry.evaluate(x[:, 0], x[:, 1]), dtype=np.float64).reshape(x.shape[0], -1) / self.unit
