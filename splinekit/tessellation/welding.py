"""Coincident points and the connected sets they form.

The tessellator welds grid-border vertices that lie within the weld distance (the
patches' shared edges, collapsed edges) and links cell edges that coincide; both need
the close pairs of a point set (:func:`close_pairs`) and the connected components of
the resulting links (:func:`components`). Compiled kernels serve both once loaded
(:mod:`splinekit._kernels`); else the numpy versions in :mod:`splinekit.brep.links` (the same
results), which brep's own edge pairing and vertex clustering use.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels
from ..brep.links import SWEEP, close_pairs as sweep_pairs, kd_pairs, link_components

__all__ = ["SWEEP", "close_pairs", "components"]


def close_pairs(X, r):
    """``(k, 2)`` index pairs ``i != j`` of the points ``X`` ``(n, 3)`` at most ``r`` apart
    (each pair once): the sweep of :func:`splinekit.brep.links.close_pairs`, compiled once
    loaded (the same pairs; a k-d tree where the sweep would compare too many)."""
    n = len(X)
    if n < 2:
        return np.zeros((0, 2), dtype=np.int64)
    jit = _kernels.get("splinekit.tessellation._kernels")
    if jit is not None:
        pairs, ok = jit.close_pairs(np.ascontiguousarray(X, dtype=np.float64), float(r), SWEEP, 16 * n + 1000)
        if ok:
            return pairs
        return kd_pairs(X, r)
    return sweep_pairs(X, r)


def components(n, a, b):
    """``(n,)`` label of each of ``n`` nodes linked by the edges ``a[k] - b[k]``: the smallest
    node of its connected component. The compiled union-find once loaded, else
    :func:`splinekit.brep.links.link_components` (whole-array rounds; the same labels)."""
    jit = _kernels.get("splinekit.tessellation._kernels")
    if jit is not None:
        return jit.components(int(n), np.ascontiguousarray(a, dtype=np.int64), np.ascontiguousarray(b, dtype=np.int64))
    return link_components(n, a, b)
