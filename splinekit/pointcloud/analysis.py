"""Curvature estimates and statistical outlier removal for point clouds."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import as_real
from ..errors import FittingError, ParameterError
from ._cloud import (
    CHUNK,
    as_cloud,
    as_neighbour_count,
    kd_tree,
    local_frames,
    neighbours,
)
from .normals import estimate_normals

__all__ = ["PointCurvature", "curvature", "remove_outliers"]


@dataclass(frozen=True, eq=False)
class PointCurvature:
    """Per-point curvature estimates of a cloud of ``n`` points.

    Attributes
    ----------
    surface_variation : (n,)
        ``lambda_0 / (lambda_0 + lambda_1 + lambda_2)`` of the neighbourhood
        covariance (Pauly et al. 2002): 0 on a plane, at most 1/3; unitless.
    mean, gaussian : (n,)
        Mean (1/length) and Gaussian (1/length^2) curvature of a quadric height
        function ``h = a x^2 + b x y + c y^2 + d x + e y + f`` fitted by least
        squares to the neighbours in the PCA frame of each point. Signs follow
        splinekit's convention (that of OpenCascade): measured against
        ``normals``, a sphere of radius R with outward normals has
        ``mean = -1/R`` and ``gaussian = 1/R^2``.
    normals : (n, 3)
        The unit normals the signs refer to (as given, or estimated and oriented).
    """

    surface_variation: np.ndarray
    mean: np.ndarray
    gaussian: np.ndarray
    normals: np.ndarray


def curvature(points, k: int = 20, *, normals=None) -> PointCurvature:
    """Curvature estimates from each point's ``k`` nearest neighbours (itself included).

    Parameters
    ----------
    points : array_like, shape (n, 3)
    k : int
        Neighbourhood size, ``6 <= k <= n`` (the quadric has 6 coefficients).
    normals : array_like, shape (n, 3), optional
        Orientation of the result; default :func:`estimate_normals` with the
        same ``k`` (oriented). Only the sign of each normal is used: the
        quadric is fitted in the PCA frame of the neighbourhood.

    Returns
    -------
    PointCurvature
    """
    P = as_cloud(points)
    k = as_neighbour_count(k, len(P), minimum=6)
    if normals is None:
        Nref = estimate_normals(P, k)
    else:
        Nref = as_cloud(normals, "normals")
        if Nref.shape != P.shape:
            raise ParameterError(f"normals must have the shape of points {P.shape}, got {Nref.shape}")
    _, idx = neighbours(kd_tree(P), P, k)
    values, vectors, _ = local_frames(P, idx)
    total = values.sum(axis=1)
    if not (total > 0).all():
        i = int(np.flatnonzero(~(total > 0))[0])
        raise FittingError(f"the {k} nearest neighbours of point {i} coincide: no curvature is defined there")
    variation = values[:, 0] / total
    n_axis = vectors[:, :, 0] * np.where(np.einsum("nd,nd->n", vectors[:, :, 0], Nref) < 0, -1.0, 1.0)[:, None]
    H = np.empty(len(P))
    K = np.empty(len(P))
    for s in range(0, len(P), CHUNK):
        sl = slice(s, s + CHUNK)
        H[sl], K[sl] = _quadric_curvature(P[idx[sl]] - P[sl, None, :], vectors[sl, :, 2], vectors[sl, :, 1], n_axis[sl])
    return PointCurvature(variation, H, K, Nref)


def _quadric_curvature(D, e1, e2, n):
    """Mean and Gaussian curvature at the origin of the least-squares quadric height field.

    ``D`` ``(m, k, 3)`` are neighbour offsets from the point; ``e1, e2, n`` ``(m, 3)`` the frame.
    """
    x = np.einsum("mkd,md->mk", D, e1)
    y = np.einsum("mkd,md->mk", D, e2)
    h = np.einsum("mkd,md->mk", D, n)
    scale = np.sqrt((x * x + y * y).mean(axis=1))
    scale = np.where(scale > 0, scale, 1.0)[:, None]
    xs, ys = x / scale, y / scale  # unit-size coordinates keep the 6 x 6 system well conditioned
    A = np.stack([xs * xs, xs * ys, ys * ys, xs, ys, np.ones_like(xs)], axis=2)
    M = np.einsum("mki,mkj->mij", A, A)
    rhs = np.einsum("mki,mk->mi", A, h)
    M += 1e-12 * np.trace(M, axis1=1, axis2=2)[:, None, None] * np.eye(6)
    c = np.linalg.solve(M, rhs[..., None])[..., 0]
    s = scale[:, 0]
    fxx, fxy, fyy = 2 * c[:, 0] / s**2, c[:, 1] / s**2, 2 * c[:, 2] / s**2
    fx, fy = c[:, 3] / s, c[:, 4] / s
    W2 = 1.0 + fx * fx + fy * fy
    K = (fxx * fyy - fxy * fxy) / W2**2
    H = ((1 + fx * fx) * fyy - 2 * fx * fy * fxy + (1 + fy * fy) * fxx) / (2 * W2**1.5)
    return H, K


def remove_outliers(points, k: int = 16, std_ratio: float = 2.0):
    """Statistical outlier removal: drop points whose mean distance to their neighbours is unusual.

    For each point the mean distance to its ``k - 1`` nearest other points is
    computed; points whose mean exceeds ``mean + std_ratio * std`` of those
    means over the cloud are removed.

    Parameters
    ----------
    points : array_like, shape (n, dim)
    k : int
        Neighbourhood size, the point itself included, ``2 <= k <= n``.
    std_ratio : float
        Threshold in standard deviations, > 0; smaller removes more.

    Returns
    -------
    kept : (m, dim) the remaining points, in their original order
    mask : (n,) bool, True where kept
    """
    P = as_cloud(points, dim=None)
    k = as_neighbour_count(k, len(P), minimum=2)
    ratio = as_real(std_ratio, "std_ratio")
    if not ratio > 0:
        raise ParameterError(f"std_ratio must be > 0, got {ratio!r}")
    d, _ = neighbours(kd_tree(P), P, k)
    mean = d[:, 1:].mean(axis=1)
    mu = mean.mean()
    # the relative slack keeps an evenly spaced cloud (std 0, mean rounded) whole
    mask = mean <= mu + ratio * mean.std() + 1e-12 * mu
    return P[mask], mask
