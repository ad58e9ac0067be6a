"""Latitude strips: the fast path's meshes of faces of revolution (:mod:`.revolution`) whose
``(u, v)`` loop is a parameter rectangle of parallels (iso-``v`` circle arcs, or a pole where
the profile meets the axis) and meridians (iso-``u`` arcs of the profile circle).

Such a face is meshed in rows at iso-``v``: row ``k`` lies at profile angle ``psi_k``, uniform
between the bottom and the top, so that its ends are exactly the samples of the two meridian
edges (they are circles of the profile's radius: their samples at uniform angle are uniform in
``psi``; the two meridians' counts are tied, :attr:`LatitudePlan.ties`). A row is a parallel
circle cut at uniform angle ``phi``; the bottom and top rows are the parallel edges' own samples
(the circles' counts in closed form, shared with the neighbouring faces), or a pole. Adjacent
rows are zipped like the cylinders' strips (:func:`zip_rows`), a pole row is a fan whose pole
corner lies at the parametric middle of its base.

Counts in closed form: a triangle between two rows ``h = psi_{k+1} - psi_k`` apart with an
angular step ``d`` errs at a connecting edge's midpoint by about
``|d^2 S_phiphi + 2 d h S_phipsi + h^2 S_psipsi| / 8``, i.e. (with ``S_phiphi = -rho r``,
``S_phipsi = rho' t``, ``|S_psipsi| = p``, ``r`` and ``t`` orthogonal)
``rho^2 d^4 + 2 h^2 (2 rho'^2 + |rho rho''|) d^2 + h^4 p^2 <= (8 c tol)^2``: a quadratic in
``d^2`` whose root gives the largest step of the strip's rows (the term in ``rho'`` is the
tangential one the parametric yardstick counts near a pole). The meridians of such faces are
counted at half the sagitta (:data:`.fast_plan.MERIDIAN`), so that the rows' quadratic has room,
the parallels as the rows next to them need (:func:`row_counts`). The deviation is then measured
with the result's yardstick, the surface at the barycentric ``(u, v)`` of every triangle's edge
midpoints and centre against the flat point (in closed form on the numpy path, on the surfaces'
own rational Bézier cells in the compiled kernel :mod:`._latitude_kernels`: the same points to
rounding); a face with a strip over the tolerance aims lower and the call is meshed again, a few
rounds at most, else the caller falls back to the general path.

Everything here runs on arrays over all faces at once (numpy), or in one compiled pass each for
the counts and the strips once the kernels are loaded.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels
from ..mesh.topology import ranges
from .edges import MAX_SEGMENTS
from .welding import components

__all__ = ["LatitudePlan", "latitude_plan", "row_counts", "mesh_rows"]

MARGIN = 0.9
"""Share ``c`` of the tolerance the closed-form row counts aim at (the rest: higher-order terms)."""
BARY = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5], [1 / 3, 1 / 3, 1 / 3]])
"""Where a triangle is measured: its edges' midpoints and its centre (barycentric)."""
BOTTOM, RIGHT, TOP, LEFT = range(4)
KERNELS = "splinekit.tessellation._latitude_kernels"
FIXED_WORK = 1000
"""Work of one call of :func:`mesh_rows` on the numpy path apart from its points (point-equivalents,
see :mod:`splinekit._kernels`: about its cost in microseconds), counted towards loading the kernel."""


class LatitudePlan:
    """Per face of revolution ``s`` (S of them, numbered among the face set's such faces):
    ``face (S,)``, ``uses (S, 4)`` (bottom, right, top, left), ``pole (S, 2)`` (bottom, top is a
    pole), ``lo, hi (S, 2)`` its ``(u, v)`` rectangle, ``phi, psi (S, 2)`` the angles of its
    ends, ``flip (S,)`` a reversed face; ``revs`` the :class:`.revolution.Revolutions`; the arcs
    of its meridians ``mer_arc (S, 2)`` (right, left), bottom and top ``bot_arc, top_arc (S,)``
    (-1: a pole); ``ties (A,)`` the arcs whose counts must be equal (a label per arc); ``nets``
    the surfaces' rational Bézier cells for the compiled kernel (:func:`bezier_nets`)."""

    __slots__ = ("face", "uses", "pole", "lo", "hi", "phi", "psi", "flip", "revs", "ties", "mer_arc", "bot_arc",
                 "top_arc", "nets")  # fmt: skip


