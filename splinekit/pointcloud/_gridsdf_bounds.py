"""Lower bounds of the distance from a point, and from a block of grid samples, to a triangle or
to a box of the triangle hierarchy: the tests of the grid kernel
:mod:`splinekit.pointcloud._gridsdf_kernels` (whose module notes give the argument), compiled
with numba and inlined there.

A triangle's bound (:func:`bound2`, :func:`margin`) reads 20 coefficients (``NB``): its unit
plane normal and offset, its three edge lines (unit in-plane normals pointing out and offsets)
and its bounding disk (centroid, radius), made by ``MeshDistance._bvh_prisms``. With ``p`` the
signed distance to the plane and ``v`` the in-plane offset of the point's foot from the
centroid, ``d(x, t) >= sqrt(p^2 + max(0, max_k (u_k . x - u_k . a_k), |v| - rho)^2)``: exact where
``x`` faces the triangle or one of its edges, within the disk's slack beyond a vertex. A sliver
whose normal rounding could turn gets zero coefficients and an infinite disk: its bound is zero
and it is always measured.
"""

from __future__ import annotations

import numpy as np
from numba import njit

FAR = 2.0
"""A block is handled by its candidate list when its centre is farther than this many
half-diagonals from the surface (the upper bound needs more than one)."""

SLACK = 1e-12
"""Relative margin of the block tests against rounding (they only prune; a wider margin only
measures a few more triangles)."""


TOL = 1e-9
"""Absolute margin (unit box) of the candidates' bounds: a triangle lies on its computed plane
and inside its computed edge lines and disk up to rounding of about ``1e-16`` times its size
(a triangle too thin for that gets no bound, module notes); the bounds are lowered by this much."""


@njit(cache=True, inline="always")
def may_hold(vx, vy, vz, rho, flat, D, eps, gx, gy, gz, hn):
    """False when no triangle within the ball of radius ``rho`` at ``c - v`` (``v = (vx, vy, vz)``)
    can pass the block test ``d_t - D - eps <= sum_i h_i |g_c,i - g_t,i|`` (module notes):
    its closest point ``q`` lies in the ball, so ``d_t >= max(|v| - rho, flat)`` (``flat`` a
    lower bound from the triangle's plane, or 0), and the unit vector ``g_t = (c - q) / d_t`` is
    within ``2 rho / |v|`` of ``v / |v|``; ``sum_i h_i |.| <= |h| |.|`` (``hn = |h|``)."""
    mc = np.sqrt(vx * vx + vy * vy + vz * vz)
    if mc <= 2.0 * rho:
        return True
    ex, ey, ez = gx - vx / mc, gy - vy / mc, gz - vz / mc
    turn = np.sqrt(ex * ex + ey * ey + ez * ez) + 2.0 * rho / mc
    return max(mc - rho, flat) - D - eps <= hn * turn * (1.0 + SLACK) + SLACK * (D + hn)


NB = 20
"""Bound coefficients per candidate (``prism`` rows, module notes)."""


