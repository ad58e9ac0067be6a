"""Derivatives of rational curves and surfaces from those of their homogeneous
form (The NURBS Book, A4.2 and A4.4), vectorized over points."""

from __future__ import annotations

from math import comb

import numpy as np


def rational_curve_derivatives(hders: np.ndarray) -> np.ndarray:
    """A4.2: ``hders`` ``(d + 1, m, dim + 1)`` homogeneous derivatives -> ``(d + 1, m, dim)``."""
    A = hders[..., :-1]
    w = hders[..., -1:]
    out = np.empty_like(A)
    for k in range(hders.shape[0]):
        v = A[k].copy()
        for i in range(1, k + 1):
            v -= comb(k, i) * w[i] * out[k - i]
        out[k] = v / w[0]
    return out


def rational_surface_derivatives(hders: np.ndarray) -> np.ndarray:
    """A4.4: ``hders`` ``(d + 1, d + 1, m, dim + 1)`` -> ``(d + 1, d + 1, m, dim)``.

    Fills every ``[k, l]`` with ``k, l <= d`` (not only ``k + l <= d``).
    """
    A = hders[..., :-1]
    w = hders[..., -1:]
    d = hders.shape[0] - 1
    out = np.empty_like(A)
    for k in range(d + 1):
        for l in range(d + 1):
            v = A[k, l].copy()
            for j in range(1, l + 1):
                v -= comb(l, j) * w[0, j] * out[k, l - j]
            for i in range(1, k + 1):
                v -= comb(k, i) * w[i, 0] * out[k - i, l]
                v2 = np.zeros_like(v)
                for j in range(1, l + 1):
                    v2 += comb(l, j) * w[i, j] * out[k - i, l - j]
                v -= comb(k, i) * v2
            out[k, l] = v / w[0, 0]
    return out
