"""Closest points: projection of many points onto curves, surfaces and implicits.

``project(geometry, points)`` finds, for every point ``P``, the point of the
geometry nearest to it, all points at once:

* **Parametric curves and surfaces** (any splinekit curve of any dimension,
  :class:`~splinekit.BSplineSurface`, :class:`~splinekit.NurbsSurface`,
  :class:`~splinekit.BezierSurface`, or any object with ``evaluate``,
  ``derivatives`` and ``domain``). The geometry is sampled on a parameter grid
  that contains every knot line, a few samples per Bézier span, refined so that
  the samples are about evenly spaced in space (short spans and high weights
  get more). A k-d tree gives each point its nearest samples; the nearest, the
  next ones that are discrete local minima of the distance (no grid neighbour
  nearer), and the next nearest other sample become Newton seeds. Newton's
  method on the point-inversion equations (The NURBS Book, section 6.1:
  ``C'.(C - P) = 0`` for a curve, the 2 x 2 system with second derivatives for
  a surface) runs on all seeds of all points as one batch, with per-seed
  convergence masks:

  - it stays inside the parameter box: a parameter that reaches the boundary
    with the gradient pointing out is frozen, so the search goes on along the
    boundary curve, or stops at the corner;
  - where the Hessian is not positive definite (far points, strong curvature)
    it is shifted to be, and only steps that do not increase the distance are
    accepted (the step is cut back otherwise), so the result is never farther
    than the seed;
  - where the geometry is only C0 (knots of full multiplicity, every knot of
    degree 1) the distance has a kink, so each seed searches one smooth piece
    at a time and crosses a crease only when the distance keeps decreasing
    across it.

  Each point keeps its nearest result. Closed curves and surfaces need nothing
  special: samples on both sides of a seam are near a point there.
* **Implicit surfaces**: any object callable on ``(n, dim)`` points returning
  ``(n,)`` values ``F`` that has ``.gradient(points)`` -> ``(n, dim)``. Points
  move by ``q <- q - F(q) grad F(q) / |grad F(q)|^2`` until ``|F(q)| <=
  tolerance``; for a true signed-distance function one step lands on the
  closest point, for other implicits the result is a nearby point of the zero
  set (not necessarily the closest one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._validate import as_float_array, as_params, as_positive
from .errors import ConvergenceError, ParameterError

__all__ = ["Projection", "distance", "project"]

MAX_ITERATIONS = 60
"""Newton iterations (rejected steps included) per seed before giving up."""

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

MAX_PIECE_CROSSINGS = 4
"""How many creases (C0 knot lines) a seed's search may cross."""

MAX_COORDINATE = 1e150
"""Largest absolute coordinate of a query point, in units of the geometry's size
when that exceeds ``LARGE`` (else in model units): squared distances (k-d tree,
Newton residuals) must stay within the float range."""

LARGE = 1e60
"""Geometry larger than this, or smaller than its inverse (largest sample
coordinate), is searched in scaled units."""

CHUNK = 32768
"""Points projected together; bounds the memory of the batch arrays."""


