"""Compiled (numba) set-up of :class:`~splinekit.pointcloud.meshdistance.MeshDistance`'s compiled
searches: the triangle hierarchy (:class:`~._trianglebvh.TriangleBVH`) and, for a closed mesh,
every per-triangle and per-vertex array the region scan reads (:mod:`._meshsetup`), in the
hierarchy's triangle order. The three passes over triangles and vertices run in parallel; the
small ones (the hierarchy, twins, renumbering, edges: 1-4 ms each) stay serial, as a parallel
launch on a loaded machine can wait milliseconds for its second thread.

Loaded through :func:`splinekit._kernels.load`. Each array equals, bit for bit, what the numpy
builders make (``TriangleBVH`` without kernels, ``_pseudo_normals``, ``MeshDistance._bvh_planes``
and ``_bvh_prisms``, ``_gridscan.adjacency``; the tests compare them): the same operations in
the same order, sums of three terms left to right as numpy's reductions add them, dot products
as numpy's ``einsum`` adds its three products (:func:`_dot`), sums over a vertex's corners or an
edge's two half-edges from ``0.0`` in the order of the corners, as ``numpy.bincount`` adds
them. What differs is the way: gathers over a vertex -> corner list instead of scatters, twins
found through that list instead of a sorted edge table, a radix sort of the Morton codes
instead of ``argsort``. Corner angles need ``arctan2``, which numpy may evaluate with its own
vector routines: the kernels give its two arguments and the caller calls ``numpy.arctan2``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

MORTON_BITS = 10
"""Bits per axis of the Morton codes (as ``TriangleBVH``)."""


@njit(cache=True, inline="always")
def _dot(ax, ay, az, bx, by, bz):
    """``a . b`` as ``numpy.einsum("ij,ij->i")`` sums it on this numpy (x and z first, then y):
    the prism offsets and corner-angle cosines must round as the numpy builders' do."""
    return (ax * bx + az * bz) + ay * by


@njit(cache=True, inline="always")
def _norm(x, y, z):
    """``numpy.linalg.norm`` of one row: the squares summed left to right."""
    return np.sqrt(x * x + y * y + z * z)


# -- the hierarchy ------------------------------------------------------------------------


@njit(cache=True)
def morton_codes(V, T, code):
    """Morton codes ``code (m,)`` of the triangles' centroids in their bounding box (as
    ``TriangleBVH``: ``MORTON_BITS`` bits per axis, x highest)."""
    m = len(T)
    cen = np.empty((m, 3))
    for t in range(m):
        for a in range(3):
            cen[t, a] = (V[T[t, 0], a] + V[T[t, 1], a] + V[T[t, 2], a]) / 3.0
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for t in range(m):
        for a in range(3):
            lo[a] = min(lo[a], cen[t, a])
            hi[a] = max(hi[a], cen[t, a])
    width = np.empty(3)
    for a in range(3):
        width[a] = max(hi[a] - lo[a], 1e-300)
    top = (1 << MORTON_BITS) - 1
    for t in range(m):
        c = 0
        for a in range(3):
            q = min(max(int((cen[t, a] - lo[a]) / width[a] * float(top)), 0), top)
            for bit in range(MORTON_BITS):
                c |= ((q >> bit) & 1) << (3 * bit + (2 - a))
        code[t] = c


@njit(cache=True)
def radix_order(code):
    """The stable ascending order of the codes (``argsort(kind="stable")``), by a least
    significant digit radix sort, ``MORTON_BITS`` bits a pass."""
    m = len(code)
    order = np.arange(m)
    key = code.copy()
    tmp_o = np.empty(m, dtype=np.int64)
    tmp_k = np.empty(m, dtype=np.int64)
    radix = 1 << MORTON_BITS
    for p in range(3):
        shift = p * MORTON_BITS
        start = np.zeros(radix + 1, dtype=np.int64)
        for i in range(m):
            start[((key[i] >> shift) & (radix - 1)) + 1] += 1
        for d in range(radix):
            start[d + 1] += start[d]
        for i in range(m):
            d = (key[i] >> shift) & (radix - 1)
            tmp_o[start[d]] = order[i]
            tmp_k[start[d]] = key[i]
            start[d] += 1
        order, tmp_o = tmp_o, order
        key, tmp_k = tmp_k, key
    return order


