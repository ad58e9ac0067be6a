"""Surfaces from point clouds: a B-spline height field and an implicit (moving least squares) surface."""

from __future__ import annotations

import numpy as np

from .._validate import as_degree, as_int, as_real
from ..errors import FittingError, ParameterError
from ..fit import fit_surface
from ..fit.scattered import plane_parameters
from ..implicit.base import Implicit
from ..tolerances import DEVIATION_RTOL
from ._cloud import as_cloud, as_neighbour_count, kd_tree, neighbours
from .normals import estimate_normals

__all__ = ["fit_height_field", "mls_distance", "reconstruct_implicit"]

DEFAULT_RELATIVE_TOLERANCE = DEVIATION_RTOL
"""Default height-field tolerance, relative to the diagonal of the cloud's bounding box."""


def _net_size(value, degree: int, name: str):
    if isinstance(value, (tuple, list, np.ndarray)):
        if len(value) != 2:
            raise ParameterError(f"{name} must be an int or a pair (nu, nv), got {value!r}")
        return tuple(as_int(v, name, minimum=degree + 1) for v in value)
    n = as_int(value, name, minimum=degree + 1)
    return n, n


def fit_height_field(
    points,
    tolerance=None,
    *,
    n_control=None,
    degree: int = 3,
    smoothing: float = 1e-7,
    max_control: int = 96,
):
    """A B-spline surface fitted to a height-field-like cloud, refined until it meets a tolerance.

    The points are parametrized by projection onto their best-fit plane
    (:func:`splinekit.fit.scattered.plane_parameters`) and fitted by
    :func:`splinekit.fit_surface` (least squares with a small thin-plate
    smoothing term that keeps sparse regions determined). Without
    ``n_control`` the control net starts at ``(degree + 2)^2`` and the number
    of knot spans doubles in both directions until every point lies within
    ``tolerance`` of the surface.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        A cloud over which one surface ``(u, v) -> R^3`` can be laid (a height
        field over its best-fit plane, or a gently curved sheet).
    tolerance : float, optional
        Largest allowed residual ``|S(u_i, v_i) - Q_i|`` in model units (an
        upper bound of each point's distance to the surface). Default
        ``1e-3`` times the diagonal of the cloud's bounding box.
    n_control : int or (int, int), optional
        A fixed control net; no refinement, no tolerance check.
    degree : int
        Degree in both directions.
    smoothing : float
        Thin-plate weight passed to :func:`splinekit.fit_surface`.
    max_control : int
        Largest control-net size per direction tried before giving up.

    Returns
    -------
    BSplineSurface on ``[0, 1]^2``.

    Raises
    ------
    FittingError
        The tolerance is not met with ``max_control`` control points per
        direction (noise above the tolerance, or not a height field); the
        message gives the residual reached.
    """
    Q = as_cloud(points, min_count=3)
    p = as_degree(degree)
    uv = plane_parameters(Q)
    if n_control is not None:
        nu, nv = _net_size(n_control, p, "n_control")
        return fit_surface(Q, nu, nv, p, p, parameters=uv, smoothing=smoothing)
    size = float(np.linalg.norm(Q.max(axis=0) - Q.min(axis=0)))
    if tolerance is None:
        tol = DEFAULT_RELATIVE_TOLERANCE * size
    else:
        tol = as_real(tolerance, "tolerance")
        if not tol > 0:
            raise ParameterError(f"tolerance must be > 0, got {tol!r}")
    limit = as_int(max_control, "max_control", minimum=p + 2)
    spans = 2
    while True:
        n = min(p + spans, limit)
        surface = fit_surface(Q, n, n, p, p, parameters=uv, smoothing=smoothing)
        residual = float(np.linalg.norm(surface.evaluate(uv[:, 0], uv[:, 1]) - Q, axis=1).max())
        if residual <= tol:
            return surface
        if n >= limit:
            raise FittingError(
                f"the height-field fit with {n} x {n} control points leaves a residual of {residual:.3g} "
                f"above the tolerance {tol:.3g}; raise max_control or the tolerance, or smooth the cloud"
            )
        spans *= 2