def side_labels(uv0, uv1, arc, pole):
    """Per use of each loop ``(S, k)`` (``uv0``, ``uv1`` ``(S, k, 2)``, ``arc``, ``pole``
    ``(S, k)`` bool; one loop per row, all loops at once): 0 bottom (``v = v_lo``, ``u``
    increasing; an arc or a pole), 1 right (``u = u_hi``, ``v`` increasing, an arc), 2 top
    (``v = v_hi``, ``u`` decreasing), 3 left (``u = u_lo``, ``v`` decreasing), -1 none; and each
    loop's rectangle ``(lo, hi)`` ``(S, 2)`` each."""
    lo, hi = np.minimum(uv0, uv1).min(axis=1), np.maximum(uv0, uv1).max(axis=1)
    eps = (1e-9 * (hi - lo))[:, None]
    at = lambda c, d: (np.abs(uv0[..., d] - c[:, None, d]) <= eps[..., d]) & (np.abs(uv1[..., d] - c[:, None, d]) <= eps[..., d])  # noqa: E731
    bottom = (arc | pole) & at(lo, 1) & (uv1[..., 0] > uv0[..., 0])
    right = arc & at(hi, 0) & (uv1[..., 1] > uv0[..., 1])
    top = (arc | pole) & at(hi, 1) & (uv1[..., 0] < uv0[..., 0])
    left = arc & at(lo, 0) & (uv1[..., 1] < uv0[..., 1])
    return np.select([bottom, right, top, left], [BOTTOM, RIGHT, TOP, LEFT], -1), lo, hi


def latitude_plan(plan, loop, rev, revs, pole_group, uv0, uv1, size):
    """The :class:`LatitudePlan` of the faces ``rev`` (``{face: Revolution}``) of the
    :class:`.fast_plan.FastPlan` ``plan`` (``loop``: each use's loop within its face; ``revs``:
    their :class:`.revolution.Revolutions`, in face order), or None
    unless each has one loop of four uses, one per side of its ``(u, v)`` rectangle, its poles
    where the profile meets the axis."""
    faces = sorted(rev)
    lp = LatitudePlan()
    S = len(faces)
    lp.face = np.array(faces, dtype=np.int64)
    lp.uses = np.zeros((S, 4), dtype=np.int64)
    lp.revs = revs
    # every face's uses at once (uses run face after face): four in its one loop, one per side
    count = np.bincount(plan.use_face, minlength=len(plan.faces))[lp.face]
    if (count != 4).any():
        return None
    mine = np.searchsorted(plan.use_face, lp.face)[:, None] + np.arange(4)  # (S, 4)
    if (loop[mine] != 0).any():
        return None
    g = plan.use_group[mine]
    label, lp.lo, lp.hi = side_labels(uv0[mine], uv1[mine], plan.arc_of[g] >= 0, pole_group[g])
    if (np.sort(label, axis=1) != np.arange(4)).any():
        return None
    q = np.arange(S)
    lp.uses[q[:, None], label] = mine
    lp.pole = pole_group[plan.use_group[lp.uses[:, [BOTTOM, TOP]]]]
    lp.phi = np.column_stack([lp.revs.umaps.angle(q, lp.lo[:, 0]), lp.revs.umaps.angle(q, lp.hi[:, 0])])
    lp.psi = np.column_stack([lp.revs.vmaps.angle(q, lp.lo[:, 1]), lp.revs.vmaps.angle(q, lp.hi[:, 1])])
    # a pole side lies on the axis, a parallel off it
    rho = np.abs(lp.revs.profile(np.repeat(q, 2), lp.psi.ravel())[0]).reshape(S, 2)
    if ((rho <= 1e-9 * size) != lp.pole).any():
        return None
    lp.flip = plan.reversed[lp.face]
    arc = plan.arc_of[plan.use_group]
    lp.mer_arc = arc[lp.uses[:, [RIGHT, LEFT]]]
    lp.bot_arc, lp.top_arc = arc[lp.uses[:, BOTTOM]], arc[lp.uses[:, TOP]]
    A = len(plan.arcs)
    lp.ties = components(A, lp.mer_arc[:, 0], lp.mer_arc[:, 1]) if A else np.zeros(0, dtype=np.int64)
    lp.nets = bezier_nets([plan.faces[f].surface for f in faces])
    return lp


