"""Rotation-minimizing frames along a curve (the double reflection method).

Sweeps (:mod:`splinekit.construct.sweep`) move their profile in these frames;
:mod:`splinekit.diffgeom.curves` re-exports :func:`rotation_minimizing_frames`
beside the Frenet frame. Vectors are ``(n, 3)`` arrays; a planar curve is
embedded in the plane z = 0.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import as_float_array
from ..errors import DomainError, ParameterError
from .differential import _as_3d, _cross, _dot, _ders, _params, _perpendicular, _scales, _tangents, _unit

__all__ = ["rotation_minimizing_frames"]

_COINCIDENT = 1e-8  # relative chord length under which two RMF samples count as one point


def rotation_minimizing_frames(curve, u, normal=None):
    """Rotation-minimizing frames ``(T, N, B)``, each ``(n, 3)``, along sorted parameters ``u`` ``(n,)``.

    The double reflection method (Wang, Juettler, Zheng, Liu, *Computation of
    rotation minimizing frames*, ACM TOG 27(1), 2008): the frame at ``u[i+1]``
    is the frame at ``u[i]`` reflected in the bisector plane of the two curve
    points, then in the plane that maps the reflected tangent onto the tangent
    at ``u[i+1]``. Its global error is ``O(h**4)`` in the step ``h``; ``N``
    has no rotation about ``T`` (``dN/ds`` is parallel to ``T``) up to that error.

    Parameters
    ----------
    curve
        A 3-D curve (a planar 2-D one is embedded in the plane z = 0).
    u : array_like, shape (n,)
        Non-decreasing parameters (repeated values give repeated frames).
    normal : array_like, shape (3,), optional
        Start normal; it is projected orthogonal to the start tangent and
        normalized. Default: the coordinate axis least aligned with the start
        tangent (the first on ties), made orthogonal to it.

    Returns
    -------
    T, N, B : ndarray, shape (n, 3)
        Unit tangents (as :func:`splinekit.diffgeom.curves.tangent`), rotation-minimizing normals and
        ``B = T x N``.

    The reflections are built for all steps at once. A pair of reflections is
    a rotation, kept as a unit quaternion (a lone reflection, where the second
    one is skipped, as minus a half-turn and a sign); their sequential
    composition is a blocked prefix product of the quaternions
    (:func:`_prefix_products`), so no Python loop runs per frame. The normals
    are re-orthogonalized against ``T`` at the end.
    """
    u = _params(u)
    if u.ndim != 1 or u.size == 0:
        raise ParameterError(f"u must be a non-empty 1-D array of parameters, got shape {u.shape}")
    steps = np.diff(u)
    if (steps < 0).any():
        i = int(np.flatnonzero(steps < 0)[0])
        raise ParameterError(
            f"u must be sorted (non-decreasing): u[{i}] = {float(u[i])!r} > u[{i + 1}] = {float(u[i + 1])!r}"
        )
    d = _ders(curve, u, 1)
    size, length = _scales(curve)
    T, defined, _ = _tangents(curve, u, d[1], size, length)
    if not defined.all():
        u0 = float(u[np.flatnonzero(~defined)[0]])
        raise DomainError(f"the curve has no tangent direction at u = {u0!r} (every derivative vanishes)")
    X = _as_3d(d[0], "rotation_minimizing_frames")
    T = _as_3d(T, "rotation_minimizing_frames")
    r0 = _start_normal(T[0], normal)
    R = np.empty((u.size, 3))
    R[0] = r0
    if u.size > 1:
        q, sign = _double_reflections(X, T, size)
        R[1:] = _rotate(_prefix_products(q), r0) * np.cumprod(sign)[:, None]
        # rounding in the long product: put N back exactly orthogonal to T
        R -= _dot(R, T)[:, None] * T
        R = _unit(R)
    return T, R, _cross(T, R)


def _start_normal(t0: np.ndarray, normal) -> np.ndarray:
    if normal is None:
        return _perpendicular(t0[None, :])[0]
    v = as_float_array(normal, "normal")
    if v.shape != (3,) or not np.isfinite(v).all():
        raise ParameterError(f"normal must be 3 finite numbers, got {np.asarray(normal).tolist()!r}")
    peak = float(np.abs(v).max())
    if peak > 0:
        v = v / peak  # only the direction matters; scaled first so that no product overflows
    norm = float(np.linalg.norm(v))
    w = v - float(v @ t0) * t0
    wn = float(np.linalg.norm(w))
    if not wn > 1e-9 * norm:
        raise ParameterError(
            f"normal {v.tolist()} is zero or parallel to the start tangent {t0.tolist()}; "
            "it must have a component orthogonal to it"
        )
    return w / wn


def _double_reflections(X: np.ndarray, T: np.ndarray, size: float):
    """Step maps as quaternions ``(n - 1, 4)`` ``(w, x, y, z)`` and signs ``(n - 1,)``.

    Step ``i`` maps the frame at ``i`` onto the one at ``i + 1`` by ``H2 H1``,
    ``H = I - 2 m m^T`` the reflection in the plane with unit normal ``m``:
    ``m1`` along the chord ``X[i+1] - X[i]``, ``m2`` along ``T[i+1] - H1 T[i]``.
    As ``H = -(half-turn about m)`` and a half-turn is the pure quaternion
    ``(0, m)``, ``H2 H1`` is the quaternion ``(0, m2)(0, m1) = (-m2.m1, m2 x m1)``
    with sign +1. Where two samples coincide (a repeated parameter) the chord's
    direction is rounding noise, so ``T[i]`` stands in for it (the limit of the
    chord direction as the step shrinks) and the step is the smallest rotation
    taking ``T[i]`` to ``T[i+1]``. Where ``T[i+1] - H1 T[i]`` vanishes the second
    reflection is skipped, as in the paper: quaternion ``(0, m1)``, sign -1.
    """
    # chords in units of the curve's size: squares of raw chords overflow beyond ~1e154
    Xs = X / size if size > 0 else X
    v1 = Xs[1:] - Xs[:-1]
    c1 = _dot(v1, v1)
    close = c1 <= _COINCIDENT**2
    m1 = np.where(close[:, None], T[:-1], v1 / np.sqrt(np.where(close, 1.0, c1))[:, None])
    tL = T[:-1] - (2.0 * _dot(m1, T[:-1]))[:, None] * m1
    v2 = T[1:] - tL
    c2 = _dot(v2, v2)
    skip = c2 <= 1e-20
    m2 = v2 / np.sqrt(np.where(skip, 1.0, c2))[:, None]
    q = np.empty((v1.shape[0], 4))
    q[:, 0] = -_dot(m2, m1)
    q[:, 1:] = _cross(m2, m1)
    q[skip, 0] = 0.0
    q[skip, 1:] = m1[skip]
    return q, np.where(skip, -1.0, 1.0)


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products ``a b`` of quaternion arrays ``(..., 4)``."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q v q*`` ``(n, 3)`` for unit quaternions ``q`` ``(n, 4)`` and one vector ``v`` ``(3,)``."""
    w, qv = q[:, :1], q[:, 1:]
    t = 2.0 * _cross(qv, v)
    return v + w * t + _cross(qv, t)


def _prefix_products(q: np.ndarray) -> np.ndarray:
    """``P[k] = q[k] q[k-1] ... q[0]`` for quaternions ``(m, 4)``.

    Blocked scan: the ``m`` quaternions are cut into about ``sqrt(m)`` blocks
    of about ``sqrt(m)``; the running products inside every block advance
    together (one batched product per position in a block), then the block
    totals are scanned the same way (recursively) and applied to every block
    in one batched product: about ``2 m`` products in ``2 sqrt(m)`` Python steps.
    """
    m = q.shape[0]
    if m <= 16:
        P = q.copy()
        for k in range(1, m):
            P[k] = _qmul(P[k], P[k - 1])
        return P
    width = math.ceil(math.sqrt(m))
    blocks = -(-m // width)
    Q = np.zeros((blocks * width, 4))
    Q[:m] = q
    Q[m:, 0] = 1.0  # identity padding
    Q = Q.reshape(blocks, width, 4)
    for j in range(1, width):
        Q[:, j] = _qmul(Q[:, j], Q[:, j - 1])
    before = _prefix_products(Q[:, -1])  # product of blocks 0..b
    Q[1:] = _qmul(Q[1:], before[:-1, None, :])
    return Q.reshape(-1, 4)[:m]