@dataclass(frozen=True, eq=False)
class Projection:
    """Closest points of a batch of points.

    Attributes
    ----------
    parameters : ndarray or None
        Curve parameters ``(n,)``, surface parameters ``(n, 2)`` as ``(u, v)``
        pairs, or ``None`` for an implicit surface.
    points : ndarray, shape (n, dim)
        The closest points on the geometry.
    distances : ndarray, shape (n,)
        Euclidean distances from the input points to ``points`` (model units).

    For input points of shape ``shape + (dim,)`` the leading ``(n,)`` above is
    ``shape``.
    """

    parameters: np.ndarray | None
    points: np.ndarray
    distances: np.ndarray


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
        best = _best_per_owner(own, dist, stop - start)
        bad = ~(converged[best] | stationary[best]) & (dist[best] > tol)
        if bad.any():
            i = start + int(np.flatnonzero(bad)[0])
            index = [int(j) for j in np.unravel_index(i, lead)] if lead else []
            raise ConvergenceError(
                f"Newton did not converge for points{index} = {(P[i] * target.unit).tolist()}: after {MAX_ITERATIONS} "
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


# --------------------------------------------------------------------------------------
# input handling


def _readonly(arr):
    arr = np.array(arr, dtype=np.float64, order="C")  # a copy; keeps 0-d results 0-d
    arr.setflags(write=False)
    return arr


def _as_query_points(points, dim: int, unit: float = 1.0):
    """``points / unit`` as a finite ``(n, dim)`` array and its leading shape."""
    P = as_float_array(points, "points", ParameterError)
    if P.ndim == 0 or P.shape[-1] != dim:
        raise ParameterError(
            f"points must have shape (n, {dim}) for this {dim}-D geometry, got an array of shape {P.shape}"
        )
    lead = P.shape[:-1]
    P = P.reshape(-1, dim)
    bad = ~np.isfinite(P).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        index = tuple(int(j) for j in np.unravel_index(i, lead)) if lead else ()
        raise ParameterError(f"points{list(index)} = {P[i].tolist()} is not finite")
    far = np.abs(P).max(axis=1, initial=0.0) > MAX_COORDINATE * unit
    if far.any():
        i = int(np.flatnonzero(far)[0])
        index = tuple(int(j) for j in np.unravel_index(i, lead)) if lead else ()
        raise ParameterError(
            f"points{list(index)} = {P[i].tolist()} has a coordinate beyond {MAX_COORDINATE * unit:g}: "
            "squared distances would overflow"
        )
    return np.ascontiguousarray(P / unit), lead


def _positive_tolerance(value) -> float:
    return as_positive(value, "tolerance")


def _domain_pair(value, name: str):
    pair = as_float_array(value, name, ParameterError)
    if pair.shape != (2,) or not np.isfinite(pair).all() or not pair[0] < pair[1]:
        raise ParameterError(f"{name} must be a finite interval (a, b) with a < b, got {value!r}")
    return float(pair[0]), float(pair[1])


def _target(geometry):
    """Wrap ``geometry`` in the adapter the projection works on."""
    from .curves import BezierCurve, SplineCurve
    from .surfaces import BezierSurface, SplineSurface

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
    from .basis.knots import distinct

    values, counts = distinct(np.asarray(knots, dtype=np.float64))
    inner = values[(values > lo) & (values < hi) & (counts >= degree)]
    return np.concatenate([[lo], inner, [hi]])


# --------------------------------------------------------------------------------------
# parametric geometry adapters: sampling, seeds, derivatives


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
            return 1e-9 * self.size
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


# --------------------------------------------------------------------------------------
# batch Newton


def _newton_step(H, G, g, fixed):
    """Newton step ``(m, k)`` for gradient ``g`` with the variables in ``fixed`` held.

    ``H`` is the Hessian of ``|S - P|^2 / 2`` and ``G = J^T J`` its Gauss-Newton
    part. Where the free block of ``H`` is not positive definite (far points,
    strongly curved geometry) it is shifted by twice its most negative
    eigenvalue, which keeps a descent direction of sensible length along the
    direction of negative curvature (plain Gauss-Newton overshoots there).
    """
    free = ~fixed
    g = np.where(free, g, 0.0)
    if g.shape[1] == 1:
        h, gn = H[:, 0, 0], G[:, 0, 0]
        h = np.where(h > 1e-10 * gn, h, np.maximum(gn, -h) + 1e-12 * gn)
        step = -np.divide(g[:, 0], h, out=np.zeros_like(h), where=h > 0)
        return step[:, None]
    a = np.where(free[:, 0], H[:, 0, 0], 1.0)
    c = np.where(free[:, 1], H[:, 1, 1], 1.0)
    b = np.where(free[:, 0] & free[:, 1], H[:, 0, 1], 0.0)
    pd = (a > 0) & (c > 0) & (a * c - b * b > 1e-10 * a * c)
    lam_min = 0.5 * (a + c) - np.sqrt(0.25 * (a - c) ** 2 + b * b)
    shift = np.where(pd, 0.0, 2.0 * np.maximum(-lam_min, 0.0) + 1e-9 * (np.abs(a) + np.abs(c)))
    a, c = a + shift, c + shift
    det = a * c - b * b
    ok = det > 0
    s0 = -np.divide(c * g[:, 0] - b * g[:, 1], det, out=np.zeros_like(det), where=ok)
    s1 = -np.divide(a * g[:, 1] - b * g[:, 0], det, out=np.zeros_like(det), where=ok)
    return np.column_stack([s0, s1])


def _gradients(S, J, H2, P):
    r = S - P
    g = np.einsum("mdk,md->mk", J, r)
    G = np.einsum("mdk,mdl->mkl", J, J)
    H = G + np.einsum("md,mdkl->mkl", r, H2)
    return r, g, G, H


def _derivs_inside(target, x, hi):
    """``target.derivs(x)`` with the derivatives of the piece ``x`` belongs to.

    At a crease the derivatives jump, and evaluation takes the piece on the
    right of a knot; a point on the upper end of its box is evaluated one ulp
    to the left so that it gets the derivatives of its own piece."""
    inner = (x >= hi) & (hi < target.hi)
    if inner.any():
        x = np.where(inner, np.nextafter(hi, -np.inf), x)
    return target.derivs(x)


def _newton(target, P, x0, lo, hi, tol):
    """Minimise ``|S(x) - P|`` from each seed ``x0`` ``(m, k)`` inside the boxes ``[lo, hi]`` ``(m, k)``.

    Returns ``(x, S(x), distances, g, converged, stationary)`` with ``g`` the
    gradient of ``|S - P|^2 / 2``; every accepted step does not increase the
    distance, so ``distances`` never exceed the seeds'.
    """
    x = np.clip(x0, lo, hi)
    S, J, H2 = _derivs_inside(target, x, hi)
    dist = np.linalg.norm(S - P, axis=1)
    scale = target.size + np.abs(P).max(axis=1)
    slack = 16 * np.finfo(float).eps * scale  # distances compare equal within rounding
    alpha = np.ones(x.shape[0])
    converged = dist == 0
    active = np.flatnonzero(~converged)
    last, last_x = [], []  # final steps (shorter than tol), checked together after the loop
    for _ in range(MAX_ITERATIONS):
        if active.size == 0:
            break
        xa, Pa, la, ha = x[active], P[active], lo[active], hi[active]
        _, g, G, H = _gradients(S[active], J[active], H2[active], Pa)
        fixed = ((xa <= la) & (g > 0)) | ((xa >= ha) & (g < 0))
        step = _newton_step(H, G, g, fixed) * alpha[active, None]
        xt = np.clip(xa + step, la, ha)
        moved = np.linalg.norm(np.einsum("mdk,mk->md", J[active], xt - xa), axis=1)
        # a step shorter than tol ends the search: it needs the new point only, not its
        # derivatives, so it is evaluated in one batch at the end
        small = moved <= tol
        if small.any():
            converged[active[small]] = True
            last.append(active[small])
            last_x.append(xt[small])
            active, xa, Pa, ha, xt = active[~small], xa[~small], Pa[~small], ha[~small], xt[~small]
            moved = moved[~small]
            if active.size == 0:
                break
        St, Jt, H2t = _derivs_inside(target, xt, ha)
        dt = np.linalg.norm(St - Pa, axis=1)
        accept = dt <= dist[active] + slack[active]
        acc = active[accept]
        x[acc], S[acc], J[acc], H2[acc], dist[acc] = xt[accept], St[accept], Jt[accept], H2t[accept], dt[accept]
        alpha[acc] = np.minimum(1.0, 4.0 * alpha[acc])
        alpha[active[~accept]] *= 0.25
        done = (moved <= tol) | (dt == 0)
        converged[active[done]] = True
        active = active[~done]
    if last:
        idx, xt = np.concatenate(last), np.concatenate(last_x)
        St = target.evaluate(xt)
        dt = np.linalg.norm(St - P[idx], axis=1)
        ok = dt <= dist[idx] + slack[idx]
        x[idx[ok]], S[idx[ok]], dist[idx[ok]] = xt[ok], St[ok], dt[ok]
    # a seed that ran out of iterations may still sit at a stationary point (slow, linear convergence)
    _, g, G, _ = _gradients(S, J, H2, P)
    fixed = ((x <= lo) & (g > 0)) | ((x >= hi) & (g < 0))
    gfree = np.linalg.norm(np.where(fixed, 0.0, g), axis=1)
    jn = np.sqrt(np.einsum("mkk->m", G))
    stationary = gfree <= 1e-8 * jn * dist + 1e-300
    return x, S, dist, g, converged, stationary


def _search(target, P, owner, x0, tol):
    """Newton from every seed, piece by piece.

    Where the geometry is only C0 (knots of full multiplicity: creases, and
    every knot of degree 1) the distance has a kink and Newton would zigzag, so
    each seed searches inside its smooth piece of the domain. A seed that stops
    on a crease with the gradient pointing across it moves into the
    neighbouring piece and searches on from there (the distance keeps
    decreasing), a few pieces at most.
    """
    left = np.zeros(x0.shape, dtype=bool)
    for j, br in enumerate(target.breaks):
        # a seed on a crease starts in both pieces beside it (samples lie on every knot line)
        on = np.isin(x0[:, j], br[1:-1])
        if on.any():
            flag = left[on]
            flag[:, j] = True
            owner, P, x0 = (np.concatenate([a, a[on]]) for a in (owner, P, x0))
            left = np.concatenate([left, flag])
    piece = np.empty(x0.shape, dtype=np.intp)
    for j, br in enumerate(target.breaks):
        piece[:, j] = np.clip(np.searchsorted(br, x0[:, j], side="right") - 1 - left[:, j], 0, br.size - 2)
    lo, hi = target.boxes(piece)
    x, S, dist, g, converged, stationary = _newton(target, P, x0, lo, hi, tol)
    rounds = 0
    while rounds < MAX_PIECE_CROSSINGS:
        down = (x <= lo) & (g > 0) & (piece > 0)
        up = (x >= hi) & (g < 0) & (piece < np.array([br.size - 2 for br in target.breaks]))
        move = np.flatnonzero((down | up).any(axis=1))
        if move.size == 0:
            break
        piece[move] += up[move].astype(np.intp) - down[move].astype(np.intp)
        lo, hi = target.boxes(piece)
        res = _newton(target, P[move], x[move], lo[move], hi[move], tol)
        for arr, new in zip((x, S, dist, g, converged, stationary), res):
            arr[move] = new
        rounds += 1
    return owner, x, S, dist, converged, stationary


def _best_per_owner(owner, dist, n):
    """Index (into the seeds) of the nearest result of each of the ``n`` points."""
    order = np.lexsort((dist, owner))
    first = np.ones(order.size, dtype=bool)
    first[1:] = owner[order[1:]] != owner[order[:-1]]
    best = order[first]
    if best.size != n:  # every point has at least one seed by construction
        raise AssertionError("a point without seeds")
    return best


# --------------------------------------------------------------------------------------
# implicit surfaces


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
            tol = 1e-9 * max(1.0, float(np.abs(P).max(initial=0.0)))
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
