"""Row-wise vector helpers of the mesh geometry (:mod:`splinekit.mesh.geometry`): cross and dot
products of vectors stored by component ``(d, m)``, sums into bins, unit rows.

Two numpy costs shape them: a reduction along a short last axis (``max(axis=1)`` of ``(m, 3)``)
costs about 20 times a loop over the three columns, and whole-mesh temporaries (24 MB per
million rows) cost page faults and cache misses, so :func:`normalize_rows` works in chunks.
"""

from __future__ import annotations

import numpy as np

__all__ = ["CHUNK", "cross", "cross_norm", "cross_rows", "dot", "normalize_rows", "per_vertex"]

CHUNK = 65_536
"""Rows per pass where a helper works in chunks (the temporaries of a chunk stay in cache)."""


def cross(u, v):
    """Cross product of 3-D vectors stored by component: ``u, v`` are ``(3, m)``."""
    return np.stack([u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]])


def cross_rows(a, b, out):
    """``out[i] = a[i] x b[i]`` for rows of 3-D vectors ``a, b`` ``(m, 3)``: the same products in
    the same order as :func:`cross`, column by column into ``out`` ``(m, 3)`` (fewer temporaries)."""
    np.multiply(a[:, 1], b[:, 2], out=out[:, 0])
    out[:, 0] -= a[:, 2] * b[:, 1]
    np.multiply(a[:, 2], b[:, 0], out=out[:, 1])
    out[:, 1] -= a[:, 0] * b[:, 2]
    np.multiply(a[:, 0], b[:, 1], out=out[:, 2])
    out[:, 2] -= a[:, 1] * b[:, 0]
    return out


def cross_norm(u, v):
    """``|u x v|`` of vectors stored by component, ``(d, m)``, for any ``d`` (Lagrange identity)."""
    d = u.shape[0]
    if d == 3:
        c = cross(u, v)
        return np.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
    acc = np.zeros(u.shape[1:])
    for a in range(d):
        for b in range(a + 1, d):
            t = u[a] * v[b] - u[b] * v[a]
            acc += t * t
    return np.sqrt(acc)


def dot(u, v):
    """Row-wise dot product of vectors stored by component ``(d, m)``."""
    return np.einsum("dm,dm->m", u, v)


def per_vertex(index, values, n):
    """Sum ``values`` (``(m,)``, or ``(d, m)`` by component) into ``n`` bins by ``index`` (``(m,)``).

    Returns ``(n,)`` or ``(n, d)``.
    """
    index = np.asarray(index).ravel()
    if values.ndim == 1:
        return np.bincount(index, weights=values, minlength=n).astype(np.float64)
    out = np.empty((n, values.shape[0]))
    for c in range(values.shape[0]):
        out[:, c] = np.bincount(index, weights=values[c], minlength=n)
    return out


def normalize_rows(X):
    """Unit rows of ``X`` ``(m, d)``; zero rows stay zero (never NaN).

    Each row is first divided by its largest ``|component|`` (so that squaring can neither
    overflow nor underflow), then by its length.
    """
    out = np.zeros_like(X)
    for s in range(0, len(X), CHUNK):
        x = X[s:s + CHUNK]
        scale = np.zeros((len(x), 1))
        for c in range(X.shape[1]):  # by columns, not max(axis=1)
            np.maximum(scale[:, 0], np.abs(x[:, c]), out=scale[:, 0])
        Y = np.divide(x, scale, out=np.zeros_like(x), where=scale > 0)
        n = np.sqrt(np.einsum("ij,ij->i", Y, Y))[:, None]
        np.divide(Y, n, out=out[s:s + CHUNK], where=n > 0)
    return out
