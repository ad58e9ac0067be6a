"""Compiled kernels for one level of Catmull-Clark and Loop refinement (numba, ``cache=True``).

This module imports numba and is itself imported only through
:func:`splinekit.basis.jit.subdiv_kernels` on the first large refinement,
never when splinekit is imported. The numpy/scipy construction in
:mod:`~splinekit.subdiv.catmull_clark`, :mod:`~splinekit.subdiv.loop` and
:mod:`~splinekit.subdiv.masks` is the reference; these kernels build the same
stencil matrix ``S`` row by row, straight into CSR arrays (sorted column
indices, no explicit zeros):

- rows ``0 .. V-1``: vertex points. Each vertex gets the mask of its parent
  rule (``rule_p``: smooth and dart use the scheme's smooth mask, crease the
  ``3/4, 1/8, 1/8`` mask along its two sharp edges, corner the vertex itself)
  and, where the rule changes at the next level, ``cp * parent + cc * child``
  with the child rule (``rule_c``) and the weights of
  :func:`~splinekit.subdiv.masks.vertex_point_matrix`. Sharp edges are those
  with sharpness ``> 0`` for the parent rule and ``> 1`` for the child rule.
- rows ``V .. V+E-1``: edge points, ``(1 - ws) smooth + ws midpoint`` with
  ``ws = clip(s, 0, 1)``.
- rows ``V+E ..`` (Catmull-Clark): face centroids.

Entries are summed in the order scipy's products and sums use for the
reference matrix wherever that is cheap (so most values agree bit for bit;
the others to one rounding). :func:`rows` serves three modes from the same row
code: row-length bounds, filling the CSR arrays, and ``S @ X`` without storing
``S`` (each row accumulated in CSR order as scipy's ``csr_matvecs`` does, so
the result is exactly ``S @ X`` for the ``S`` the fill mode builds).

Performance notes: the parallel kernels only split the work into chunks and
call a plain function per chunk (numba's parallel passes are slow to compile
on large bodies), and the row code is written out in one function with
scalar-only helpers (numba reference-counts every array argument of an
inlined function on each call, which cost more than the rows themselves).

The child connectivity (faces and the edge tables of
:class:`~splinekit.mesh.topology.Topology`) is numbered exactly as
:func:`splinekit.subdiv.split.child_topology` numbers it; the edge tables are
derived from the child faces plus three per-edge parent arrays (low end and
the two half-edges), so they can also be built later, on first use.

Corners of uniform meshes (``k = 4`` quads, ``k = 3`` triangles) are located by
arithmetic; other meshes pass ``cf`` (face of each corner).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

_CHUNK = 1024
SMOOTH, DART, CREASE, CORNER = 0, 1, 2, 3
CATMULL_CLARK, LOOP = 0, 1


# -- corners ------------------------------------------------------------------------------------
# Helpers take scalars only (see the module docstring). Face ``f`` spans corners ``fs .. fe - 1``.
@njit(cache=True, inline="always")
def _nxt(c, k, fs, fe):
    if k == 4:
        return c - 3 if (c & 3) == 3 else c + 1
    if k == 3:
        return c - 2 if c % 3 == 2 else c + 1
    return fs if c + 1 == fe else c + 1


@njit(cache=True, inline="always")
def _prv(c, k, fs, fe):
    if k == 4:
        return c + 3 if (c & 3) == 0 else c - 1
    if k == 3:
        return c + 2 if c % 3 == 0 else c - 1
    return fe - 1 if c == fs else c - 1


@njit(cache=True, inline="always")
def _fof(c, k):
    """Face of corner ``c`` of a uniform mesh (``k`` 3 or 4)."""
    return c >> 2 if k == 4 else c // 3


@njit(cache=True)
def vertex_corners(fi, n_vertices, edges):
    """Corners of each vertex (ascending) as CSR ``(offsets (V+1,), corners (H,) int32)`` and the
    valence (edges per vertex)."""
    H = fi.size
    vc_off = np.zeros(n_vertices + 1, np.int64)
    for h in range(H):
        vc_off[fi[h] + 1] += 1
    for v in range(n_vertices):
        vc_off[v + 1] += vc_off[v]
    pos = vc_off[:-1].copy()
    vc = np.empty(H, np.int32)
    for h in range(H):
        v = fi[h]
        vc[pos[v]] = h
        pos[v] += 1
    valence = np.zeros(n_vertices, np.int64)
    for e in range(edges.shape[0]):
        valence[edges[e, 0]] += 1
        valence[edges[e, 1]] += 1
    return vc_off, vc, valence


@njit(cache=True)
def _heap_sort(keys, vals, base, n):
    """In-place heap sort of ``keys[base:base+n]`` (unique), ``vals`` alongside."""
    for start in range(n // 2 - 1, -1, -1):
        _sift(keys, vals, base, start, n)
    for end in range(n - 1, 0, -1):
        k = keys[base]
        keys[base] = keys[base + end]
        keys[base + end] = k
        x = vals[base]
        vals[base] = vals[base + end]
        vals[base + end] = x
        _sift(keys, vals, base, 0, end)


@njit(cache=True)
def _sift(keys, vals, base, root, end):
    while True:
        child = 2 * root + 1
        if child >= end:
            return
        if child + 1 < end and keys[base + child + 1] > keys[base + child]:
            child += 1
        if keys[base + root] >= keys[base + child]:
            return
        k = keys[base + root]
        keys[base + root] = keys[base + child]
        keys[base + child] = k
        x = vals[base + root]
        vals[base + root] = vals[base + child]
        vals[base + child] = x
        root = child


# -- stencil matrix and its product -------------------------------------------------------------
BOUNDS, FILL, APPLY = 0, 1, 2


@njit(cache=True)
def _chunk(mode, lo, hi, scheme, V, E, fi, off, k, cf, he, edges, h0, h1, vc_off, vc, valence, edge_s, rule_p,
           rule_c, cp, cc, beta_tab, max_bound, bound, indices, data, counts, X, Y):
    """Rows ``lo .. hi - 1`` of :func:`rows` (one thread's share).

    Each row is built as one or two lists of ``(column, value)`` (two for a vertex whose rule
    changes: the parent and the child rule's mask), each sorted by column with equal columns
    summed in order, then combined: ``cp * parent + cc * child`` for vertices, the sharp-rule
    blend for edges. Scratch: ``cols/vals``, regions ``[0, size)`` and ``[size, 2 size)`` for the
    lists, ``[2 size, 3 size)`` for the row.
    """
    if mode == BOUNDS:
        # an upper bound of each row's length (exact unless columns repeat or values cancel)
        mb = 0
        for r in range(lo, hi):
            if r < V:
                rp = rule_p[r]
                rc = rule_c[r]
                if rp <= DART or rc <= DART:
                    n = 1 + valence[r]
                    if scheme == CATMULL_CLARK:
                        if k == 4:
                            n += vc_off[r + 1] - vc_off[r]
                        elif k == 0:
                            for j in range(vc_off[r], vc_off[r + 1]):
                                f = cf[vc[j]]
                                n += max(off[f + 1] - off[f] - 3, 0)
                    b = n  # the smooth list, before merging: no shorter than the row, either rule
                elif rp == CREASE or rc == CREASE:
                    b = 3
                else:
                    b = 1
            elif r < V + E:
                e = r - V
                if edge_s[e] >= 1.0:
                    b = 2
                elif scheme == CATMULL_CLARK:
                    if k > 0:
                        b = k if h1[e] < 0 else 2 * k - 2
                    else:
                        f = cf[h0[e]]
                        b = off[f + 1] - off[f]
                        if h1[e] >= 0:
                            f = cf[h1[e]]
                            b += off[f + 1] - off[f] - 2
                else:
                    b = 4 if h1[e] >= 0 else 3
            else:
                f = r - V - E
                b = off[f + 1] - off[f]
            bound[r + 1] = b
            mb = max(mb, b)
        return mb

    D = X.shape[1]
    size = max_bound + 8
    cols = np.empty(3 * size, np.int64)
    vals = np.empty(3 * size)
    acc = np.zeros(D)
    out = 2 * size
    fs = 0
    fe = 0
    for r in range(lo, hi):
        rp = 0
        rc = 0
        n_parts = 1
        if r < V:
            rp = rule_p[r]
            rc = rule_c[r]
            if rp != rc:
                n_parts = 2
        elif r < V + E and edge_s[r - V] >= 1.0:
            # sharp edge: the midpoint
            e = r - V
            cols[out] = edges[e, 0]
            vals[out] = 0.5
            cols[out + 1] = edges[e, 1]
            vals[out + 1] = 0.5
            n_parts = 0
        n1 = 0
        n2 = 0
        for part in range(n_parts):
            base = out if (n_parts == 1 and r >= V) else part * size
            m = base
            if r < V:
                v = r
                rule = rp if part == 0 else rc
                if rule <= DART and scheme == CATMULL_CLARK:
                    # diag(centre) + neighbours(inv2) + vf @ Sf
                    nv = valence[v]
                    if nv > 0:
                        nf = float(nv)
                        inv2 = 1.0 / (nf * nf)
                        centre = (nf - 2.0) / nf
                    else:
                        inv2 = 0.0
                        centre = 1.0
                    cols[m] = v
                    m += 1
                    fsum = 0.0
                    for j in range(vc_off[v], vc_off[v + 1]):
                        c = np.int64(vc[j])
                        if k > 0:
                            x = inv2 * (1.0 / k)
                        else:
                            f = cf[c]
                            fs = off[f]
                            fe = off[f + 1]
                            x = inv2 * (1.0 / (fe - fs))
                        fsum += x
                        p = _prv(c, k, fs, fe)
                        for side in range(2):
                            h = c if side == 0 else p
                            e = he[h]
                            if h0[e] == h:
                                q = h1[e]
                                if q >= 0:
                                    if k > 0:
                                        xq = inv2 * (1.0 / k)
                                    else:
                                        g = cf[q]
                                        xq = inv2 * (1.0 / (off[g + 1] - off[g]))
                                    w = inv2 + (x + xq)
                                else:
                                    w = inv2 + x
                                cols[m] = edges[e, 0] + edges[e, 1] - v
                                vals[m] = w
                                m += 1
                        d = _nxt(_nxt(c, k, fs, fe), k, fs, fe)
                        while d != p:
                            cols[m] = fi[d]
                            vals[m] = x
                            m += 1
                            d = _nxt(d, k, fs, fe)
                    vals[base] = centre + fsum
                elif rule <= DART:
                    # Loop: (1 - n beta) v + beta sum(neighbours)
                    nv = valence[v]
                    beta = beta_tab[nv]
                    cols[m] = v
                    vals[m] = 1.0 - nv * beta
                    m += 1
                    for j in range(vc_off[v], vc_off[v + 1]):
                        c = np.int64(vc[j])
                        if k == 0:
                            f = cf[c]
                            fs = off[f]
                            fe = off[f + 1]
                        p = _prv(c, k, fs, fe)
                        for side in range(2):
                            h = c if side == 0 else p
                            e = he[h]
                            if h0[e] == h:
                                cols[m] = edges[e, 0] + edges[e, 1] - v
                                vals[m] = beta
                                m += 1
                elif rule == CREASE:
                    # 3/4 v + 1/8 (a + b) along the sharp edges (s > 0 for the parent rule,
                    # s - 1 > 0 for the child's)
                    thresh = 0.0 if part == 0 else 1.0
                    cols[m] = v
                    vals[m] = 0.75
                    m += 1
                    for j in range(vc_off[v], vc_off[v + 1]):
                        c = np.int64(vc[j])
                        if k == 0:
                            f = cf[c]
                            fs = off[f]
                            fe = off[f + 1]
                        p = _prv(c, k, fs, fe)
                        for side in range(2):
                            h = c if side == 0 else p
                            e = he[h]
                            if h0[e] == h and edge_s[e] > thresh:
                                cols[m] = edges[e, 0] + edges[e, 1] - v
                                vals[m] = 0.125
                                m += 1
                else:
                    cols[m] = v
                    vals[m] = 1.0
                    m += 1
            elif r < V + E:
                e = r - V
                a = edges[e, 0]
                b = edges[e, 1]
                cols[m] = a
                cols[m + 1] = b
                m += 2
                if scheme == CATMULL_CLARK:
                    # 0.5 midpoint + 1/4 of each face centroid
                    sab = 0.0
                    for side in range(2):
                        q = h0[e] if side == 0 else h1[e]
                        if q < 0:
                            break
                        if k == 0:
                            f = cf[q]
                            fs = off[f]
                            fe = off[f + 1]
                            x = 0.25 * (1.0 / (fe - fs))
                        else:
                            x = 0.25 * (1.0 / k)
                        sab = x if side == 0 else sab + x
                        d = _nxt(_nxt(q, k, fs, fe), k, fs, fe)
                        while d != q:
                            cols[m] = fi[d]
                            vals[m] = x
                            m += 1
                            d = _nxt(d, k, fs, fe)
                    vals[base] = 0.25 + sab
                    vals[base + 1] = 0.25 + sab
                else:
                    # 3/8 (a + b) + 1/8 of each opposite vertex
                    vals[base] = 0.375
                    vals[base + 1] = 0.375
                    for side in range(2):
                        q = h0[e] if side == 0 else h1[e]
                        if q < 0:
                            break
                        if k == 0:
                            f = cf[q]
                            fs = off[f]
                            fe = off[f + 1]
                        cols[m] = fi[_prv(q, k, fs, fe)]
                        vals[m] = 0.125
                        m += 1
            else:
                f = r - V - E
                fs = off[f]
                fe = off[f + 1]
                w = 1.0 / (fe - fs)
                for c in range(fs, fe):
                    cols[m] = fi[c]
                    vals[m] = w
                    m += 1
            # sort the list by column (stable) and sum equal columns in order
            n = m - base
            if n > 32:
                # long rows (high valence): heap sort on the unique keys (column, position)
                for i in range(n):
                    cols[base + i] = (cols[base + i] << 32) | i
                _heap_sort(cols, vals, base, n)
                for i in range(n):
                    cols[base + i] = cols[base + i] >> 32
            else:
                for i in range(base + 1, base + n):
                    ci = cols[i]
                    xi = vals[i]
                    j = i - 1
                    while j >= base and cols[j] > ci:
                        cols[j + 1] = cols[j]
                        vals[j + 1] = vals[j]
                        j -= 1
                    cols[j + 1] = ci
                    vals[j + 1] = xi
            m = base
            for i in range(base, base + n):
                if m > base and cols[m - 1] == cols[i]:
                    vals[m - 1] += vals[i]
                else:
                    cols[m] = cols[i]
                    vals[m] = vals[i]
                    m += 1
            if part == 0:
                n1 = m - base
            else:
                n2 = m - base

        # combine into the row at [out, out + nr)
        nr = 0
        if n_parts == 0:
            nr = 2
        elif r < V and n_parts == 1:
            # same rule at both levels: coef_parent = 1
            for i in range(n1):
                if vals[i] != 0.0:
                    cols[out + nr] = cols[i]
                    vals[out + nr] = vals[i]
                    nr += 1
        elif r < V:
            ca = cp[r]
            cb = cc[r]
            i = 0
            j = size
            i_end = n1
            j_end = size + n2
            while i < i_end or j < j_end:
                if j >= j_end or (i < i_end and cols[i] < cols[j]):
                    col = cols[i]
                    val = ca * vals[i]
                    i += 1
                elif i >= i_end or cols[j] < cols[i]:
                    col = cols[j]
                    val = cb * vals[j]
                    j += 1
                else:
                    col = cols[i]
                    val = ca * vals[i] + cb * vals[j]
                    i += 1
                    j += 1
                if val != 0.0:
                    cols[out + nr] = col
                    vals[out + nr] = val
                    nr += 1
        elif r < V + E:
            # (1 - ws) smooth + ws midpoint
            e = r - V
            a = edges[e, 0]
            b = edges[e, 1]
            ws = min(max(edge_s[e], 0.0), 1.0)
            om = 1.0 - ws
            hw = ws * 0.5
            for i in range(out, out + n1):
                val = om * vals[i]
                if cols[i] == a or cols[i] == b:
                    val = val + hw
                if val != 0.0:
                    cols[out + nr] = cols[i]
                    vals[out + nr] = val
                    nr += 1
        else:
            nr = n1

        if mode == FILL:
            s = bound[r]
            for i in range(nr):
                indices[s + i] = cols[out + i]
                data[s + i] = vals[out + i]
            counts[r] = nr
        else:
            for d in range(D):
                acc[d] = 0.0
            for i in range(out, out + nr):
                a = vals[i]
                col = cols[i]
                for d in range(D):
                    acc[d] += a * X[col, d]
            for d in range(D):
                Y[r, d] = acc[d]
    return 0


@njit(cache=True, parallel=True)
def rows(mode, scheme, V, E, n_rows, fi, off, k, cf, he, edges, h0, h1, vc_off, vc, valence, edge_s, rule_p, rule_c,
         cp, cc, beta_tab, max_bound, bound, indices, data, counts, X, Y):
    """All rows of ``S``, by ``mode``:

    - ``BOUNDS``: ``bound[r + 1]`` = an upper bound of row r's length (caller takes the prefix
      sum); returns the largest;
    - ``FILL``: rows into ``indices`` / ``data`` from ``bound[r]`` (the prefix sums), lengths
      into ``counts``;
    - ``APPLY``: ``Y = S @ X``, each row summed in CSR order as scipy's ``csr_matvecs`` does.
    """
    n_chunks = (n_rows + _CHUNK - 1) // _CHUNK
    best = np.zeros(max(n_chunks, 1), np.int64)
    for ch in prange(n_chunks):
        best[ch] = _chunk(mode, ch * _CHUNK, min(n_rows, (ch + 1) * _CHUNK), scheme, V, E, fi, off, k, cf, he, edges,
                          h0, h1, vc_off, vc, valence, edge_s, rule_p, rule_c, cp, cc, beta_tab, max_bound, bound,
                          indices, data, counts, X, Y)
    return best.max()


@njit(cache=True, parallel=True)
def compact(indptr, indices, data, counts, new_indptr, new_indices, new_data):
    """Drop the unused tail of each row (rows shorter than their bound)."""
    n_rows = counts.size
    n_chunks = (n_rows + _CHUNK - 1) // _CHUNK
    for ch in prange(n_chunks):
        for r in range(ch * _CHUNK, min(n_rows, (ch + 1) * _CHUNK)):
            s = indptr[r]
            t = new_indptr[r]
            for i in range(counts[r]):
                new_indices[t + i] = indices[s + i]
                new_data[t + i] = data[s + i]


# -- child connectivity -------------------------------------------------------------------------
@njit(cache=True, parallel=True)
def cc_child_faces(V, E, fi, off, k, cf, he):
    """Quads ``(vertex, edge point, face point, previous edge point)``, one per parent corner."""
    H = fi.size
    out = np.empty(4 * H, np.int64)
    n_chunks = (H + _CHUNK - 1) // _CHUNK
    for ch in prange(n_chunks):
        _cc_faces_chunk(ch * _CHUNK, min(H, (ch + 1) * _CHUNK), V, E, fi, off, k, cf, he, out)
    return out


@njit(cache=True)
def _cc_faces_chunk(lo, hi, V, E, fi, off, k, cf, he, out):
    fs = 0
    fe = 0
    for c in range(lo, hi):
        if k > 0:
            f = _fof(c, k)
        else:
            f = cf[c]
            fs = off[f]
            fe = off[f + 1]
        p = _prv(c, k, fs, fe)
        out[4 * c] = fi[c]
        out[4 * c + 1] = V + he[c]
        out[4 * c + 2] = V + E + f
        out[4 * c + 3] = V + he[p]


@njit(cache=True, parallel=True)
def cc_child_edges(V, E, cfaces, off, k, lo, h0, h1):
    """Edge tables ``(edges, halfedge_edge, h0, h1)`` of a Catmull-Clark child, from its faces
    (quad ``c`` is ``(vertex, V + edge, V + E + face, V + previous edge)`` of parent corner ``c``)
    and the parent's ``off`` (face offsets, when ``k == 0``), ``lo`` (low end of each edge) and
    ``h0``, ``h1`` (its half-edges)."""
    H = cfaces.size // 4
    nE = 2 * E + H
    edges = np.empty((nE, 2), np.int64)
    eh0 = np.empty(nE, np.int64)
    eh1 = np.empty(nE, np.int64)
    che = np.empty(4 * H, np.int64)
    n_chunks = (E + _CHUNK - 1) // _CHUNK
    for ch in prange(n_chunks):
        _cc_halves_chunk(ch * _CHUNK, min(E, (ch + 1) * _CHUNK), V, E, cfaces, off, k, lo, h0, h1, edges, eh0, eh1)
    n_chunks = (H + _CHUNK - 1) // _CHUNK
    for ch in prange(n_chunks):
        _cc_inner_chunk(ch * _CHUNK, min(H, (ch + 1) * _CHUNK), V, E, cfaces, off, k, lo, edges, eh0, eh1, che)
    return edges, che, eh0, eh1


@njit(cache=True)
def _cc_halves_chunk(e_lo, e_hi, V, E, cfaces, off, k, lo, h0, h1, edges, eh0, eh1):
    """Child edges ``2e`` = (low end, edge point), ``2e + 1`` = (high end, edge point)."""
    FO = V + E
    fs = 0
    fe = 0
    for e in range(e_lo, e_hi):
        p0 = h0[e]
        p1 = h1[e]
        low = lo[e]
        if k == 0:
            f = cfaces[4 * p0 + 2] - FO
            fs = off[f]
            fe = off[f + 1]
        n0 = _nxt(p0, k, fs, fe)
        s0 = cfaces[4 * p0]
        ka = 1 if s0 != low else 0
        edges[2 * e, 0] = low
        edges[2 * e, 1] = V + e
        edges[2 * e + 1, 0] = s0 + cfaces[4 * n0] - low
        edges[2 * e + 1, 1] = V + e
        eh0[2 * e + ka] = 4 * p0
        eh0[2 * e + 1 - ka] = 4 * n0 + 3
        if p1 >= 0:
            if k == 0:
                f = cfaces[4 * p1 + 2] - FO
                fs = off[f]
                fe = off[f + 1]
            n1 = _nxt(p1, k, fs, fe)
            eh1[2 * e + ka] = 4 * n1 + 3
            eh1[2 * e + 1 - ka] = 4 * p1
        else:
            eh1[2 * e + ka] = -1
            eh1[2 * e + 1 - ka] = -1


@njit(cache=True)
def _cc_inner_chunk(c_lo, c_hi, V, E, cfaces, off, k, lo, edges, eh0, eh1, che):
    """Child edge ``2E + c`` = (edge point, face point) of corner ``c``, and the edge of every
    child half-edge."""
    FO = V + E
    fs = 0
    fe = 0
    for c in range(c_lo, c_hi):
        if k == 0:
            f = cfaces[4 * c + 2] - FO
            fs = off[f]
            fe = off[f + 1]
        p = _prv(c, k, fs, fe)
        nx = _nxt(c, k, fs, fe)
        i = 2 * E + c
        edges[i, 0] = cfaces[4 * c + 1]
        edges[i, 1] = cfaces[4 * c + 2]
        eh0[i] = 4 * c + 1
        eh1[i] = 4 * nx + 2
        v = cfaces[4 * c]
        eo = cfaces[4 * c + 1] - V
        ei = cfaces[4 * c + 3] - V
        che[4 * c] = 2 * eo + (1 if v != lo[eo] else 0)
        che[4 * c + 1] = i
        che[4 * c + 2] = 2 * E + p
        che[4 * c + 3] = 2 * ei + (1 if v != lo[ei] else 0)


@njit(cache=True, parallel=True)
def loop_child_faces(V, fi, he):
    """Four triangles per parent triangle ``(a, b, c)``: ``(a, ab, ca)``, ``(ab, b, bc)``,
    ``(ca, bc, c)``, ``(ab, bc, ca)``."""
    T = fi.size // 3
    out = np.empty(12 * T, np.int64)
    n_chunks = (T + _CHUNK - 1) // _CHUNK
    for ch in prange(n_chunks):
        _loop_faces_chunk(ch * _CHUNK, min(T, (ch + 1) * _CHUNK), V, fi, he, out)
    return out


@njit(cache=True)
def _loop_faces_chunk(t_lo, t_hi, V, fi, he, out):
    for t in range(t_lo, t_hi):
        a = fi[3 * t]
        b = fi[3 * t + 1]
        c = fi[3 * t + 2]
        e0 = V + he[3 * t]
        e1 = V + he[3 * t + 1]
        e2 = V + he[3 * t + 2]
        o = 12 * t
        out[o] = a
        out[o + 1] = e0
        out[o + 2] = e2
        out[o + 3] = e0
        out[o + 4] = b
        out[o + 5] = e1
        out[o + 6] = e2
        out[o + 7] = e1
        out[o + 8] = c
        out[o + 9] = e0
        out[o + 10] = e1
        out[o + 11] = e2


@njit(cache=True, inline="always")
def _lout(t, i):
    """Child half-edge from corner ``i`` of triangle ``t`` to its outgoing edge point."""
    return 12 * t + 4 * i  # 0, 4, 8


@njit(cache=True, inline="always")
def _lin(t, i):
    """Child half-edge from the outgoing edge point of corner ``i`` to the next corner."""
    return 12 * t + (3 if i == 0 else (7 if i == 1 else 2))


@njit(cache=True, parallel=True)
def loop_child_edges(V, E, cfaces, lo, h0, h1):
    """Edge tables ``(edges, halfedge_edge, h0, h1)`` of a Loop child, from its faces and the
    parent's ``lo``, ``h0``, ``h1`` (see :func:`cc_child_edges`)."""
    T = cfaces.size // 12
    nE = 2 * E + 3 * T
    edges = np.empty((nE, 2), np.int64)
    eh0 = np.empty(nE, np.int64)
    eh1 = np.empty(nE, np.int64)
    che = np.empty(12 * T, np.int64)
    n_chunks = (E + _CHUNK - 1) // _CHUNK
    for ch in prange(n_chunks):
        _loop_halves_chunk(ch * _CHUNK, min(E, (ch + 1) * _CHUNK), V, cfaces, lo, h0, h1, edges, eh0, eh1)
    n_chunks = (T + _CHUNK - 1) // _CHUNK
    for ch in prange(n_chunks):
        _loop_inner_chunk(ch * _CHUNK, min(T, (ch + 1) * _CHUNK), V, E, cfaces, lo, edges, eh0, eh1, che)
    return edges, che, eh0, eh1


@njit(cache=True)
def _loop_halves_chunk(e_lo, e_hi, V, cfaces, lo, h0, h1, edges, eh0, eh1):
    for e in range(e_lo, e_hi):
        p0 = h0[e]
        p1 = h1[e]
        low = lo[e]
        t0 = p0 // 3
        i0 = p0 - 3 * t0
        s0 = cfaces[12 * t0 + 4 * i0]  # corner vertices sit at 0, 4, 8 of the triangle's block
        d0 = cfaces[12 * t0 + 4 * ((i0 + 1) % 3)]
        ka = 1 if s0 != low else 0
        edges[2 * e, 0] = low
        edges[2 * e, 1] = V + e
        edges[2 * e + 1, 0] = s0 + d0 - low
        edges[2 * e + 1, 1] = V + e
        eh0[2 * e + ka] = _lout(t0, i0)
        eh0[2 * e + 1 - ka] = _lin(t0, i0)
        if p1 >= 0:
            t1 = p1 // 3
            i1 = p1 - 3 * t1
            eh1[2 * e + ka] = _lin(t1, i1)
            eh1[2 * e + 1 - ka] = _lout(t1, i1)
        else:
            eh1[2 * e + ka] = -1
            eh1[2 * e + 1 - ka] = -1


@njit(cache=True)
def _loop_inner_chunk(t_lo, t_hi, V, E, cfaces, lo, edges, eh0, eh1, che):
    for t in range(t_lo, t_hi):
        o = 12 * t
        a = cfaces[o]
        b = cfaces[o + 4]
        c = cfaces[o + 8]
        E0 = cfaces[o + 1]
        E1 = cfaces[o + 5]
        E2 = cfaces[o + 2]
        e0 = E0 - V
        e1 = E1 - V
        e2 = E2 - V
        i = 2 * E + 3 * t
        edges[i, 0] = min(E0, E2)
        edges[i, 1] = max(E0, E2)
        edges[i + 1, 0] = min(E0, E1)
        edges[i + 1, 1] = max(E0, E1)
        edges[i + 2, 0] = min(E2, E1)
        edges[i + 2, 1] = max(E2, E1)
        eh0[i] = o + 1
        eh1[i] = o + 11
        eh0[i + 1] = o + 5
        eh1[i + 1] = o + 9
        eh0[i + 2] = o + 6
        eh1[i + 2] = o + 10
        che[o] = 2 * e0 + (1 if a != lo[e0] else 0)
        che[o + 1] = i
        che[o + 2] = 2 * e2 + (1 if a != lo[e2] else 0)
        che[o + 3] = 2 * e0 + (1 if b != lo[e0] else 0)
        che[o + 4] = 2 * e1 + (1 if b != lo[e1] else 0)
        che[o + 5] = i + 1
        che[o + 6] = i + 2
        che[o + 7] = 2 * e1 + (1 if c != lo[e1] else 0)
        che[o + 8] = 2 * e2 + (1 if c != lo[e2] else 0)
        che[o + 9] = i + 1
        che[o + 10] = i + 2
        che[o + 11] = i
