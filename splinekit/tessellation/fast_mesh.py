"""The fast B-rep tessellation path: planes and right circular cylinders bounded by lines and
circles, meshed from a :class:`.fast_plan.FastPlan` with the tolerance-dependent work only.

Per call: every circle's segment count in closed form (the sagitta and the angle criterion, then
raised where a cylinder's parametric midpoints err more than the sagitta: its rational
parametrization does not run at uniform angle), the circles' points at uniform angle, each use's
``(u, v)`` through the exact maps of the plan, then per face: the fixed triangles of a
straight-edged plane, ear clipping of a plane's boundary polygon with holes
(``mapbox_earcut``), or a strip between a cylinder's two sides. The result is the same
:class:`.result.Tessellation` as the general path's, with the same guarantees: shared vertices
are shared indices, triangles follow the faces' orientation, normals are exact, and
``max_deviation`` is measured with the same yardstick (the surface at the parametric centre and
edge midpoints of every triangle against the flat point), in closed form: zero inside a plane up
to its points' offsets from it, and on a cylinder ``S(u, v) = C(u) + (v - v0) D`` the distance
of its circle at the barycentric ``u`` from the barycentric combination of the corners' circle
points. Where a call cannot keep a guarantee (ear clipping fails, a deviation or an angle over
the limit), it returns None and the caller runs the general path.
"""

from __future__ import annotations

import numpy as np

from .. import limits
from ..mesh.topology import ranges
from .edges import MAX_SEGMENTS
from .fast_plan import PLANE, cyl_param, planar_triangles
from .result import Tessellation
from .surfaces import BYTES_PER_TRIANGLE

__all__ = ["fast_tessellation"]

MAX_ROUNDS = 8
"""Largest number of rounds raising circle counts for the cylinders' parametric midpoints."""
BARY = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5], [1 / 3, 1 / 3, 1 / 3]])
"""Where a triangle is measured: its edges' midpoints and its centre (barycentric)."""


def _param_deviation(plan, n, tol):
    """``(A,)`` largest deviation of each arc's segments (``n + 1`` samples at uniform angle) at
    the parametric midpoints of the cylinder faces that use it (0 where none does)."""
    dev = np.zeros(len(n))
    for i in plan.arc_cyl_use:
        a = int(plan.arc_of[plan.use_group[i]])
        cmap = plan.cyl[int(plan.use_face[i])].cmap
        k = np.arange(n[a] + 1)
        off, sense = plan.use_arc_cyl[i]
        u = cyl_param(cmap, off + sense * plan.arc_sweep[a] * k / n[a])
        u0, u1 = plan.use_uv0[i, 0], plan.use_uv1[i, 0]
        u[0], u[-1] = (u1, u0) if plan.use_flip[i] else (u0, u1)
        th = cmap.angle(u)
        tm = cmap.angle(0.5 * (u[1:] + u[:-1]))
        dx = np.cos(tm) - 0.5 * (np.cos(th[1:]) + np.cos(th[:-1]))
        dy = np.sin(tm) - 0.5 * (np.sin(th[1:]) + np.sin(th[:-1]))
        dev[a] = max(dev[a], cmap.circle.radius * float(np.sqrt(dx * dx + dy * dy).max()))
    return dev


def _arc_counts(plan, tol, angle_tol):
    """``(A,)`` segments per circle arc, or None past :data:`.edges.MAX_SEGMENTS`."""
    r = plan.arc_r
    step = 2.0 * np.arccos(np.clip(1.0 - tol / r, -1.0, 1.0))
    if angle_tol is not None:
        step = np.minimum(step, angle_tol)
    n = np.ceil(plan.arc_sweep / step * (1.0 + 1e-9))
    n = np.maximum(n, np.where(plan.arc_closed, 3, 1)).astype(np.int64)
    for _ in range(MAX_ROUNDS):
        if n.size and n.max() > MAX_SEGMENTS:
            return None
        if plan.arc_cyl_use.size == 0:
            return n
        dev = _param_deviation(plan, n, tol)
        over = dev > tol
        if not over.any():
            return n
        n[over] = np.maximum(n[over] + 1, np.ceil(n[over] * np.sqrt(dev[over] / tol))).astype(np.int64)
    return None


def _zipper(bottom, top, ub, ut):
    """Counter-clockwise triangles ``(t, 3)`` of the strip between the point chains ``bottom``
    (at ``v = v_lo``) and ``top`` (at ``v = v_hi``), both in increasing ``u`` (``ub``, ``ut``)
    and sharing their first and last ``u``: the side whose next point comes first advances."""
    nb, nt = len(bottom) - 1, len(top) - 1
    order = np.argsort(np.concatenate([ub[1:], ut[1:]]), kind="stable")  # ties: bottom first
    is_b = order < nb
    i = np.cumsum(is_b) - is_b
    j = np.cumsum(~is_b) - ~is_b
    b_next = bottom[np.minimum(i + 1, nb)]
    t_next = top[np.minimum(j + 1, nt)]
    # a bottom step: (b_i, b_i+1, t_j); a top step: (b_i, t_j+1, t_j)
    return np.column_stack([bottom[i], np.where(is_b, b_next, t_next), top[j]])