@njit(cache=True, inline="always")
def tangent(cv, e, px, py, pz):
    """Candidate ``e``'s bound at ``p`` (unsquared; :func:`bound2` squared) and its gradient there:
    ``(b, gx, gy, gz)``. The bound is convex in ``p`` (module notes), so ``b + g . (x - p)``
    bounds it from below everywhere (the block test, :func:`block_test`); at a kink the selects
    pick one active piece, whose gradient is a subgradient. Branch-free (selects), so that the
    loop over the candidates vectorizes: every coefficient is read once into a local (reading
    one twice kept numba 0.68's loop from vectorizing)."""
    n0, n1, n2 = cv[0, e], cv[1, e], cv[2, e]
    u0x, u0y, u0z = cv[4, e], cv[5, e], cv[6, e]
    u1x, u1y, u1z = cv[8, e], cv[9, e], cv[10, e]
    u2x, u2y, u2z = cv[12, e], cv[13, e], cv[14, e]
    hh = px * n0 + py * n1 + pz * n2 - cv[3, e]
    s0 = px * u0x + py * u0y + pz * u0z - cv[7, e]
    s1 = px * u1x + py * u1y + pz * u1z - cv[11, e]
    s2 = px * u2x + py * u2y + pz * u2z - cv[15, e]
    vx = px - cv[16, e] - hh * n0
    vy = py - cv[17, e] - hh * n1
    vz = pz - cv[18, e] - hh * n2
    lv = np.sqrt(vx * vx + vy * vy + vz * vz)
    sd = lv - cv[19, e]
    # the largest in-plane part and its gradient (unit direction)
    c1 = s1 > s0
    ss, ux, uy, uz = (s1 if c1 else s0), (u1x if c1 else u0x), (u1y if c1 else u0y), (u1z if c1 else u0z)
    c2 = s2 > ss
    ss, ux, uy, uz = (s2 if c2 else ss), (u2x if c2 else ux), (u2y if c2 else uy), (u2z if c2 else uz)
    cd = sd > ss
    il = 1.0 / max(lv, 1e-300)
    ss, ux, uy, uz = (sd if cd else ss), (vx * il if cd else ux), (vy * il if cd else uy), (vz * il if cd else uz)
    a = max(abs(hh) - TOL, 0.0)
    a = a if hh >= 0.0 else -a
    ss = max(ss - TOL, 0.0)
    bl = np.sqrt(a * a + ss * ss)
    ib = 1.0 / max(bl, 1e-300)
    return bl, (a * n0 + ss * ux) * ib, (a * n1 + ss * uy) * ib, (a * n2 + ss * uz) * ib


@njit(cache=True, inline="always")
def block_test(bl, tx, ty, tz, hx, hy, hz, gx, gy, gz, top):
    """The block test of a candidate whose bound at the block's centre is ``bl`` with gradient
    ``t`` (:func:`tangent`), for a block of half extents ``h``, upper bound's gradient ``g`` and
    ``top`` = ``D + eps`` plus margin: positive when the bound, linearized at the centre (it is
    convex, so that bounds it from below), stays above the upper bound all over the block
    (module notes of the grid kernel). A zero bound (the centre on the triangle's prism)
    always passes."""
    turn = hx * abs(gx - tx) + hy * abs(gy - ty) + hz * abs(gz - tz)
    return bl - top - turn * (1.0 + SLACK) if bl > 0.0 else -1.0


@njit(cache=True, inline="always")
def margin(cv, e, px, py, pz, hx, hy, hz, gx, gy, gz, top):
    """The block test of candidate ``e`` for a block with centre ``p`` (:func:`block_test` of its
    :func:`tangent`); branch-free, so that the loop over the candidates vectorizes."""
    bl, tx, ty, tz = tangent(cv, e, px, py, pz)
    return block_test(bl, tx, ty, tz, hx, hy, hz, gx, gy, gz, top)


@njit(cache=True, inline="always")
def bound2(cv, e, px, py, pz):
    """Squared lower bound of the distance from ``p`` to candidate ``e``'s triangle (module
    notes): plane part squared plus in-plane part squared, each lowered by :data:`TOL`;
    branch-free, every coefficient read once (as in :func:`margin`)."""
    n0, n1, n2 = cv[0, e], cv[1, e], cv[2, e]
    hh = px * n0 + py * n1 + pz * n2 - cv[3, e]
    s0 = px * cv[4, e] + py * cv[5, e] + pz * cv[6, e] - cv[7, e]
    s1 = px * cv[8, e] + py * cv[9, e] + pz * cv[10, e] - cv[11, e]
    s2 = px * cv[12, e] + py * cv[13, e] + pz * cv[14, e] - cv[15, e]
    vx = px - cv[16, e] - hh * n0
    vy = py - cv[17, e] - hh * n1
    vz = pz - cv[18, e] - hh * n2
    sd = np.sqrt(vx * vx + vy * vy + vz * vz) - cv[19, e]
    ss = max(max(s0, s1, s2, sd) - TOL, 0.0)
    hh = max(abs(hh) - TOL, 0.0)
    return hh * hh + ss * ss
