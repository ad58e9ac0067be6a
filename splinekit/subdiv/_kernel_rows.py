"""The compiled stencil rows of one Catmull-Clark or Loop level (numba, ``cache=True``): the rows of
``S`` straight into CSR arrays, or ``S @ X`` without storing ``S``; see :mod:`splinekit.subdiv._kernels`
for what each row holds and how the values agree with the numpy rules."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._kernel_corners import _CHUNK, CATMULL_CLARK, CREASE, DART, _nxt, _prv


# -- sorting a row's (column, value) list ------------------------------------------------------
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
