"""The fast B-rep tessellation path: planes and right circular cylinders bounded by lines and
circles (and faces of revolution: :mod:`.latitude`), meshed from a :class:`.fast_plan.FastPlan`
with the tolerance-dependent work only.

Per call: every circle's segment count in closed form (the sagitta and the angle criterion, the
sagitta scaled by ``sqrt(1 + kappa^2)`` where a cylinder uses the circle: its rational
parametrization does not run at uniform angle, so a parametric midpoint strays along the circle
by up to ``kappa step^2 / 8``), the circles' points at uniform angle, each use's
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

A face set without circles has the same mesh at every tolerance: it is kept with the plan. The
rest is a fixed cost of about 150 numpy calls (300-400 us for a cylinder or a box with a hole),
so once the compiled kernels are loaded (:mod:`splinekit._kernels`: at once with
``SPLINEKIT_NUMBA=1``, else once the session's work pays for loading them) the steps between the
counts and the result run in two compiled passes around the ear clipping (:mod:`._fast_kernels`).
"""

from __future__ import annotations

import mapbox_earcut as earcut
import numpy as np

from .. import _kernels, limits
from ..mesh.topology import ranges
from .edges import MAX_SEGMENTS
from .fast_plan import REVOLUTION
from .latitude import mesh_rows, row_counts, tie
from .result import Tessellation
from .surfaces import BYTES_PER_TRIANGLE

__all__ = ["fast_tessellation"]

KERNELS = "splinekit.tessellation._fast_kernels"
FIXED_WORK = 300
"""Work of one call on the numpy path apart from its points (point-equivalents, see
:mod:`splinekit._kernels`: about its cost in microseconds), counted towards loading the kernels."""

BARY = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5], [1 / 3, 1 / 3, 1 / 3]])
"""Where a triangle is measured: its edges' midpoints and its centre (barycentric)."""


def _arc_counts(plan, tol, angle_tol):
    """``(A,)`` segments per circle arc: the largest uniform angular step whose sagitta (times
    the arc's cylinder factor, see :func:`.fast_plan._derive`) is within ``tol`` and which meets
    the angle criterion; None past :data:`.edges.MAX_SEGMENTS`."""
    step = 2.0 * np.arccos(np.maximum(1.0 - tol / (plan.arc_r * plan.arc_factor), -1.0))
    if angle_tol is not None:
        step = np.minimum(step, angle_tol)
    n = np.maximum(np.ceil(plan.arc_sweep / step * (1.0 + 1e-9)), plan.arc_min).astype(np.int64)
    if plan.lat is not None:
        n = tie(plan.lat, n)
    return None if n.size and n.max() > MAX_SEGMENTS else n