def fast_tessellation(plan, tol, angle_tol):
    """The :class:`Tessellation` of the plan's faces at tolerance ``tol`` (model units) and
    ``angle_tol`` (radians or None), or None where the general path must do it."""
    n_arc = _arc_counts(plan, tol, angle_tol)
    if n_arc is None:
        return None
    arc_of, G = plan.arc_of, len(plan.arc_of)
    is_arc = arc_of >= 0
    m = np.full(G, 2, dtype=np.int64)
    m[is_arc] = n_arc[arc_of[is_arc]] + 1
    limits.check(int(m.sum()) * 4 * BYTES_PER_TRIANGLE, f"tessellation of trimmed faces at tolerance {tol:.3g}")
    goff = np.cumsum(m) - m
    # the samples of every group: ends are the welded corners, inner points numbered after them
    C = len(plan.corners)
    inner = m - 2
    base = C + np.cumsum(inner) - inner
    g_of = np.repeat(np.arange(G), m)
    j = np.arange(int(m.sum())) - goff[g_of]
    svid = base[g_of] + j - 1
    first, last = j == 0, j == m[g_of] - 1
    svid[first] = plan.end_vid[g_of[first], 0]
    svid[last] = plan.end_vid[g_of[last], 1]
    n_vid = C + int(inner.sum())
    sX = np.empty((len(j), 3))
    sX[first | last] = plan.corners[svid[first | last]]
    s_arc = arc_of[g_of]
    mid = np.flatnonzero(~first & ~last)
    a = s_arc[mid]
    stheta = np.zeros(len(j))
    stheta[mid] = plan.arc_sweep[a] * j[mid] / n_arc[a]
    th = stheta[mid][:, None]
    sX[mid] = plan.arc_c[a] + plan.arc_r[a][:, None] * (np.cos(th) * plan.arc_e1[a] + np.sin(th) * plan.arc_e2[a])
    # the loops' points: every use's samples in its own direction, its last one left to the next use
    ug = plan.use_group
    cnt = m[ug] - 1
    U = len(ug)
    owner = np.repeat(np.arange(U), cnt)
    ustart = np.cumsum(cnt) - cnt
    k = np.arange(int(cnt.sum())) - ustart[owner]
    idx = goff[ug][owner] + np.where(plan.use_flip[owner], cnt[owner] - k, k)
    pX, pvid, pface = sX[idx], svid[idx], plan.use_face[owner]
    puv = np.einsum("nij,nj->ni", plan.A[pface], pX) + plan.b[pface]
    for f, (cyl, sel_use) in plan.cyl_arc_uses.items():
        sel = np.flatnonzero(sel_use[owner])
        o = owner[sel]
        off, sense = plan.use_arc_cyl[o, 0], plan.use_arc_cyl[o, 1]
        puv[sel, 0] = cyl_param(cyl.cmap, off + sense * stheta[idx[sel]])
        puv[sel, 1] = plan.use_uv0[o, 1]
    puv[ustart] = plan.use_uv0
    # triangles, as indices into the loops' points
    F = len(plan.faces)
    fcount = np.bincount(pface, minlength=F)
    fstart = np.cumsum(fcount) - fcount
    tris = [plan.fixed_T + fstart[plan.fixed_face][:, None]]
    loop_size = np.add.reduceat(cnt, plan.loop_first)
    for f in plan.curved_planes:
        loops = plan.face_loops[f]
        ends = np.cumsum(loop_size[loops])
        s = int(fstart[f])
        T = planar_triangles(puv[s : s + int(ends[-1])], ends)
        if T is None:
            return None
        tris.append(T + s)
    cyl_tris = []
    for f, (order, nb) in plan.cyl_faces.items():
        bottom = np.append(ranges(ustart[order[:nb]], cnt[order[:nb]]), ustart[order[nb]])
        top = np.append(ranges(ustart[order[nb + 1 : -1]], cnt[order[nb + 1 : -1]]), ustart[order[-1]])[::-1]
        T = _zipper(bottom, top, puv[bottom, 0], puv[top, 0])
        tris.append(T)
        cyl_tris.append((f, T))
    T = np.concatenate(tris)
    tface = pface[T[:, 0]]
    # deviation: planes from their points' offsets, cylinders in closed form (see the docstring)
    plane_pt = plan.kind[pface] == PLANE
    off = np.einsum("ij,ij->i", pX[plane_pt] - plan.origin[pface[plane_pt]], plan.normal[pface[plane_pt]])
    max_dev = float(np.abs(off).max()) if off.size else 0.0
    for f, Tc in cyl_tris:
        cmap = plan.cyl[f].cmap
        th = cmap.angle(puv[Tc, 0])  # (t, 3)
        if angle_tol is not None and (np.ptp(th, axis=1) > angle_tol * (1.0 + 1e-9)).any():
            return None
        tm = cmap.angle(puv[Tc, 0] @ BARY.T)  # (t, 4)
        dx = np.cos(tm) - np.cos(th) @ BARY.T
        dy = np.sin(tm) - np.sin(th) @ BARY.T
        max_dev = max(max_dev, cmap.circle.radius * float(np.sqrt(dx * dx + dy * dy).max()))
    if max_dev > tol:
        return None
    flip = plan.reversed[tface]
    T = np.where(flip[:, None], T[:, [0, 2, 1]], T)
    # one representative loop point per vertex: its face, (u, v) and normal
    V = np.empty((n_vid, 3))
    V[svid] = sX
    rep = np.empty(n_vid, dtype=np.int64)
    rep[pvid[::-1]] = np.arange(len(pvid))[::-1]
    VP = pface[rep]
    N = plan.normal[VP]
    for f, cyl in plan.cyl.items():
        sel = np.flatnonzero(VP == f)
        d = V[sel] - cyl.cmap.circle.centre
        d -= np.outer(d @ cyl.axis, cyl.axis)
        s = cyl.sign * (-1.0 if plan.reversed[f] else 1.0)
        N[sel] = s * d / np.linalg.norm(d, axis=1, keepdims=True)
    return Tessellation._build(V, pvid[T], N, puv[rep], VP, tface, puv[T], max_dev, tol)

