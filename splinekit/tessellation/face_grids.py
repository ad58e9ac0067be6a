"""The interior parameter grid of each trimmed face (step 1 of :mod:`.trimmed`).

Each face's surface is cut into Bézier cells; the a-priori bounds on the second derivatives
give each cell its ``nu x nv`` steps and a knot span row (column) takes the largest count of its
cells; that grid is evaluated once (one batch evaluation of every face) and each span's count is
lowered to what its measured chord error needs.
"""

from __future__ import annotations

import numpy as np

from .counts import initial_counts
from .grids import span_params

__all__ = ["FaceGrid", "face_grids"]

GRID_FRACTION = 0.75
"""The a-priori grid steps are bounds over whole cells; the interior grid starts at this
fraction of them and the measured refinement adds points where the bound was needed."""
MEASURED_FRACTION = 0.4
"""The interior grid's steps are set so that their measured chord error along each parameter
direction is this fraction of the tolerance (a triangle's diagonal then errs by about the sum)."""
MIN_LOWERING = 0.5
"""The measured counts are at least this fraction of the a-priori ones."""


class FaceGrid:
    """A face's interior parameter grid ``us`` x ``vs`` and its scale (steps per parameter unit)."""

    __slots__ = ("us", "vs", "scale")


def face_grids(batch, tol, angle_tol, bounds=None, memo=None):
    """The interior grid of every surface of ``batch`` (a :class:`.batch.SurfaceBatch`): per knot
    span row (column) the largest a-priori count of its cells, times :data:`GRID_FRACTION`, then
    lowered where the grid's MEASURED chord error allows (:func:`_measured_counts`)
    (``bounds``: the cell sets' second-derivative bounds, when already known; ``memo``: a dict
    kept with the face set, where the angle criterion's counts, which do not depend on ``tol``,
    are kept).

    A face whose every cell needs one step in both directions (a plane, or a surface flat
    within a small fraction of the tolerance) gets its knot breaks as its grid without further
    work: lowering never goes below one step, so the result is the same, and the planar faces
    of a machined part (most of its faces) then cost no per-face Python work here."""
    nu, nv = initial_counts(batch.cellsets, tol, angle_tol, bounds)
    if angle_tol is not None:  # the angle criterion's own counts: a floor for the measured ones
        memo = {} if memo is None else memo
        if memo.get("angle", (None,))[0] != angle_tol:
            memo["angle"] = angle_tol, initial_counts(batch.cellsets, np.inf, angle_tol, bounds)
        au, av = memo["angle"][1]
    else:
        au, av = np.ones_like(nu), np.ones_like(nv)
    # faces whose cells all have one step per direction (cells of a face are contiguous)
    order = np.argsort(batch.first, kind="stable")
    top = np.maximum.reduceat(np.maximum(nu, nv), batch.first[order])
    single = np.empty(len(order), dtype=bool)
    single[order] = top <= 1
    counts = {}
    for k in np.flatnonzero(~single):
        cells = slice(batch.first[k], batch.first[k] + batch.nsu[k] * batch.nsv[k])
        shape = (batch.nsu[k], batch.nsv[k])

        def per_span(c, axis):
            return np.maximum(np.ceil(c[cells].reshape(shape).max(axis=axis) * GRID_FRACTION), 1).astype(np.int64)

        counts[k] = (per_span(nu, 1), per_span(nv, 0), per_span(au, 1), per_span(av, 0))
    lowered = _measured_counts(batch, counts, tol)
    out = []
    for k in range(len(batch.bu)):
        bu, bv = batch.bu[k], batch.bv[k]
        g = FaceGrid()
        if single[k]:
            g.us, g.vs = bu, bv
            g.scale = np.array([(bu.size - 1) / (bu[-1] - bu[0]), (bv.size - 1) / (bv[-1] - bv[0])])
            out.append(g)
            continue
        cu, cv = lowered[k]
        g.us, _ = span_params(bu, cu)
        g.vs, _ = span_params(bv, cv)
        # the scaled plane stays the a-priori one: edges keep their sampling, and Delaunay its
        # metric near collapsed edges (a cone's apex), where a coarser one flips triangles
        g.scale = np.array([counts[k][0].sum() / (bu[-1] - bu[0]), counts[k][1].sum() / (bv[-1] - bv[0])])
        out.append(g)
    return out


def _measured_counts(batch, counts, tol):
    """Per face, the a-priori per-span counts ``(cu, cv)`` lowered to what the grid's measured
    chord error needs: the a-priori counts come from bounds over whole cells (a sphere's
    equator sets its count up to the poles; a rational arc's fastest end sets the whole arc's),
    so the grid is evaluated once, each span's largest second difference along u (v) gives the
    chord error of its steps (``|second difference| / 8``), and the span's count is scaled so
    that it becomes :data:`MEASURED_FRACTION` of ``tol``, never above the a-priori count nor
    below the angle criterion's (``counts``: face index -> ``(cu, cv, angle cu, angle cv)``).
    One batch evaluation of every face's grid. Returns ``{face: (cu, cv)}``."""
    if not counts:
        return {}
    fs, us, vs, grids = [], [], [], {}
    for k, (cu, cv, _, _) in counts.items():
        u, _ = span_params(batch.bu[k], cu)
        v, _ = span_params(batch.bv[k], cv)
        fs.append(np.full(u.size * v.size, k))
        us.append(np.repeat(u, v.size))
        vs.append(np.tile(v, u.size))
        grids[k] = (u, v)
    X = batch.evaluate(np.concatenate(fs), np.concatenate(us), np.concatenate(vs))
    out, start = {}, 0
    for k, (cu, cv, au, av) in counts.items():
        u, v = grids[k]
        n = u.size * v.size
        G = X[start : start + n].reshape(u.size, v.size, 3)
        start += n
        out[k] = (_lowered(G, u, batch.bu[k], cu, au, tol), _lowered(G.transpose(1, 0, 2), v, batch.bv[k], cv, av, tol))
    return out


def _lowered(G, t, breaks, c, floor, tol):
    """Counts ``c`` per span of the grid lines along axis 0 of ``G`` ``(n, m, 3)`` (parameters
    ``t`` ``(n,)`` over spans ``breaks``) scaled to the measured chord error (see
    :func:`_measured_counts`)."""
    if G.shape[0] < 3:
        return c
    d2 = G[:-2] - 2.0 * G[1:-1] + G[2:]
    m = np.sqrt(np.einsum("ijk,ijk->ij", d2, d2)).max(axis=1)  # (n - 2,) largest over the lines
    span = np.clip(np.searchsorted(breaks, t[1:-1], side="right") - 1, 0, c.size - 1)
    worst = np.zeros(c.size)
    np.maximum.at(worst, span, m)
    factor = np.sqrt(worst / (8.0 * MEASURED_FRACTION * tol))
    # at most halved: lines that measure straight (a cone's rulings) keep some interior points,
    # without which the triangles fanning from a collapsed edge (the apex) flip
    low = np.maximum(np.minimum(floor, c), np.ceil(MIN_LOWERING * c))
    return np.clip(np.ceil(c * factor), low, c).astype(np.int64)