def _zipper(plan, ustart, cnt, puv):
    """Counter-clockwise triangles ``(t, 3)`` (loop point indices) of every cylinder's strip
    between its bottom chain (``v = v_lo``) and its top chain (``v = v_hi``), both in increasing
    ``u`` from ``u_lo`` to ``u_hi``: at each step the chain whose next point comes first
    advances (ties: the bottom). All cylinders at once: the steps are sorted by ``2 slot + u``
    (``u`` scaled to [0, 1]). Returns ``(triangles, slot of each)``."""
    cb, ct = cnt[plan.zb_use], cnt[plan.zt_use]
    bp = ranges(ustart[plan.zb_use], cb)
    tp = ranges(ustart[plan.zt_use], ct)[::-1]
    bq = np.repeat(plan.zb_slot, cb)
    ub, ut = puv[bp, 0], puv[tp, 0]
    if len(bp) == len(tp) and (np.abs(ub - ut) <= 1e-9 * (plan.slot_hi - plan.slot_lo)[bq]).all():
        # both chains at the same u up to rounding (the usual cylinder: two circles cut alike):
        # two triangles per step, as the merge below makes them where the u are equal
        step = np.ones(len(bp), dtype=bool)
        step[np.cumsum(np.bincount(bq)) - 1] = False  # each chain's last point starts no step
        i = np.flatnonzero(step)
        T = np.empty((2 * i.size, 3), dtype=np.int64)
        T[0::2, 0], T[0::2, 1], T[0::2, 2] = bp[i], bp[i + 1], tp[i]
        T[1::2, 0], T[1::2, 1], T[1::2, 2] = bp[i + 1], tp[i + 1], tp[i]
        return T, np.repeat(bq[i], 2)
    tq = np.repeat(plan.zt_slot, ct)[::-1]
    span = plan.slot_hi - plan.slot_lo
    kb = 2.0 * bq + (ub - plan.slot_lo[bq]) / span[bq] - 1e-9  # ties within 1e-9 of the span: bottom
    kt = 2.0 * tq + (ut - plan.slot_lo[tq]) / span[tq]
    # every point but each chain's first is a step
    sb = np.ones(len(bp), dtype=bool)
    sb[np.cumsum(np.bincount(bq, minlength=len(span))) - np.bincount(bq, minlength=len(span))] = False
    st = np.ones(len(tp), dtype=bool)
    st[np.cumsum(np.bincount(tq, minlength=len(span))) - np.bincount(tq, minlength=len(span))] = False
    keys = np.concatenate([kb[sb], kt[st]])
    order = np.argsort(keys, kind="stable")
    is_b = order < int(sb.sum())
    q = (keys[order] // 2).astype(np.int64)
    i = np.cumsum(is_b) - is_b + q
    j = np.cumsum(~is_b) - ~is_b + q
    # a bottom step: (b_i, b_i+1, t_j); a top step: (b_i, t_j+1, t_j)
    nxt = np.where(is_b, bp[np.minimum(i + 1, len(bp) - 1)], tp[np.minimum(j + 1, len(tp) - 1)])
    return np.column_stack([bp[i], nxt, tp[j]]), q


def fast_tessellation(plan, tol, angle_tol):
    """The :class:`Tessellation` of the plan's faces at tolerance ``tol`` (model units) and
    ``angle_tol`` (radians or None), or None where the general path must do it."""
    if plan.static is not None:  # no circles: the mesh is the same at every tolerance
        return Tessellation._build(*plan.static, tol)
    if not plan.arcs:
        mesh = _mesh(plan, tol, angle_tol)
        if mesh is not None:
            plan.static = (mesh.vertices, mesh.faces, mesh.normals, mesh.uv, mesh.vertex_patch, mesh.face_patch,
                           mesh.corner_uv, mesh.max_deviation)  # fmt: skip
        return mesh
    return _mesh(plan, tol, angle_tol)


def _mesh(plan, tol, angle_tol):
    """:func:`fast_tessellation` without the shortcut of a face set without circles."""
    n = _arc_counts(plan, tol, angle_tol)
    if n is None:
        return None
    if plan.lat is not None:
        return _mixed(plan, n, tol, angle_tol)
    parts = _base(plan, n, tol, angle_tol)
    return None if parts is None else Tessellation._build(*parts, tol)


ROUNDS = 4
"""Largest number of meshings of a face set with faces of revolution (the first one's closed-form
counts nearly always hold; a strip over the tolerance refines its face and meshes again)."""


def _mixed(plan, n, tol, angle_tol):
    """:func:`_mesh` of a face set with faces of revolution (:mod:`.latitude`): the planes and
    cylinders as usual, the faces of revolution in latitude strips on the same arc samples."""
    lat = plan.lat
    margin = np.ones(len(lat.face))
    base = None
    for _ in range(ROUNDS):
        counted = row_counts(lat, n, tol, angle_tol, margin)
        if counted is None:
            return None
        n_new, m = counted
        if base is None or not np.array_equal(n_new, n):
            n = n_new
            base = _base(plan, n, tol, angle_tol)
            if base is None:
                return None
        V, T, N, UV, VP, tface, CUV, max_dev = base
        limits.check(int(m.sum() + m.size) * 4 * BYTES_PER_TRIANGLE, "tessellation of faces of revolution")
        rows = mesh_rows(plan, lat, n, m, V, len(V))
        if rows.max_dev <= tol:
            break
        # the faces with a strip over the tolerance aim lower next round
        bad = np.zeros(len(margin))
        np.maximum.at(bad, rows.strip_rows[:, 0], rows.strip_dev)
        over = bad > tol
        margin[over] *= np.maximum(0.5, 0.95 * tol / bad[over])
    else:
        return None
    # the shared vertices whose representative lies on a face of revolution: its (u, v) and normal
    fv = rows.fix_vid
    sel = plan.kind[VP[fv]] == REVOLUTION
    UV, N, VP = UV.copy(), N.copy(), VP.copy()
    UV[fv[sel]], N[fv[sel]], VP[fv[sel]] = rows.fix_uv[sel], rows.fix_N[sel], rows.fix_face[sel]
    return Tessellation._build(np.concatenate([V, rows.V]), np.concatenate([T, rows.T]), np.concatenate([N, rows.N]),
                               np.concatenate([UV, rows.UV]), np.concatenate([VP, rows.VP]),
                               np.concatenate([tface, rows.face]), np.concatenate([CUV, rows.corner_uv]),
                               max(max_dev, rows.max_dev), tol)  # fmt: skip


def _base(plan, n, tol, angle_tol):
    """The planes and cylinders of the plan with arc counts ``n``: ``(V, T, N, UV, VP, face,
    corner_uv, max_dev)`` as :meth:`.result.Tessellation._build` takes them (every corner and
    arc sample a vertex), or None where the general path must do it."""
    n_pts = plan.n_line_uses + int(n[plan.au_arc].sum())
    limits.check(n_pts * 4 * BYTES_PER_TRIANGLE, "tessellation of trimmed faces (planes and cylinders)")
    K = _kernels.load(KERNELS, work=FIXED_WORK + 2 * n_pts, min_work=0)
    if K is not None:
        return _base_compiled(K, plan, n, tol, angle_tol)
    au = plan.au
    U = len(plan.use_group)
    cnt = np.ones(U, dtype=np.int64)
    cnt[au] = n[plan.au_arc]
    ustart = np.cumsum(cnt) - cnt
    C = len(plan.corners)
    inner = n - 1
    abase = C + np.cumsum(inner) - inner  # first vertex id of each arc's inner points
    n_vid = C + int(inner.sum())
    pvid = np.empty(n_pts, dtype=np.int64)
    pX = np.empty((n_pts, 3))
    puv = np.empty((n_pts, 2))
    pface = np.repeat(plan.use_face, cnt)
    pvid[ustart] = plan.start_vid
    pX[ustart] = plan.start_X
    puv[ustart] = plan.use_uv0
    # the arc uses' inner points, k = 1 .. n - 1 along the use (kk along the arc itself)
    ci = cnt[au] - 1
    o = np.repeat(np.arange(au.size), ci)
    k = np.arange(int(ci.sum())) - np.repeat(np.cumsum(ci) - ci, ci) + 1
    pos = ustart[au][o] + k
    a = plan.au_arc[o]
    na = n[a]
    kk = np.where(plan.au_flip[o], na - k, k)
    theta = plan.arc_sweep[a] * kk / na
    pvid[pos] = abase[a] + kk - 1
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    X = plan.arc_c[a] + plan.arc_r[a][:, None] * (c * plan.arc_e1[a] + s * plan.arc_e2[a])
    pX[pos] = X
    slot = plan.au_slot[o]
    uv = np.einsum("nij,nj->ni", plan.au_A[o], X) + plan.au_b[o]
    cy = np.flatnonzero(slot >= 0)
    if cy.size:
        oc = o[cy]
        uv[cy, 0] = plan.maps.param(slot[cy], plan.au_off[oc] + plan.au_sense[oc] * theta[cy])
        uv[cy, 1] = plan.au_v[oc]
    puv[pos] = uv
    # triangles, as indices into the loop points
    fstart = ustart[plan.face_first_use]
    tris = [plan.fixed_T + fstart[plan.fixed_face][:, None]]
    if plan.curved_planes:
        # ear clipping per face (one call each); checked for all faces at once: every triangle
        # counter-clockwise, n + 2 holes - 2 of them, their areas adding up to the polygon's
        Tp, wanted = _ear_clip(plan, puv, ustart, cnt)
        if len(Tp) != wanted:
            return None
        a, b, c = puv[Tp[:, 0]], puv[Tp[:, 1]], puv[Tp[:, 2]]
        area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        if not (area > 0).all():
            return None
        loop_size = np.add.reduceat(cnt, plan.loop_first)
        # per face: the triangles' areas against the polygon's (shoelace over its loops)
        first = ustart[plan.loop_first[plan.cp_loops]]
        size = loop_size[plan.cp_loops]
        idx = ranges(first, size)
        nxt = idx + 1
        ends = np.cumsum(size) - 1
        nxt[ends] = first
        shoe = puv[idx, 0] * puv[nxt, 1] - puv[nxt, 0] * puv[idx, 1]
        F = len(plan.faces)
        poly = np.bincount(pface[idx], shoe, F)
        got = np.bincount(pface[Tp[:, 0]], area, F)
        if np.abs(got - poly).max() > 1e-9 * np.abs(poly).max():
            return None
        tris.append(Tp)
    max_dev = plan.plane_offset
    if plan.zb_use is not None:
        Tc, q = _zipper(plan, ustart, cnt, puv)
        tris.append(Tc)
        # deviation of the cylinders
        # measured in closed form: S(u, v) = C(u) + (v - v0) D, so only u matters
        U3 = puv[Tc, 0]
        qq = np.repeat(q, 7)
        th = plan.maps.angle(qq, np.concatenate([U3, U3 @ BARY.T], axis=1).ravel()).reshape(-1, 7)
        if angle_tol is not None and (th[:, :3].max(axis=1) - th[:, :3].min(axis=1) > angle_tol * (1.0 + 1e-9)).any():
            return None
        dx = np.cos(th[:, 3:]) - np.cos(th[:, :3]) @ BARY.T
        dy = np.sin(th[:, 3:]) - np.sin(th[:, :3]) @ BARY.T
        max_dev = max(max_dev, float((plan.slot_radius[q][:, None] * np.sqrt(dx * dx + dy * dy)).max()))
    if max_dev > tol:
        return None
    T = np.concatenate(tris)
    tface = pface[T[:, 0]]
    T = np.where(plan.reversed[tface][:, None], T[:, [0, 2, 1]], T)
    # one representative loop point per vertex: its face, (u, v) and normal
    V = np.empty((n_vid, 3))
    V[pvid] = pX
    rep = np.empty(n_vid, dtype=np.int64)
    rep[pvid[::-1]] = np.arange(n_pts)[::-1]
    VP = pface[rep]
    N = plan.normal[VP]
    vq = plan.slot_of_face[VP]
    sel = np.flatnonzero(vq >= 0)
    if sel.size:
        q = vq[sel]
        d = V[sel] - plan.slot_centre[q]
        ax = plan.slot_axis[q]
        d -= np.einsum("ij,ij->i", d, ax)[:, None] * ax
        N[sel] = d * (plan.slot_sign[q] / np.linalg.norm(d, axis=1))[:, None]
    return V, pvid[T], N, puv[rep], VP, tface, puv[T], max_dev


def _ear_clip(plan, puv, ustart, cnt):
    """The ear-clipping triangles (loop point indices) of every plane with circles, one call per
    face, and how many a triangulation of those polygons has (points + 2 holes - 2 per face)."""
    loop_size = np.add.reduceat(cnt, plan.loop_first)
    fstart = ustart[plan.face_first_use]
    wanted, cp = 0, []
    for f, loops in plan.curved_planes:
        ends = np.cumsum(loop_size[loops])
        s0 = int(fstart[f])
        T = earcut.triangulate_float64(puv[s0 : s0 + int(ends[-1])], ends.astype(np.uint32))
        wanted += int(ends[-1]) + 2 * len(loops) - 4
        cp.append(T.astype(np.int64) + s0)
    return (np.concatenate(cp).reshape(-1, 3) if cp else np.zeros((0, 3), dtype=np.int64)), wanted


def _base_compiled(K, plan, n, tol, angle_tol):
    """:func:`_base` on the compiled kernels (:mod:`._fast_kernels`)."""
    maps, angle, zips = plan.kernel_args
    cnt, ustart, vid, X, uv, face, n_vid = K.points(
        n, len(plan.corners), plan.use_face, plan.use_arc, plan.use_flip, plan.start_vid, plan.start_X, plan.use_uv0,
        plan.use_slot, plan.use_off, plan.use_sense, plan.arc_c, plan.arc_r, plan.arc_e1, plan.arc_e2, plan.arc_sweep,
        plan.A, plan.b, *maps)  # fmt: skip
    Tp, wanted = _ear_clip(plan, uv, ustart, cnt)
    ok, T, CUV, tf, V, N, UV, VP, max_dev = K.finish(
        tol, -1.0 if angle_tol is None else angle_tol, ustart, cnt, vid, X, uv, face, n_vid, plan.fixed_T,
        plan.fixed_face, plan.face_first_use, Tp, wanted, plan.cp_first_use, plan.cp_loop_uses, *zips, *angle,
        plan.normal, plan.reversed, plan.slot_of_face, plan.plane_offset)  # fmt: skip
    if not ok:
        return None
    return V, T, N, UV, VP, tf, CUV, max_dev