def bezier_nets(surfaces):
    """The biquadratic rational Bézier cells of ``surfaces`` for the compiled kernel's deviation
    (the surfaces' own form, no sines or cosines): ``(ubreaks, uoff, vbreaks, voff, first,
    nets)``: surface ``s``'s breaks are ``ubreaks[uoff[s]:uoff[s + 1]]`` (likewise in ``v``), its
    cell ``(i, j)`` is ``nets[first[s] + i * (v pieces) + j]`` ``(3, 3, 4)``, homogeneous."""
    ub, vb, nets = [], [], []
    for S in surfaces:
        (bu, mu), (bv, mv) = (np.unique(np.asarray(k, dtype=np.float64), return_counts=True) for k in (S.knots_u, S.knots_v))
        ub.append(bu)
        vb.append(bv)
        if all(m[0] == 3 and m[-1] == 3 and (m[1:-1] == 2).all() for m in (mu, mv)):
            # joints of multiplicity 2 (as OCC writes spheres and tori): the cells' nets are the
            # surface's control points, three by three
            w = np.asarray(S.weights, dtype=np.float64)[..., None]
            H = np.concatenate([np.asarray(S.control_points) * w, w], axis=2)
            i = 2 * np.arange(len(bu) - 1)[:, None, None, None] + np.arange(3)[:, None]
            j = 2 * np.arange(len(bv) - 1)[None, :, None, None] + np.arange(3)
            nets.extend(H[i, j].reshape(-1, 3, 3, 4))
            continue
        for row in S.to_bezier():
            for b in row:
                w = np.asarray(b.weights, dtype=np.float64)[..., None]
                nets.append(np.concatenate([np.asarray(b.control_points) * w, w], axis=2))
    off = lambda parts: np.concatenate([[0], np.cumsum([len(x) for x in parts])]).astype(np.int64)  # noqa: E731
    cells = np.array([(len(u) - 1) * (len(v) - 1) for u, v in zip(ub, vb)], dtype=np.int64)
    return np.concatenate(ub), off(ub), np.concatenate(vb), off(vb), np.cumsum(cells) - cells, np.array(nets)


def tie(lp, n):
    """``n`` ``(A,)`` with the tied arcs' counts raised to their largest."""
    top = np.zeros(len(n), dtype=np.int64)
    np.maximum.at(top, lp.ties, n)
    return top[lp.ties]