@njit(cache=True)
def hierarchy(V, T, order, L, tri, tlo, thi, nlo, nhi):
    """The triangles' corners ``tri (m, 3, 3)`` in ``order``, their boxes ``tlo``, ``thi``
    ``(4 L, 3)`` (padding empty: ``inf`` / ``-inf``) and the node boxes ``nlo``, ``nhi``
    ``(2 L, 3)`` of the heap over ``L`` leaves of four (as ``TriangleBVH``)."""
    m = len(order)
    for s in range(4 * L):
        for a in range(3):
            if s < m:
                t = order[s]
                x0, x1, x2 = V[T[t, 0], a], V[T[t, 1], a], V[T[t, 2], a]
                tri[s, 0, a], tri[s, 1, a], tri[s, 2, a] = x0, x1, x2
                tlo[s, a] = min(min(x0, x1), x2)
                thi[s, a] = max(max(x0, x1), x2)
            else:
                tlo[s, a], thi[s, a] = np.inf, -np.inf
    for i in range(L):
        for a in range(3):
            lo, hi = np.inf, -np.inf
            for j in range(4):
                lo = min(lo, tlo[4 * i + j, a])
                hi = max(hi, thi[4 * i + j, a])
            nlo[L + i, a], nhi[L + i, a] = lo, hi
    s = L // 2
    while s >= 1:
        for i in range(s, 2 * s):
            for a in range(3):
                nlo[i, a] = min(nlo[2 * i, a], nlo[2 * i + 1, a])
                nhi[i, a] = max(nhi[2 * i, a], nhi[2 * i + 1, a])
        s //= 2
    for a in range(3):
        nlo[0, a], nhi[0, a] = np.inf, -np.inf


# -- connectivity, in the new vertex numbering and the hierarchy's triangle order ------------


@njit(cache=True)
def renumber(T, order, nv, nT):
    """Vertices in the order of the first triangle (in ``order``) at each, ties by original
    number, unused vertices last: returns ``(vorder (nv,), new (nv,), at (m,))``, new ->
    original vertex and back, and original triangle -> its place in ``order``; ``nT (m, 3)``
    receives the triangles in ``order`` with new vertex numbers. The passes after this one work
    in these numberings, where what is near on the mesh is near in memory."""
    new = np.full(nv, -1, dtype=np.int64)
    vorder = np.empty(nv, dtype=np.int64)
    at = np.empty(len(order), dtype=np.int64)
    n = 0
    for s in range(len(order)):
        t = order[s]
        at[t] = s
        a, b, c = T[t, 0], T[t, 1], T[t, 2]
        # the up to three vertices first seen here, ascending
        if a > b:
            a, b = b, a
        if b > c:
            b, c = c, b
        if a > b:
            a, b = b, a
        for v in (a, b, c):
            if new[v] < 0:
                new[v] = n
                vorder[n] = v
                n += 1
        for k in range(3):
            nT[s, k] = new[T[t, k]]
    for v in range(nv):
        if new[v] < 0:
            new[v] = n
            vorder[n] = v
            n += 1
    return vorder, new, at


@njit(cache=True)
def corners(T, at, new):
    """Vertex -> corner lists in the new numbering: CSR ``(ptr (nv + 1,), corner (3 m,))``,
    corner ``3 s + k`` being corner ``k`` of the ``s``-th triangle of the hierarchy (each
    vertex's corners in ascending *original* number ``3 t + k``: the order the numpy builder
    adds their weights in), beside each the vertex after it in its triangle ``ahead (3 m,)``
    (its half-edge's end, new number); and whether every triangle has three distinct vertices."""
    m, nv = len(T), len(new)
    ptr = np.zeros(nv + 1, dtype=np.int64)
    distinct = True
    for t in range(m):
        a, b, c = T[t, 0], T[t, 1], T[t, 2]
        if a == b or b == c or c == a:
            distinct = False
        ptr[new[a] + 1] += 1
        ptr[new[b] + 1] += 1
        ptr[new[c] + 1] += 1
    for v in range(nv):
        ptr[v + 1] += ptr[v]
    fill = ptr[:-1].copy()
    corner = np.empty(3 * m, dtype=np.int64)
    ahead = np.empty(3 * m, dtype=np.int64)
    for t in range(m):
        for k in range(3):
            v = new[T[t, k]]
            corner[fill[v]] = 3 * at[t] + k
            ahead[fill[v]] = new[T[t, (k + 1) % 3]]
            fill[v] += 1
    return ptr, corner, ahead, distinct


