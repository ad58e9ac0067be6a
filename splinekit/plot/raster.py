"""A z-buffer triangle rasterizer in numpy: orthographic views of triangles in 3-D.

Every pixel shows the nearest triangle that covers its centre, whatever order the
triangles come in, so surfaces that pierce or overlap each other (a teapot's spout
and body, the far wall seen through a hole) are drawn right. The work is done on
flat arrays of (triangle, pixel) candidates, a bounded number at a time: no Python
loop per triangle or pixel.

Conventions: pixel ``(row, col)`` has its centre at ``x = col + 0.5``, ``y = row + 0.5``
(rows grow downwards); depth grows towards the viewer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import limits

CANDIDATES_PER_PASS = 1 << 19
"""(triangle, pixel) candidates tested per pass: bounds the scratch memory (~100 bytes each)."""

_BYTES_PER_CANDIDATE = 112


def view_basis(elevation: float, azimuth: float):
    """``(eye, right, up)``: unit vectors ``(3,)`` of an orthographic camera at ``elevation``
    and ``azimuth`` in degrees (matplotlib's convention: azimuth about +z from +x,
    +z up on the screen). ``eye`` points from the scene towards the viewer."""
    e, a = np.radians(elevation), np.radians(azimuth)
    eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    right = np.array([-np.sin(a), np.cos(a), 0.0])
    return eye, right, np.cross(eye, right)


def project(points, view, width: int, height: int, fill: float = 0.92):
    """Screen coordinates of ``(n, 3)`` points seen along ``view`` = ``(elevation, azimuth)``.

    One scale for all three axes (true proportions), chosen so that the points'
    projected bounding box fills ``fill`` of the ``width x height`` frame, centred.
    Returns ``(xy (n, 2) in pixels, depth (n,) in model units (larger is nearer), scale)``,
    ``scale`` in pixels per model unit.
    """
    eye, right, up = view_basis(*view)
    points = np.asarray(points, dtype=np.float64)
    sx, sy, depth = points @ right, points @ up, points @ eye
    if not len(points):
        return np.zeros((0, 2)), depth, 1.0
    lo_x, hi_x, lo_y, hi_y = sx.min(), sx.max(), sy.min(), sy.max()
    span = max(hi_x - lo_x, 1e-300), max(hi_y - lo_y, 1e-300)
    scale = fill * min(width / span[0], height / span[1])
    x = 0.5 * width + scale * (sx - 0.5 * (lo_x + hi_x))
    y = 0.5 * height - scale * (sy - 0.5 * (lo_y + hi_y))
    return np.column_stack([x, y]), depth, float(scale)


@dataclass(frozen=True)
class Fragments:
    """What each pixel of a ``(height, width)`` frame shows: ``triangle`` ``(height, width)``
    the index of the nearest covering triangle (-1: background), ``weights``
    ``(height, width, 3)`` its barycentric coordinates there (0 on the background)
    and ``depth`` ``(height, width)`` (-inf on the background)."""

    triangle: np.ndarray
    weights: np.ndarray
    depth: np.ndarray

    @property
    def covered(self) -> np.ndarray:
        return self.triangle >= 0

    def interpolate(self, corner_values, covered=None) -> np.ndarray:
        """Values ``(n, ...)`` at the ``n`` covered pixels (row by row, as ``np.nonzero(covered)``
        lists them) of per-corner ``(T, 3, ...)`` data; ``covered`` may be passed when known."""
        corner_values = np.asarray(corner_values)
        hit = self.covered if covered is None else covered
        w = self.weights[hit]
        picked = corner_values[self.triangle[hit]].reshape(len(w), 3, -1)
        blend = w[:, 0, None] * picked[:, 0] + w[:, 1, None] * picked[:, 1] + w[:, 2, None] * picked[:, 2]
        return blend.reshape((len(w),) + corner_values.shape[2:])


def rasterize(xy, depth, width: int, height: int) -> Fragments:
    """Rasterize triangles given by screen corners ``xy`` ``(T, 3, 2)`` and corner depths
    ``depth`` ``(T, 3)`` into a ``width x height`` frame with a depth test.

    A pixel is covered when its centre lies inside or on the triangle; a shared edge is
    computed with the same numbers from both sides, so meshes show no cracks.
    Triangles seen edge-on (zero screen area) cover nothing.
    """
    xy = np.asarray(xy, dtype=np.float64)
    depth = np.asarray(depth, dtype=np.float64)
    limits.check(width * height * (8 + 8 + 24), "the z-buffer of a picture")
    z_buffer = np.full(width * height, -np.inf)
    winner = np.full(width * height, -1, dtype=np.int64)
    weights = np.zeros((width * height, 3))

    a, b, c = xy[:, 0], xy[:, 1], xy[:, 2]
    twice_area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    # edge i (from corner i+1 to corner i+2) as a linear function of the pixel centre,
    # w_i = ex * x + ey * y + e0, positive inside: twice the area of (p, corner i+1, corner i+2).
    # The reversed edge of a neighbour gets exactly the negated coefficients, hence no cracks.
    p, q = xy[:, [1, 2, 0]], xy[:, [2, 0, 1]]
    orient = np.sign(twice_area)[:, None]
    edges = np.concatenate([(p[..., 1] - q[..., 1]) * orient, (q[..., 0] - p[..., 0]) * orient,
                            (p[..., 0] * q[..., 1] - p[..., 1] * q[..., 0]) * orient], axis=1).T.copy()  # (9, T): ex, ey, e0
    lo, hi = xy.min(axis=1), xy.max(axis=1)
    # the pixels whose centres lie in each triangle's bounding box, clipped to the frame
    col0 = np.clip(np.ceil(lo[:, 0] - 0.5), 0, width).astype(np.int64)
    col1 = np.clip(np.floor(hi[:, 0] - 0.5), -1, width - 1).astype(np.int64)
    row0 = np.clip(np.ceil(lo[:, 1] - 0.5), 0, height).astype(np.int64)
    row1 = np.clip(np.floor(hi[:, 1] - 0.5), -1, height - 1).astype(np.int64)
    n_cols = np.maximum(col1 - col0 + 1, 0)
    counts = np.where(twice_area != 0, n_cols * np.maximum(row1 - row0 + 1, 0), 0)
    ends = np.cumsum(counts)
    total = int(ends[-1]) if len(ends) else 0

    for start in range(0, total, CANDIDATES_PER_PASS):  # bounded passes over the flat candidate list
        stop = min(start + CANDIDATES_PER_PASS, total)
        limits.check((stop - start) * _BYTES_PER_CANDIDATE, "rasterizing a picture")
        first, last = np.searchsorted(ends, [start, stop - 1], side="right")
        taken = counts[first:last + 1].copy()  # this pass's share of each triangle's candidates
        taken[-1] = stop - (ends[last] - counts[last])
        taken[0] = min(ends[first], stop) - start
        t = np.repeat(np.arange(first, last + 1), taken)
        local = np.arange(start, stop) - np.repeat(ends[first:last + 1] - counts[first:last + 1], taken)
        row, col = np.divmod(local, n_cols[t])
        row += row0[t]
        col += col0[t]
        x, y = col + 0.5, row + 0.5
        w = []
        for i in range(3):  # the three edge tests, dropping outside candidates as soon as one fails
            wi = edges[i][t] * x + edges[3 + i][t] * y + edges[6 + i][t]
            keep = wi >= 0
            t, x, y, w = t[keep], x[keep], y[keep], [wj[keep] for wj in w] + [wi[keep]]
        w = np.column_stack(w)
        w /= (w[:, 0] + w[:, 1] + w[:, 2])[:, None]
        pixel = (y - 0.5).astype(np.int64) * width + (x - 0.5).astype(np.int64)
        z = np.einsum("nk,nk->n", w, depth[t])
        # the nearest candidate per pixel against everything rasterized so far
        np.maximum.at(z_buffer, pixel, z)
        best = z >= z_buffer[pixel]
        winner[pixel[best]] = t[best]
        weights[pixel[best]] = w[best]
    return Fragments(winner.reshape(height, width), weights.reshape(height, width, 3), z_buffer.reshape(height, width))


def fan_triangles(corners: np.ndarray):
    """``(F (k - 2), 3)`` fan triangles of ``(F, k)`` polygon corners and the ``(F (k - 2),)``
    polygon each came from (k >= 3)."""
    corners = np.asarray(corners)
    k = corners.shape[1]
    fan = np.stack([np.zeros(k - 2, dtype=np.int64), np.arange(1, k - 1), np.arange(2, k)], axis=1)
    triangles = corners[:, fan].reshape(-1, 3)
    return triangles, np.repeat(np.arange(len(corners)), k - 2)