def _row_need(lp, nm, tol, angle_tol, c):
    """Per row (face after face, ``nm + 1`` rows each) the segments it needs (the quadratic of the
    module docstring at the worst row of each strip next to it, aiming at ``c (S,) * tol``; not
    rounded up yet) and per face whether its rows' spacing leaves room at all (``(need, ok)``)."""
    K = _kernels.get(KERNELS)
    revs = lp.revs
    if K is not None:
        return K.row_need(nm, lp.psi, lp.phi, revs.rho_c, revs.z_c, revs.p, revs.g1, revs.g2, revs.kappa_u, c, tol,
                          -1.0 if angle_tol is None else angle_tol)  # fmt: skip
    S = len(nm)
    rs = np.repeat(np.arange(S), nm + 1)
    k = np.arange(rs.size) - np.repeat(np.cumsum(nm + 1) - nm - 1, nm + 1)
    h = (lp.psi[:, 1] - lp.psi[:, 0]) / nm
    psi = lp.psi[rs, 0] + k * h[rs]
    rho, _, drho, _, ddrho, _ = revs.profile(rs, psi)
    rho2 = rho * rho * (1.0 + (1.02 * revs.kappa_u[rs]) ** 2)  # the u map's parametric midpoints stray along the parallel
    mix = 2.0 * drho * drho + np.abs(rho * ddrho)
    # per strip (a row and the next one of the same face): the worst of its two rows
    st = np.setdiff1d(np.arange(rs.size), np.cumsum(nm + 1) - 1, assume_unique=True)
    f = rs[st]
    R2 = np.maximum(rho2[st], rho2[st + 1])
    B = 2.0 * (h[f] * h[f]) * np.maximum(mix[st], mix[st + 1])
    C = (h * h * revs.p) ** 2 - (8.0 * c * tol) ** 2
    ok = C < 0
    Cf = C[f]
    A = np.where(ok[f], -2.0 * Cf / (B + np.sqrt(np.maximum(B * B - 4.0 * R2 * Cf, 0.0)) + 1e-300), 0.0)
    step = np.sqrt(A)
    if angle_tol is not None:
        step = np.minimum(step, angle_tol)
    row_step = np.full(rs.size, np.inf)
    np.minimum.at(row_step, st, step)
    np.minimum.at(row_step, st + 1, step)
    return np.ceil((lp.phi[rs, 1] - lp.phi[rs, 0]) / np.maximum(row_step, 1e-300) * (1.0 + 1e-9)), ok


def row_counts(lp, n, tol, angle_tol, margin):
    """The arcs' counts ``n`` raised where a face's meridians leave its rows no room or its
    bottom or top row needs more than its arc gives, and every face's rows' segment counts
    ``(rows,)`` (0 at a pole); ``margin (S,)`` scales :data:`MARGIN` per face. None past
    :data:`.edges.MAX_SEGMENTS`."""
    c = MARGIN * margin
    n = n.copy()
    np.maximum.at(n, lp.mer_arc[lp.pole.all(axis=1), 0], 2)  # pole to pole: at least one row between
    n = tie(lp, n)
    for _ in range(8):
        nm = n[lp.mer_arc[:, 0]]
        need, ok = _row_need(lp, nm, tol, angle_tol, c)
        n = n.copy()
        if not ok.all():  # rows at most sqrt(0.7) of the spacing whose sagitta alone is the aim
            f = np.flatnonzero(~ok)
            h_max = np.sqrt(0.7 * 8.0 * c[f] * tol / lp.revs.p[f])
            np.maximum.at(n, lp.mer_arc[f, 0], np.ceil((lp.psi[f, 1] - lp.psi[f, 0]) / h_max).astype(np.int64))
            n = tie(lp, n)
            if n.max() > MAX_SEGMENTS:
                return None
            continue
        if need.max(initial=0) > MAX_SEGMENTS:
            return None
        need = np.maximum(need, 1).astype(np.int64)
        first, last = np.cumsum(nm + 1) - nm - 1, np.cumsum(nm + 1) - 1
        for side, rows, arcs in ((0, first, lp.bot_arc), (1, last, lp.top_arc)):
            live = ~lp.pole[:, side]
            np.maximum.at(n, arcs[live], need[rows[live]])
        n = tie(lp, n)
        if (n[lp.mer_arc[:, 0]] != nm).any():  # a meridian was also a parallel: count again
            continue
        m = need
        m[first] = np.where(lp.pole[:, 0], 0, n[lp.bot_arc])
        m[last] = np.where(lp.pole[:, 1], 0, n[lp.top_arc])
        return n, m
    return None