@njit(cache=True)
def twins(nT, ptr, corner, ahead, twin):
    """The opposite half-edge ``twin (3 m,)`` of every half-edge ``3 s + k`` (``nT[s, k] ->
    nT[s, k + 1]``), found among the corners of its end; returns the number of half-edges
    without exactly one opposite, or whose opposite's opposite is another (0: the mesh is closed
    and consistently oriented, every edge has two triangles, one each way)."""
    bad = 0
    for s in range(len(nT)):
        for k in range(3):
            a, b = nT[s, k], nT[s, (k + 1) % 3]
            found, hits = -1, 0
            for i in range(ptr[b], ptr[b + 1]):
                if ahead[i] == a:
                    found = corner[i]
                    hits += 1
            twin[3 * s + k] = found
            bad += hits != 1
    if bad == 0:
        for h in range(3 * len(nT)):
            bad += twin[twin[h]] != h
    return bad


# -- per triangle ---------------------------------------------------------------------------


@njit(cache=True, parallel=True)
def faces(tri, thin, fn, plane, ball, prism, sin_ang, cos_ang):
    """Per triangle (``tri (m, 3, 3)``, the hierarchy's order): unit face normal ``fn (m, 3)``
    (as the pseudo-normals: zero-area triangles keep their zero cross product), the plane of the
    grid kernels ``plane (m, 3)`` (zero when the cross product is at most ``thin`` times its two
    edges' lengths), bounding ball ``(m, 4)``, prism ``(m, 20)`` (plane and offset, three edge
    lines, disk; zero and an infinite radius for a thin triangle) and, per corner, the two
    arguments of ``arctan2`` that give its angle, ``sin_ang`` (``|u x w|``) and ``cos_ang``
    (``u . w``), ``(m, 3)`` each."""
    m = len(tri)
    for t in prange(m):
        ax, ay, az = tri[t, 0, 0], tri[t, 0, 1], tri[t, 0, 2]
        e1x, e1y, e1z = tri[t, 1, 0] - ax, tri[t, 1, 1] - ay, tri[t, 1, 2] - az
        e2x, e2y, e2z = tri[t, 2, 0] - ax, tri[t, 2, 1] - ay, tri[t, 2, 2] - az
        nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
        ln = _norm(nx, ny, nz)
        d = ln if ln > 0 else 1.0
        fn[t, 0], fn[t, 1], fn[t, 2] = nx / d, ny / d, nz / d
        # the plane: a cross product this small against its edges has a direction rounding may turn
        flat = not (ln > thin * _norm(e1x, e1y, e1z) * _norm(e2x, e2y, e2z))
        if flat:
            px, py, pz = 0.0, 0.0, 0.0
        else:
            px, py, pz = nx / ln, ny / ln, nz / ln
        plane[t, 0], plane[t, 1], plane[t, 2] = px, py, pz
        cx = (tri[t, 0, 0] + tri[t, 1, 0] + tri[t, 2, 0]) / 3.0
        cy = (tri[t, 0, 1] + tri[t, 1, 1] + tri[t, 2, 1]) / 3.0
        cz = (tri[t, 0, 2] + tri[t, 1, 2] + tri[t, 2, 2]) / 3.0
        rad = -np.inf
        for c in range(3):
            rad = max(rad, _norm(tri[t, c, 0] - cx, tri[t, c, 1] - cy, tri[t, c, 2] - cz))
        ball[t, 0], ball[t, 1], ball[t, 2] = cx, cy, cz
        ball[t, 3] = rad * (1.0 + 1e-12) + 1e-15  # rounding may only widen it
        for c in range(3):  # corner angles: the edges out of corner c
            b, e = (c + 1) % 3, (c + 2) % 3
            ux, uy, uz = tri[t, b, 0] - tri[t, c, 0], tri[t, b, 1] - tri[t, c, 1], tri[t, b, 2] - tri[t, c, 2]
            wx, wy, wz = tri[t, e, 0] - tri[t, c, 0], tri[t, e, 1] - tri[t, c, 1], tri[t, e, 2] - tri[t, c, 2]
            sin_ang[t, c] = _norm(uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx)
            cos_ang[t, c] = _dot(ux, uy, uz, wx, wy, wz)
        for j in range(20):
            prism[t, j] = 0.0
        if flat:
            prism[t, 19] = np.inf  # no disk either
            continue
        prism[t, 0], prism[t, 1], prism[t, 2] = px, py, pz
        prism[t, 3] = _dot(px, py, pz, ax, ay, az)
        for k in range(3):  # edge lines: unit in-plane normals pointing out
            a, b = k, (k + 1) % 3
            dx, dy, dz = tri[t, b, 0] - tri[t, a, 0], tri[t, b, 1] - tri[t, a, 1], tri[t, b, 2] - tri[t, a, 2]
            ux, uy, uz = dy * pz - dz * py, dz * px - dx * pz, dx * py - dy * px
            lu = _norm(ux, uy, uz)
            lu = lu if lu > 0 else 1.0
            ux, uy, uz = ux / lu, uy / lu, uz / lu
            prism[t, 4 + 4 * k], prism[t, 5 + 4 * k], prism[t, 6 + 4 * k] = ux, uy, uz
            prism[t, 7 + 4 * k] = _dot(ux, uy, uz, tri[t, a, 0], tri[t, a, 1], tri[t, a, 2])
        prism[t, 16], prism[t, 17], prism[t, 18], prism[t, 19] = cx, cy, cz, ball[t, 3]