def mls_distance(points, normals, tree, k: int, queries, gradient: bool = True):
    """Implicit moving-least-squares distance (and its gradient) at ``queries`` ``(m, 3)``.

    ``points`` and ``normals`` ``(n, 3)`` are the cloud and its unit normals
    (as held by a reconstruction, not re-checked here), ``tree`` a
    ``scipy.spatial.cKDTree`` over ``points`` (None builds one), ``k`` the
    neighbour count (``2 <= k <= n``).

    ``F(q) = sum_i w_i (q - p_i) . n_i / sum_i w_i`` over the ``k`` nearest
    cloud points, with Wendland weights ``w_i = phi(|q - p_i| / D)``,
    ``phi(t) = (1 - t)^4 (4 t + 1)`` and ``D`` the distance to the ``k``-th
    neighbour (whose weight is therefore 0, which keeps ``F`` continuous when
    the neighbour set changes). Returns ``F (m,)``, or ``(F, grad F (m, 3))``
    with ``gradient``; the gradient is analytic (including the motion of ``D``).
    Where every weight underflows (a query some ten thousand spacings away)
    ``F`` is the distance to the nearest point's tangent plane.
    """
    if tree is None:
        tree = kd_tree(points)
    d, idx = neighbours(tree, queries, k)
    r = queries[:, None, :] - points[idx]
    n = normals[idx]
    s = np.einsum("mkd,mkd->mk", r, n)
    D = d[:, -1:]
    D = np.where(D > 0, D, 1.0)
    t = np.minimum(d / D, 1.0)
    u = 1.0 - t
    u3 = u * u * u
    w = u3 * u * (4.0 * t + 1.0)
    B = w.sum(axis=1)
    far = ~(B > 1e-250)
    B[far] = 1.0
    F = np.einsum("mk,mk->m", w, s) / B
    if far.any():
        F[far] = s[far, 0]
    if not gradient:
        return F
    # d w_i / dq = phi'(t_i) grad t_i = -20 (1 - t_i)^3 (r_i - t_i^2 r_K) / D^2
    c = (-20.0 / D**2) * u3
    rK = r[:, -1, :]
    cs = c * s
    gA = np.einsum("mk,mkd->md", cs, r) - np.einsum("mk,mk->m", cs, t * t)[:, None] * rK
    gA += np.einsum("mk,mkd->md", w, n)
    gB = np.einsum("mk,mkd->md", c, r) - np.einsum("mk,mk->m", c, t * t)[:, None] * rK
    G = (gA - F[:, None] * gB) / B[:, None]
    if far.any():
        G[far] = n[far, 0]
    return F, G


class MLSImplicit(Implicit):
    """Signed implicit moving-least-squares distance to an oriented point cloud.

    ``F < 0`` inside (behind the normals). Near the cloud ``F`` approximates
    the signed distance to the sampled surface (``|grad F|`` about 1); its
    zero set smooths the samples over about ``k`` neighbours, so on a
    surface of curvature radius ``R`` sampled at spacing ``h`` it lies
    within about ``k h^2 / (4 pi R)`` of the true surface. See
    :func:`mls_distance`.

    Attributes
    ----------
    points, normals : (n, 3) the cloud and its unit normals
    k : int
    """

    def __init__(self, points, normals, k, bounds):
        super().__init__(bounds=bounds, exact=False)
        self.points, self.normals, self.k = points, normals, k
        self._tree = kd_tree(points)

    def __repr__(self):
        return f"MLSImplicit({len(self.points)} points, k={self.k})"

    def _value(self, p):
        return mls_distance(self.points, self.normals, self._tree, self.k, p, gradient=False)

    def _gradient(self, p):
        return mls_distance(self.points, self.normals, self._tree, self.k, p)[1]


def reconstruct_implicit(points, normals=None, *, k: int = 16):
    """An implicit surface through an oriented point cloud (implicit moving least squares).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Samples of a closed surface (model units), ``n >= k``.
    normals : array_like, shape (n, 3), optional
        Outward normals (any non-zero length); default
        :func:`~splinekit.pointcloud.estimate_normals` with the same ``k``.
    k : int
        Neighbours blended at each evaluation, ``3 <= k <= n``. Larger
        smooths more (noise) and rounds off more (curvature).

    Returns
    -------
    MLSImplicit
        A :class:`splinekit.implicit.Implicit` (negative inside) with an
        analytic gradient, whose ``bounds`` are the cloud's bounding box grown
        by 10 % of its diagonal; mesh it with ``.to_mesh(edge_length)``.
    """
    P = as_cloud(points, min_count=3)
    k = as_neighbour_count(k, len(P))
    if normals is None:
        N = estimate_normals(P, k)
    else:
        N = as_cloud(normals, "normals")
        if N.shape != P.shape:
            raise ParameterError(f"normals must have the shape of points {P.shape}, got {N.shape}")
        length = np.linalg.norm(N, axis=1)
        if not (length > 0).all():
            i = int(np.flatnonzero(~(length > 0))[0])
            raise ParameterError(f"normals[{i}] is the zero vector")
        N = N / length[:, None]
    lo, hi = P.min(axis=0), P.max(axis=0)
    margin = 0.1 * float(np.linalg.norm(hi - lo))
    if not margin > 0:
        raise FittingError("the cloud is a single point: it defines no surface")
    return MLSImplicit(P, np.ascontiguousarray(N), k, (lo - margin, hi + margin))