def _use_vids(plan, n, abase, use, k):
    """Vertex ids of the ``k``-th samples (along each use, from its start) of arc uses ``use``."""
    g = plan.use_group[use]
    a = plan.arc_of[g]
    na = n[a]
    kk = np.where(plan.use_flip[use], na - k, k)
    return np.where(kk == 0, plan.end_vid[g, 0], np.where(kk == na, plan.end_vid[g, 1], abase[a] + kk - 1))


def zip_rows(bkey, bq, tkey, tq, n_strips):
    """Counter-clockwise triangles between the bottom chains (points numbered ``0 ..`` in strip
    order, sorted by ``bkey`` in ``[0, 1]`` within each strip ``bq``) and the top chains
    (likewise, ``tkey``, ``tq``): at each step the chain whose next point comes first advances
    (ties: the bottom). Returns ``(k, 3)`` triangles of which each corner is ``(index, is_top)``
    encoded as ``index`` (bottom) or ``-1 - index`` (top), and their strips."""
    nb = np.bincount(bq, minlength=n_strips)
    nt = np.bincount(tq, minlength=n_strips)
    sb = np.ones(len(bq), dtype=bool)
    sb[np.cumsum(nb) - nb] = False  # every point but each chain's first is a step
    st = np.ones(len(tq), dtype=bool)
    st[np.cumsum(nt) - nt] = False
    keys = np.concatenate([2.0 * bq[sb] + bkey[sb] - 1e-9, 2.0 * tq[st] + tkey[st]])
    order = np.argsort(keys, kind="stable")
    is_b = order < int(sb.sum())
    q = np.concatenate([bq[sb], tq[st]])[order]
    # before each step: how many bottom (top) steps came earlier, plus one first point per strip
    i = np.cumsum(is_b) - is_b + q
    j = np.cumsum(~is_b) - ~is_b + q
    # a bottom step: (b_i, b_i+1, t_j); a top step: (b_i, t_j+1, t_j)
    second = np.where(is_b, i + 1, -1 - (j + 1))
    return np.column_stack([i, second, -1 - j]), q


class RowMesh:
    """The latitude strips of one call: triangles ``T (t, 3)`` (vertex ids), ``corner_uv (t, 3,
    2)``, ``face (t,)``, ``strip_dev (strips,)`` and ``max_dev``; the new vertices (ids from
    ``n_vid`` on) ``V, N, UV, VP``; for the faces' boundary vertices ``fix_vid`` with their
    ``fix_uv, fix_N, fix_face`` on a face of revolution; ``strip_rows (strips, 2)``."""

    __slots__ = ("T", "corner_uv", "face", "strip_dev", "max_dev", "V", "N", "UV", "VP", "fix_vid", "fix_uv", "fix_N",
                 "fix_face", "strip_rows")  # fmt: skip


