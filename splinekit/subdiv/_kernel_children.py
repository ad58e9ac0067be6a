"""The compiled child connectivity of one Catmull-Clark or Loop level (numba, ``cache=True``): child
faces, and the child edge tables numbered as :func:`splinekit.subdiv.split.child_topology` numbers
them (derived from the child faces plus three per-edge parent arrays, so they can also be built
later, on first use)."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._kernel_corners import _CHUNK, _fof, _nxt, _prv


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