# -- the region scan's connectivity and the pseudo-normals ----------------------------------


@njit(cache=True, inline="always")
def _original(hs, order):
    """Original number ``3 t + k`` of half-edge ``hs = 3 s + k`` (``t = order[s]``)."""
    return 3 * order[hs // 3] + hs % 3


@njit(cache=True)
def edges(nT, order, vorder, twin, ea, eb, eh):
    """Every edge once, in the order of its lower half-edge ``3 s + k``: its ends ``ea``, ``eb``
    (new numbers of its lower and higher original vertex) and its two half-edges ``eh (E, 2)``,
    the one of lower original number first (the numpy builder's edge table, renumbered)."""
    n = 0
    for hs in range(3 * len(nT)):
        gs = twin[hs]
        if hs > gs:
            continue
        s, k = hs // 3, hs % 3
        a, b = nT[s, k], nT[s, (k + 1) % 3]
        if vorder[a] > vorder[b]:
            a, b = b, a
        ea[n], eb[n] = a, b
        if _original(hs, order) > _original(gs, order):
            hs, gs = gs, hs
        eh[n, 0], eh[n, 1] = hs, gs
        n += 1


@njit(cache=True, parallel=True)
def vertices(V, vorder, ptr, corner, ahead, fn, ang, vsum, nV, nbr, vown):
    """Per vertex, in parallel, in the new numbering ``i`` (original ``vorder[i]``): its
    coordinates ``nV (nv, 3)`` (from ``V``, original numbering); its neighbours in the CSR
    ``ptr``, ``nbr`` (one per outgoing half-edge, ascending by original number, given in new
    numbers); a triangle at it ``vown`` (of its corners the last by local corner, then by place in
    the hierarchy); the angle-weighted sum of its triangles' normals ``vsum (nv, 3)`` (face
    normals ``fn`` and corner angles ``ang`` ``(m, 3)``, the hierarchy's order), its corners
    added from 0.0 in ascending original number, as ``numpy.bincount`` adds them."""
    m = len(fn)
    for i in prange(len(vorder)):
        v = vorder[i]
        nV[i, 0], nV[i, 1], nV[i, 2] = V[v, 0], V[v, 1], V[v, 2]
        o = ptr[i]
        key = -1
        sx, sy, sz = 0.0, 0.0, 0.0
        for j in range(o, ptr[i + 1]):
            c = corner[j]
            s, k = c // 3, c % 3
            w = ang[s, k]
            sx += fn[s, 0] * w
            sy += fn[s, 1] * w
            sz += fn[s, 2] * w
            key = max(key, k * m + s)
            u = ahead[j]
            p = j  # insertion, ascending by original number
            while p > o and vorder[nbr[p - 1]] > vorder[u]:
                nbr[p] = nbr[p - 1]
                p -= 1
            nbr[p] = u
        vsum[i, 0], vsum[i, 1], vsum[i, 2] = sx, sy, sz
        vown[i] = key % m if key >= 0 else 0


@njit(cache=True, parallel=True)
def triangles(nT, order, twin, fn, vsum, en, vn):
    """Per triangle, in parallel, in the hierarchy's order: the sum of the face normals ``fn``
    of the two triangles at each local edge (01, 12, 20) ``en (m, 3, 3)``, added from 0.0 in
    the order of their half-edges' original numbers (as ``numpy.bincount`` adds them), and the
    vertex sums ``vsum`` (:func:`vertices`) at its corners ``vn (m, 3, 3)``."""
    for s in prange(len(nT)):
        for k in range(3):
            hs = 3 * s + k
            gs = twin[hs]
            first, second = hs // 3, gs // 3
            if _original(hs, order) > _original(gs, order):
                first, second = second, first
            v = nT[s, k]
            for a in range(3):
                en[s, k, a] = (0.0 + fn[first, a]) + fn[second, a]
                vn[s, k, a] = vsum[v, a]