def mesh_rows(plan, lp, n, m, V_base, n_vid):
    """The :class:`RowMesh` of the faces of revolution with arc counts ``n`` and row segment
    counts ``m`` (:func:`row_counts`); ``V_base`` the positions of the vertices ``0 .. n_vid - 1``
    (corners and arc samples, shared with the other faces)."""
    revs = lp.revs
    nm = n[lp.mer_arc[:, 0]]
    S = len(nm)
    inner = n - 1
    abase = len(plan.corners) + np.cumsum(inner) - inner
    K = _kernels.load(KERNELS, work=FIXED_WORK + 4 * int(m.sum()), min_work=0)
    if K is not None:
        maps = tuple((c.akey, c.tkey, c.table, c.first, c.last, c.sweep, c.full, c.t0, c.t1)
                     for c in (revs.umaps, revs.vmaps))  # fmt: skip
        out = RowMesh()
        (out.T, out.corner_uv, out.face, out.strip_dev, out.V, out.N, out.UV, out.VP, out.fix_vid, out.fix_uv, out.fix_N,
         out.fix_face) = K.rows(nm, m, lp.phi, lp.psi, lp.lo, lp.hi, lp.pole, lp.uses, lp.flip, lp.face, plan.use_group,
                                plan.use_flip, plan.arc_of, plan.end_vid, n, abase, V_base, n_vid, *maps, revs.O, revs.a,
                                revs.e1, revs.e2, revs.rho_c, revs.z_c, revs.p, revs.g1, revs.g2, lp.nets)  # fmt: skip
        out.max_dev = float(out.strip_dev.max()) if out.strip_dev.size else 0.0
        rs = np.repeat(np.arange(S), nm + 1)
        out.strip_rows = np.column_stack([rs, np.arange(m.size) - (np.cumsum(nm + 1) - nm - 1)[rs]])
        return out
    rs = np.repeat(np.arange(S), nm + 1)
    first = np.cumsum(nm + 1) - nm - 1
    k = np.arange(rs.size) - first[rs]
    h = (lp.psi[:, 1] - lp.psi[:, 0]) / nm
    r_psi = lp.psi[rs, 0] + k * h[rs]
    r_v = revs.vmaps.param(rs, r_psi)
    r_v = np.where(k == 0, lp.lo[rs, 1], np.where(k == nm[rs], lp.hi[rs, 1], r_v))
    # row points (pole rows have none here: their fans get a pole corner per triangle below)
    cnt = np.where(m > 0, m + 1, 0)
    pr = np.repeat(np.arange(rs.size), cnt)
    j = np.arange(pr.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    ps, pk, pm = rs[pr], k[pr], m[pr]
    phi = lp.phi[ps, 0] + j * (lp.phi[ps, 1] - lp.phi[ps, 0]) / np.maximum(pm, 1)
    u = np.where(j == 0, lp.lo[ps, 0], np.where(j == pm, lp.hi[ps, 0], revs.umaps.param(ps, phi)))
    v = r_v[pr]
    psi = r_psi[pr]
    vid = np.full(pr.size, -1, dtype=np.int64)
    for side, sel in ((BOTTOM, pk == 0), (TOP, pk == nm[ps])):
        s = np.flatnonzero(sel)
        vid[s] = _use_vids(plan, n, abase, lp.uses[ps[s], side], j[s] if side == BOTTOM else pm[s] - j[s])
    mid = (pk > 0) & (pk < nm[ps])
    s = np.flatnonzero(mid & (j == 0))
    vid[s] = _use_vids(plan, n, abase, lp.uses[ps[s], LEFT], nm[ps[s]] - pk[s])
    s = np.flatnonzero(mid & (j == pm))
    vid[s] = _use_vids(plan, n, abase, lp.uses[ps[s], RIGHT], pk[s])
    new = np.flatnonzero(vid < 0)
    vid[new] = n_vid + np.arange(new.size)
    X = np.empty((pr.size, 3))
    old = np.flatnonzero(vid < n_vid)
    X[old] = V_base[vid[old]]
    X[new] = revs.points(ps[new], phi[new], psi[new])
    # strips: rows k and k + 1 of a face; zipped, or a fan where one of them is a pole
    row_first = np.cumsum(cnt) - cnt  # first point of each row
    last = first + nm
    st = np.setdiff1d(np.arange(rs.size), last, assume_unique=True)
    zs = st[(m[st] > 0) & (m[st + 1] > 0)]
    bp, bq = ranges(row_first[zs], cnt[zs]), np.repeat(np.arange(zs.size), cnt[zs])
    tp, tq = ranges(row_first[zs + 1], cnt[zs + 1]), np.repeat(np.arange(zs.size), cnt[zs + 1])
    Tz, zq = zip_rows(j[bp] / m[pr[bp]], bq, j[tp] / m[pr[tp]], tq, zs.size)
    Tz = np.where(Tz >= 0, bp[np.maximum(Tz, 0)], tp[np.maximum(-1 - Tz, 0)])
    tris, strip_of = [Tz], [zs[zq]]
    # fans: a base row's segments and a pole corner at the parametric middle of each
    extra_uv, extra_vid, extra_slot, extra_psi = [], [], [], []
    n_pts = pr.size
    for top in (True, False):
        fs = st[m[st + 1] == 0] if top else st[m[st] == 0]
        base = fs if top else fs + 1
        seg = np.maximum(m[base], 0)
        a = ranges(row_first[base], seg)  # each segment's first point
        sq = np.repeat(fs, seg)
        slot = rs[sq]
        pole_v = np.where(top, lp.hi[slot, 1], lp.lo[slot, 1])
        pole_use = lp.uses[slot, TOP if top else BOTTOM]
        pid = n_pts + np.arange(a.size)
        n_pts += a.size
        extra_uv.append(np.column_stack([0.5 * (u[a] + u[a + 1]), pole_v]))
        extra_vid.append(plan.end_vid[plan.use_group[pole_use], 0])
        extra_slot.append(slot)
        extra_psi.append(lp.psi[slot, 1 if top else 0])
        tris.append(np.column_stack([a, a + 1, pid]) if top else np.column_stack([pid, a + 1, a]))
        strip_of.append(sq)
    # triangles strip after strip and the pole corners in that order too, as the compiled kernel
    # makes them: every call on a face set gives the same mesh whichever path it takes
    e_strip = np.concatenate(strip_of[1:])
    perm = np.argsort(e_strip, kind="stable")
    inv = np.empty_like(perm)
    inv[perm] = np.arange(perm.size)
    euv, e_vid, e_slot, e_psi = (np.concatenate(x)[perm] for x in (extra_uv, extra_vid, extra_slot, extra_psi))
    P_uv = np.concatenate([np.column_stack([u, v]), euv])
    P_vid = np.concatenate([vid, e_vid])
    P_slot = np.concatenate([ps, e_slot])
    P_X = np.concatenate([X, V_base[e_vid]])
    P_psi = np.concatenate([psi, e_psi])
    P_phi = np.concatenate([phi, revs.umaps.angle(e_slot, euv[:, 0])])
    T = np.concatenate(tris)
    if perm.size:
        T = np.where(T >= pr.size, pr.size + inv[np.maximum(T - pr.size, 0)], T)
    strip = np.concatenate(strip_of)
    order = np.argsort(strip, kind="stable")
    T, strip = T[order], strip[order]
    out = RowMesh()
    # the deviation in closed form, the result's yardstick: the surface at the barycentric (u, v)
    # of every triangle's edge midpoints and centre against the flat point
    tslot = P_slot[T[:, 0]]
    cuv = P_uv[T]
    buv = np.einsum("bj,tjd->tbd", BARY, cuv).reshape(-1, 2)
    flat = np.einsum("bj,tjd->tbd", BARY, P_X[T]).reshape(-1, 3)
    exact = revs.evaluate(np.repeat(tslot, len(BARY)), buv[:, 0], buv[:, 1])
    dev = np.linalg.norm(exact - flat, axis=1).reshape(-1, len(BARY)).max(axis=1)
    out.strip_dev = np.zeros(rs.size)
    np.maximum.at(out.strip_dev, strip, dev)
    out.max_dev = float(dev.max()) if dev.size else 0.0
    out.strip_rows = np.column_stack([rs, k])
    flip = lp.flip[tslot]
    out.T = np.where(flip[:, None], P_vid[T][:, [0, 2, 1]], P_vid[T])
    out.corner_uv = np.where(flip[:, None, None], cuv[:, [0, 2, 1]], cuv)
    out.face = lp.face[tslot]
    normals = revs.normals(P_slot, P_phi, P_psi) * np.where(lp.flip[P_slot], -1.0, 1.0)[:, None]
    # one point per new vertex; the others fix the shared vertices' (u, v), face and normal
    out.V, out.N, out.UV, out.VP = X[new], normals[new], P_uv[new], lp.face[P_slot[new]]
    fix = np.flatnonzero(P_vid < n_vid)
    out.fix_vid, out.fix_uv, out.fix_N, out.fix_face = P_vid[fix], P_uv[fix], normals[fix], lp.face[P_slot[fix]]
    return out
