"""Smoothed least-squares fit of a B-spline surface to scattered points.

The unknown control net ``P`` (``nu * nv`` points) minimises

    |A P - Q|^2 + lam * (|D_uu P|^2 + 2 |D_uv P|^2 + |D_vv P|^2)

where row ``k`` of the sparse matrix ``A`` holds the tensor-product basis
functions at the point's parameters and ``D_uu``, ``D_uv``, ``D_vv`` are second
divided differences of the control net over its Greville abscissae (a discrete
thin-plate energy that vanishes exactly on affine surfaces). The normal
equations are sparse and symmetric positive definite when the data (and the
smoothing) determine every control point.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp

from .._validate import as_degree, as_float_array, as_points, as_real
from ..basis.bspline import basis_funs_t, find_span
from ..basis.knots import clamped_uniform, validate_knots
from ..errors import FittingError, KnotVectorError, ParameterError
from ..surfaces import BSplineSurface
from .parametrize import as_control_count, denormalized, normalized

__all__ = ["fit_surface", "greville", "plane_parameters", "thin_plate_energy"]

PIVOT_RTOL = 1e-12
"""A pivot of the sparse factorization below this fraction of the largest marks
control points the data and smoothing leave undetermined."""


def plane_parameters(points) -> np.ndarray:
    """Parameters ``(n, 2)`` in ``[0, 1]^2``: the points projected on their best-fit plane.

    The plane is spanned by the two principal directions of the centred points
    (PCA by SVD). Within the plane the axes are then turned to those of the
    smallest-area rectangle around the projected points (so a square patch
    maps onto the whole unit square rather than a diamond inside it), and each
    coordinate is scaled onto [0, 1]. Raises :class:`FittingError` if the
    points are (nearly) collinear.
    """
    Q = as_points(points, "points")
    if Q.shape[1] < 2:
        raise FittingError(
            f"points need at least 2 coordinates to define a plane, got {Q.shape[1]}"
        )
    if Q.shape[0] < 3:
        raise FittingError(f"a plane needs at least 3 points, got {Q.shape[0]}")
    Q = normalized(Q)[0]
    centred = Q - Q.mean(axis=0)
    _, s, vt = np.linalg.svd(centred, full_matrices=False)
    if not s[1] > 1e-10 * s[0]:
        raise FittingError(
            "the points are collinear: no best-fit plane to parametrize them over"
        )
    uv = centred @ vt[:2].T
    uv = uv @ _min_area_rectangle_axes(uv)
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    return np.clip((uv - lo) / (hi - lo), 0.0, 1.0)


def _min_area_rectangle_axes(xy: np.ndarray) -> np.ndarray:
    """Orthonormal ``(2, 2)`` axes (columns) of the smallest-area bounding rectangle of ``xy (n, 2)``.

    The best rectangle has a side along an edge of the convex hull, so every
    hull edge direction is tried at once.
    """
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = xy[ConvexHull(xy).vertices]
    except QhullError:
        return np.eye(2)
    edges = np.roll(hull, -1, axis=0) - hull
    length = np.linalg.norm(edges, axis=1)
    keep = length > 0
    d = edges[keep] / length[keep, None]  # (h, 2) candidate first axes
    normal = np.stack([-d[:, 1], d[:, 0]], axis=1)
    a, b = hull @ d.T, hull @ normal.T  # (hull points, h)
    area = np.ptp(a, axis=0) * np.ptp(b, axis=0)
    k = int(np.argmin(area))
    if area[k] >= np.ptp(xy[:, 0]) * np.ptp(xy[:, 1]) * (1 - 1e-12):
        return np.eye(2)  # keep the principal axes unless a turn is strictly better
    return np.stack([d[k], normal[k]], axis=1)


def _normal_equations(pu, pv, Ku, Kv, nu, nv, uv, Q):
    """``A^T A`` (CSC, ``(nu * nv, nu * nv)``) and ``A^T Q`` (``(nu * nv, dim)``) without forming ``A``.

    Row ``k`` of ``A`` holds ``N_i(u_k) N_j(v_k)`` at column ``i * nv + j``. All
    points in one knot cell share the same ``L = (pu + 1)(pv + 1)`` non-zero
    columns, so each entry of the small symmetric ``(L, L)`` cell blocks is one
    ``np.bincount`` over the cells (the loop runs over the ``L (L + 1) / 2``
    local pairs, never over points), and the blocks of the cells holding data
    are scattered once.
    """
    u, v = uv[:, 0], uv[:, 1]
    su, sv = find_span(pu, Ku, u), find_span(pv, Kv, v)
    Nu, Nv = (
        basis_funs_t(pu, Ku, su, u),
        basis_funs_t(pv, Kv, sv, v),
    )  # (pu+1, n), (pv+1, n)
    cells_v = nv - pv
    # only the knot cells holding data get a block: memory follows the data, not the net
    occupied, cell = np.unique((su - pu) * cells_v + (sv - pv), return_inverse=True)
    cell = cell.ravel()
    L = (pu + 1) * (pv + 1)
    w = (Nu[:, None, :] * Nv[None, :, :]).reshape(
        L, -1
    )  # (L, n): one contiguous row per local function
    n_cells = occupied.size
    dim = Q.shape[1]
    gram = np.empty((n_cells, L, L))
    for i in range(L):
        for j in range(i, L):
            gram[:, i, j] = gram[:, j, i] = np.bincount(
                cell, w[i] * w[j], minlength=n_cells
            )
    moment = np.empty((n_cells, L, dim))
    for i in range(L):
        for d in range(dim):
            moment[:, i, d] = np.bincount(cell, w[i] * Q[:, d], minlength=n_cells)
    # global column of local function (a, b) in cell (cu, cv): (cu + a) * nv + (cv + b)
    cu, cv = np.divmod(occupied, cells_v)
    local = (np.arange(pu + 1)[:, None] * nv + np.arange(pv + 1)[None, :]).ravel()
    cols = (cu * nv + cv)[:, None] + local[None, :]  # (n_cells, L)
    size = nu * nv
    rows_g = np.broadcast_to(cols[:, :, None], gram.shape)
    cols_g = np.broadcast_to(cols[:, None, :], gram.shape)
    M = sp.csc_matrix(
        (gram.ravel(), (rows_g.ravel(), cols_g.ravel())), shape=(size, size)
    )
    rhs = np.zeros((size, Q.shape[1]))
    np.add.at(rhs, cols.ravel(), moment.reshape(-1, Q.shape[1]))
    return M, rhs


def greville(degree: int, knots: np.ndarray) -> np.ndarray:
    """Greville abscissae ``(n,)``: means of ``degree`` consecutive inner knots (where control points sit)."""
    c = np.concatenate([[0.0], np.cumsum(knots[1:-1])])
    return (c[degree:] - c[:-degree]) / degree


def _second_difference(x: np.ndarray) -> sp.csr_matrix:
    """Second divided differences on abscissae ``x (n,)``: ``(n - 2, n)``, zero on affine data."""
    h = np.diff(x)
    a, b = 1.0 / h[:-1], 1.0 / h[1:]
    scale = 2.0 / (h[:-1] + h[1:])
    n = x.size
    i = np.arange(n - 2)
    rows = np.repeat(i, 3)
    cols = (i[:, None] + np.arange(3)).ravel()
    vals = (scale[:, None] * np.stack([a, -(a + b), b], axis=1)).ravel()
    return sp.csr_matrix((vals, (rows, cols)), shape=(n - 2, n))


def _first_difference(x: np.ndarray) -> sp.csr_matrix:
    """First divided differences on abscissae ``x (n,)``: ``(n - 1, n)``."""
    n = x.size
    inv = 1.0 / np.diff(x)
    i = np.arange(n - 1)
    return sp.csr_matrix(
        (
            np.stack([-inv, inv], axis=1).ravel(),
            (np.repeat(i, 2), (i[:, None] + np.arange(2)).ravel()),
        ),
        shape=(n - 1, n),
    )


def thin_plate_energy(
    degree_u: int, degree_v: int, knots_u: np.ndarray, knots_v: np.ndarray
) -> sp.csr_matrix:
    """Discrete thin-plate energy of a control net: ``E^T E`` ``(nu * nv, nu * nv)``.

    ``E`` stacks the second divided differences ``D_uu``, ``sqrt(2) D_uv``,
    ``D_vv`` of the net over its Greville abscissae, each row weighted by the
    square root of the area it stands for, so that ``P^T E^T E P``
    approximates ``integral(S_uu^2 + 2 S_uv^2 + S_vv^2) du dv``. Its null space
    is the nets of affine surfaces ``a + b u + c v``.

    ``knots_u``, ``knots_v`` are checked like a surface's knot vectors (each
    must define at least ``degree + 1`` control points); ``nu``, ``nv`` are
    their lengths minus ``degree + 1``.
    """
    knots_u, knots_v = (
        _energy_knots(k, degree, name)
        for k, degree, name in ((knots_u, degree_u, "knots_u"), (knots_v, degree_v, "knots_v"))
    )
    degree_u, degree_v = as_degree(degree_u, "degree_u"), as_degree(degree_v, "degree_v")
    xu, xv = greville(degree_u, knots_u), greville(degree_v, knots_v)
    nu, nv = xu.size, xv.size
    area_u, area_v = np.ptp(xu) / max(nu - 1, 1), np.ptp(xv) / max(nv - 1, 1)
    Iu, Iv = sp.identity(nu), sp.identity(nv)
    blocks = []
    if nu >= 3:
        blocks.append(sp.kron(_second_difference(xu), Iv))
    if nv >= 3:
        blocks.append(sp.kron(Iu, _second_difference(xv)))
    blocks.append(np.sqrt(2.0) * sp.kron(_first_difference(xu), _first_difference(xv)))
    E = sp.vstack(blocks).tocsr() * np.sqrt(area_u * area_v)
    return (E.T @ E).tocsr()


def _energy_knots(knots, degree, name: str) -> np.ndarray:
    """A validated knot vector of at least ``degree + 1`` control points."""
    p = as_degree(degree, "degree_u" if name.endswith("u") else "degree_v")
    U = as_float_array(knots, name, KnotVectorError)
    if U.ndim != 1 or U.size < 2 * p + 2:
        raise KnotVectorError(
            f"{name} must be 1-D with at least 2 * degree + 2 = {2 * p + 2} values, got shape {U.shape}"
        )
    return validate_knots(U, p, U.size - p - 1, name)


MAX_SMOOTHING = 1e12
"""Largest smoothing weight: the solve loses about ``smoothing * 1e-16`` relative
accuracy on the data term (measured: 3e-5 at 1e12, rank deficient at 1e15)."""

MAX_NET = 1 << 22
"""Largest control net ``n_control_u * n_control_v`` fit_surface accepts (its
sparse normal equations grow with the net; a sparse factorization of more
than a few million unknowns is beyond a fitting call)."""


def fit_surface(
    points,
    n_control_u: int,
    n_control_v: int,
    degree_u: int = 3,
    degree_v: int = 3,
    *,
    parameters=None,
    smoothing: float = 0.0,
) -> BSplineSurface:
    """A B-spline surface on [0, 1]^2 fitted to scattered points by smoothed least squares.

    Parameters
    ----------
    points : array_like, shape (n, dim)
        Scattered data (a height-field-like or disk-like cloud for the default
        parameters); ``dim >= 2`` unless ``parameters`` is given.
    n_control_u, n_control_v : int
        Size of the control net, at least ``degree + 1`` each; knots are clamped uniform.
    degree_u, degree_v : int
    parameters : array_like, shape (n, 2), optional
        ``(u, v)`` of each point in [0, 1]^2; default :func:`plane_parameters`
        (projection onto the best-fit plane, scaled to the unit square).
    smoothing : float
        Weight ``>= 0`` of the thin-plate energy of the control net (second
        divided differences, see :func:`thin_plate_energy`), relative to the data
        term: the energy matrix is first scaled to the same trace as
        ``A^T A``. 0 is plain least squares; 1e-6 .. 1e-2 fills gaps in the
        data and damps noise; large values (up to ``1e12``) tend to the
        least-squares affine surface ``a + b u + c v``.

    Returns
    -------
    BSplineSurface with control points ``(n_control_u, n_control_v, dim)``.

    Raises :class:`FittingError` when the data (with ``smoothing = 0``, fewer
    points than control points or a region without data) leave control points
    undetermined.
    """
    Q = as_points(points, "points")
    pu, pv = as_degree(degree_u, "degree_u"), as_degree(degree_v, "degree_v")
    nu = as_control_count(n_control_u, "n_control_u", pu)
    nv = as_control_count(n_control_v, "n_control_v", pv)
    if nu * nv > MAX_NET:
        raise FittingError(
            f"a {nu} x {nv} control net has {nu * nv} control points, more than fit_surface handles ({MAX_NET})"
        )
    lam = as_real(smoothing, "smoothing")
    if lam < 0:
        raise ParameterError(f"smoothing must be >= 0, got {lam!r}")
    if lam > MAX_SMOOTHING:
        raise ParameterError(
            f"smoothing = {lam!r} is too large: above {MAX_SMOOTHING:g} the data term is lost to rounding "
            "(the result would be the affine fit, or a rank-deficient system)"
        )
    n_pts = Q.shape[0]
    if lam == 0 and n_pts < nu * nv:
        raise FittingError(
            f"too few points: {n_pts} points cannot determine {nu} x {nv} = {nu * nv} control points "
            "without smoothing; pass smoothing > 0 or a smaller net"
        )
    if parameters is None:
        uv = plane_parameters(Q)
    else:
        uv = as_float_array(parameters, "parameters", ParameterError)
        if uv.shape != (n_pts, 2):
            raise ParameterError(
                f"parameters must have shape ({n_pts}, 2), got {uv.shape}"
            )
        bad = ~((uv >= 0.0) & (uv <= 1.0))  # also catches NaN
        if bad.any():
            k = int(np.argwhere(bad)[0][0])
            raise ParameterError(
                f"parameters[{k}] = {uv[k].tolist()} lies outside [0, 1]^2"
            )
    Ku, Kv = clamped_uniform(pu, nu), clamped_uniform(pv, nv)
    Q, center, half = normalized(
        Q
    )  # affine invariance: fit in [-1, 1], no overflow in any units
    M, rhs = _normal_equations(pu, pv, Ku, Kv, nu, nv, uv, Q)
    if lam > 0:
        E = thin_plate_energy(pu, pv, Ku, Kv)
        with np.errstate(over="ignore"):
            weight = lam * (M.diagonal().sum() / E.diagonal().sum())
        if not np.isfinite(weight):
            raise ParameterError(f"smoothing = {lam!r} is too large: the weighted energy overflows")
        M = M + weight * E
    ctrl = denormalized(
        _solve_spd(sp.csc_matrix(M), rhs, nv), center, half, "fitted surface"
    )
    return BSplineSurface(pu, pv, Ku, Kv, ctrl.reshape(nu, nv, -1))


def _solve_spd(M: sp.csc_matrix, rhs: np.ndarray, nv: int) -> np.ndarray:
    """Sparse symmetric positive (semi)definite solve with a rank check on the pivots."""
    import scipy.sparse.linalg as spla  # imported on use (slow to import)

    scale = M.diagonal()
    if not (scale > 0).all():
        i, j = divmod(int(np.flatnonzero(~(scale > 0))[0]), nv)
        raise FittingError(
            f"control point [{i}, {j}] has no data in its support and no smoothing: it is undetermined; "
            "pass smoothing > 0 or fewer control points"
        )
    # symmetric diagonal scaling makes the pivot test independent of units and basis magnitudes
    d = 1.0 / np.sqrt(scale)
    Ms = sp.csc_matrix(M.multiply(d[:, None]).multiply(d[None, :]))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            lu = spla.splu(
                Ms,
                permc_spec="MMD_AT_PLUS_A",
                diag_pivot_thresh=0.0,
                options={"SymmetricMode": True},
            )
    except (RuntimeError, spla.MatrixRankWarning):
        raise FittingError(
            "the fit is rank deficient: the data leave control points undetermined; pass smoothing > 0"
        ) from None
    pivots = np.abs(lu.U.diagonal())
    if not pivots.min() > PIVOT_RTOL * pivots.max():
        raise FittingError(
            "the fit is rank deficient: the data leave some control points undetermined "
            "(a region of the parameter square without data?); pass smoothing > 0 or fewer control points"
        )
    out = d[:, None] * lu.solve(d[:, None] * rhs)
    if not np.isfinite(out).all():
        raise FittingError("the fit is numerically singular; pass smoothing > 0")
    return out
