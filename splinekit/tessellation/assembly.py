"""The mesh of a tessellation assembled from its evaluated grids.

Grids are triangulated by index arithmetic. Only vertices on a grid's border (its
"ring") can merge: collapsed cell edges (poles) become one vertex, the rest are welded
where they lie within the weld distance (:mod:`.welding`), and only triangles touching
a ring are remapped, and dropped when they collapse. A closed body facing inward is
then turned outward (:func:`outward`). With compiled kernels loaded, the vertex
gathering, the triangle remap and the orientation test run compiled, with the numpy
path's results bit for bit.
"""

from __future__ import annotations

import functools
import itertools

import numpy as np

from .. import _kernels
from .poles import fix_weak_normals
from .result import Tessellation
from .welding import close_pairs, components

__all__ = ["assemble", "outward"]


def _grid_triangles(n, m):
    """``(2 n m, 3)`` local vertex indices of an ``(n + 1) x (m + 1)`` grid, counter-clockwise
    in (u, v): triangles ``(00, 10, 11)`` and ``(00, 11, 01)`` per quad."""
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    v00 = (i * (m + 1) + j).ravel()
    v10, v01 = v00 + (m + 1), v00 + 1
    v11 = v10 + 1
    return np.stack([np.column_stack([v00, v10, v11]), np.column_stack([v00, v11, v01])], axis=1).reshape(-1, 3)


@functools.lru_cache(maxsize=256)
def _edge_locals(n, m):
    """Local vertex indices along the four cell edges (v = 0, v = 1, u = 0, u = 1) (cached,
    read-only)."""
    i, j = np.arange(n + 1), np.arange(m + 1)
    out = (i * (m + 1), i * (m + 1) + m, j, n * (m + 1) + j)
    for a in out:
        a.setflags(write=False)
    return out


@functools.lru_cache(maxsize=256)
def _edge_slots(n, m):
    """``(slots (4, max(n, m) + 1), first (4,))``: the ring slots (:func:`_ring_split`) of the
    local vertices along the four cell edges of :func:`_edge_locals`, rows padded with their
    last value, and each edge's first slot (cached, read-only)."""
    slot = _ring_split(n, m)[2]
    width = max(n, m) + 1
    out = np.stack([np.pad(slot[loc], (0, width - loc.size), mode="edge") for loc in _edge_locals(n, m)])
    first = out[:, 0].copy()
    for a in (out, first):
        a.setflags(write=False)
    return out, first


@functools.lru_cache(maxsize=256)
def _ring_split(n, m):
    """Index tables of an ``(n + 1) x (m + 1)`` grid (cached, read-only): interior and
    ring (border) local vertices ``Li``, ``Lr``; each vertex's ``slot`` among its kind;
    the ``on_ring`` mask; the local triangles off the ring and touching it."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(m + 1), indexing="ij")
    on_ring = ((i == 0) | (i == n) | (j == 0) | (j == m)).ravel()
    Li, Lr = np.flatnonzero(~on_ring), np.flatnonzero(on_ring)
    slot = np.empty(on_ring.size, dtype=np.int64)
    slot[Li] = np.arange(Li.size)
    slot[Lr] = np.arange(Lr.size)
    tmpl = _grid_triangles(n, m)
    touch = on_ring[tmpl].any(axis=1)
    out = (Li, Lr, slot, on_ring, tmpl[~touch], tmpl[touch])
    for a in out:
        a.setflags(write=False)
    return out


@functools.lru_cache(maxsize=512)
def _template_slots(n, m, touching):
    """``(is_ring, slot)`` ``(t, 3)`` of the local triangles of an ``(n + 1) x (m + 1)`` grid
    off the ring (``touching=False``) or touching it (cached, read-only)."""
    _, _, slot, on_ring, tmpl_in, tmpl_edge = _ring_split(n, m)
    tmpl = tmpl_edge if touching else tmpl_in
    out = (on_ring[tmpl], slot[tmpl])
    for a in out:
        a.setflags(write=False)
    return out


class _Piece:
    """One evaluated grid's share of the mesh, split into interior and ring (grid
    boundary) vertices: only ring vertices can be welded, so interior vertices are
    numbered first and never renumbered, and only triangles touching the ring are
    remapped, filtered and deduplicated."""

    def __init__(self, b, keep, collapsed, span_of):
        n, m = b.n, b.m
        per = (n + 1) * (m + 1)
        if b.kind == "cells":
            sel = keep
            cs = b.set
            local = b.local[keep]
            box = cs.box[local]
            U = box[:, 0, None] + (box[:, 1] - box[:, 0])[:, None] * (np.arange(n + 1) / n)  # (c, n + 1)
            W = box[:, 2, None] + (box[:, 3] - box[:, 2])[:, None] * (np.arange(m + 1) / m)  # (c, m + 1)
            self.pid = cs.patch[local]
        else:
            sel = np.array([0])
            U, W = b.us[None], b.vs[None]
            self.pid = np.array([b.index])
        c = sel.size
        if c == b.V.shape[0]:
            sel = slice(None)  # every cell of the grid is current: no copy
        self.Li, self.Lr, self.slot, self.on_ring, self.tmpl_in, self.tmpl_edge = _ring_split(n, m)
        self.n, self.m, self.c, self.per = n, m, c, per
        self.V = b.V[sel].reshape(c, per, 3)
        self.N = b.N[sel].reshape(c, per, 3)
        self.weak = b.weak[sel].reshape(c, per)
        self.U, self.W = U, W
        # collapsed cell edges: (ring vertex, ring vertex it becomes), in this piece's ring slots
        pins = []
        slot, on_ring = self.slot, self.on_ring
        col = collapsed[b.cells[keep]]
        if col.any():
            if b.kind == "cells":
                # every collapsed edge e of a cell k: its ring vertices -> the edge's first one
                edge_slots, edge_first = _edge_slots(n, m)
                k, e = np.nonzero(col)
                base = k * self.Lr.size
                L = np.where(e < 2, n + 1, m + 1)[:, None]
                r = base[:, None] + edge_slots[e]  # (pairs, max(n, m) + 1): rows padded past their L
                live = np.arange(r.shape[1]) < L
                pins.append(np.column_stack([r[live], np.repeat(base + edge_first[e], L.ravel())]))
            else:
                cu, cv = b.counts
                r0s, c0s = np.concatenate([[0], np.cumsum(cu)]), np.concatenate([[0], np.cumsum(cv)])
                for k, e in zip(*np.nonzero(col)):
                    iu, iv = span_of[b.cells[k]]
                    rows, cols = np.arange(r0s[iu], r0s[iu + 1] + 1), np.arange(c0s[iv], c0s[iv + 1] + 1)
                    loc = rows * (m + 1) + cols[0 if e == 0 else -1] if e < 2 else rows[0 if e == 2 else -1] * (m + 1) + cols
                    if on_ring[loc].all():  # (an interior knot line that collapses is left as is)
                        r = slot[loc]
                        pins.append(np.column_stack([r, np.full(r.size, r[0])]))
        self.pins = np.concatenate(pins) if pins else np.zeros((0, 2), dtype=np.int64)

    def uv(self, L):
        """``(c, len(L), 2)`` parameters of the local vertices ``L``."""
        i, j = L // (self.m + 1), L % (self.m + 1)
        return np.stack([self.U[:, i], self.W[:, j]], axis=-1)

    def triangles(self, touching, int_base, ring_base, out=None):
        """Global triangles ``(c * t, 3)`` of the local triangles touching the ring
        (``touching=True``, ``tmpl_edge``) or not (``tmpl_in``)."""
        ni, nr = self.Li.size, self.Lr.size
        is_ring, slot = _template_slots(self.n, self.m, touching)
        cell = np.arange(self.c)[:, None, None]
        base = np.where(is_ring[None], ring_base + cell * nr, int_base + cell * ni)
        if out is None:
            return (base + slot[None]).reshape(-1, 3)
        np.add(base, slot[None], out=out.reshape(self.c, len(slot), 3))
        return out


def outward(mesh, welded, vertices, triangles):
    """A closed body whose patches all face inward (``Su x Sv`` pointing into
    the solid, e.g. a profile revolved the other way round) turned outward:
    triangle winding, corner parameters and normals flipped, so its volume is
    positive, as OCC's solids and manifold3d expect. An unwelded mesh is open,
    and an outward closed one is recognised by a cheap volume sum: both skip the
    edge table that ``is_closed`` builds. ``vertices`` ``(n, 3)`` and ``triangles``
    ``(F, 3)`` are the mesh's arrays."""
    if len(triangles) == 0 or not welded or _clearly_positive_volume(vertices, triangles):
        return mesh
    if not mesh.is_closed or mesh.volume >= 0:
        return mesh
    return type(mesh)._build(
        mesh.vertices, np.asarray(mesh.faces)[:, ::-1], -mesh.normals, mesh.uv, mesh.vertex_patch,
        mesh.face_patch, np.asarray(mesh.corner_uv)[:, ::-1], mesh.max_deviation, mesh.tolerance,
    )  # fmt: skip


def _clearly_positive_volume(vertices, triangles) -> bool:
    """True when the signed volume about the bounding-box centre is positive by a margin
    far above rounding (then ``mesh.volume``, the same sum, is positive if the mesh is
    closed, and an open mesh is left as it is anyway)."""
    jit = _kernels.get("splinekit.tessellation._kernels")
    if jit is not None:
        return bool(jit.clearly_positive_volume(np.ascontiguousarray(vertices, dtype=np.float64),
                                                np.ascontiguousarray(triangles, dtype=np.int64)))  # fmt: skip
    X = np.array(vertices.T, order="C")  # (3, n) copy: rows are fast to reduce and gather
    X -= 0.5 * (X.min(axis=1) + X.max(axis=1))[:, None]
    F = triangles
    a, b, c = (X.take(F[:, k], axis=1) for k in range(3))  # (3, F) each
    det = a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) + a[2] * (b[0] * c[1] - b[1] * c[0])
    return bool(det.sum() > 1e-9 * np.abs(det).sum())


def _gather(pieces):
    """``(V, N, WK, UV, VP)`` vertex data of the pieces: interior vertices of every
    piece, then ring vertices."""
    V = np.concatenate([p.V[:, p.Li].reshape(-1, 3) for p in pieces] + [p.V[:, p.Lr].reshape(-1, 3) for p in pieces])
    N = np.concatenate([p.N[:, p.Li].reshape(-1, 3) for p in pieces] + [p.N[:, p.Lr].reshape(-1, 3) for p in pieces])
    WK = np.concatenate([p.weak[:, p.Li].ravel() for p in pieces] + [p.weak[:, p.Lr].ravel() for p in pieces])
    UV = np.concatenate([p.uv(p.Li).reshape(-1, 2) for p in pieces] + [p.uv(p.Lr).reshape(-1, 2) for p in pieces])
    VP = np.concatenate([np.repeat(p.pid, p.Li.size) for p in pieces] + [np.repeat(p.pid, p.Lr.size) for p in pieces])
    return V, N, WK, UV, VP


def _weld_triangles(E0, FE, rep, NI, NR, T, FP, n_in):
    """The triangles ``E0`` (patches ``FE``) touching a grid ring remapped after welding
    (ring vertex ``NI + r`` becomes ``NI + rep[r]``), without those that collapse or
    repeat, the ring vertices still in use renumbered after the interior ones, written
    into ``T``, ``FP`` from row ``n_in`` on. Returns ``(T, FP, E0, kept)``: the arrays
    cut to size, the survivors' pre-weld corners and the kept ring vertices."""
    full = np.concatenate([np.arange(NI), NI + rep])
    E = full[E0]
    good = (E[:, 0] != E[:, 1]) & (E[:, 1] != E[:, 2]) & (E[:, 0] != E[:, 2])
    E, FE, E0 = E[good], FE[good], E0[good]
    # drop exact duplicates (same corners in the same cyclic order) made by welding
    if len(E):
        nv = NI + NR
        if nv < 2_000_000:  # one int64 key per triangle: a 1-D sort instead of a row sort
            # the rotation that starts at the smallest corner has the smallest key
            a, b, c = E[:, 0], E[:, 1], E[:, 2]
            key = np.minimum(np.minimum((a * nv + b) * nv + c, (b * nv + c) * nv + a), (c * nv + a) * nv + b)
            _, first_idx = np.unique(key, return_index=True)
        else:
            rot = np.argmin(E, axis=1)
            canon = np.take_along_axis(E, (rot[:, None] + np.arange(3)) % 3, axis=1)
            _, first_idx = np.unique(canon, axis=0, return_index=True)
        if first_idx.size != len(E):
            first_idx.sort()
            E, FE, E0 = E[first_idx], FE[first_idx], E0[first_idx]
    # keep the ring vertices still in use, renumbered after the interior ones
    used = np.zeros(NR, dtype=bool)
    ring_refs = E[E >= NI] - NI
    used[ring_refs] = True
    kept = np.flatnonzero(used)
    new_ring = np.full(NR, -1, dtype=np.int64)
    new_ring[kept] = NI + np.arange(kept.size)
    E = np.where(E >= NI, new_ring[np.maximum(E - NI, 0)], E)
    T[n_in : n_in + len(E)], FP[n_in : n_in + len(E)] = E, FE
    T, FP = T[: n_in + len(E)], FP[: n_in + len(E)]
    return T, FP, E0, kept


def assemble(grids, record, collapsed, span_of, cell_index, tol, weld_tol):
    """Concatenate the latest evaluation of every cell, weld and triangulate.

    Returns ``(mesh, welded, vertices, triangles)``: ``welded`` is False when no two grid
    vertices were merged (then every grid's border edges keep their single triangle: the
    mesh is open); the arrays are the mesh's, as built.
    """
    pieces = []
    max_dev = 0.0
    for r, b in enumerate(grids):
        keep = np.flatnonzero(record[b.cells] == r)
        if keep.size == 0:
            continue
        pieces.append(_Piece(b, keep, collapsed, span_of))
        errs = (b.err_u, b.err_v, b.err_d) if keep.size == len(b.cells) else (b.err_u[keep], b.err_v[keep], b.err_d[keep])
        max_dev = max(max_dev, *(float(e.max()) for e in errs))
    # first interior and first ring vertex of each piece (Python ints: a handful of pieces)
    int_base = [0, *itertools.accumulate(p.c * p.Li.size for p in pieces)]
    NI = int_base[-1]
    ring_base = [NI + r for r in (0, *itertools.accumulate(p.c * p.Lr.size for p in pieces))]
    NR = ring_base[-1] - NI
    # vertex data: interior vertices of every piece, then ring vertices
    jit = _kernels.get("splinekit.tessellation._kernels")
    if jit is not None:
        V, N, UV = np.empty((NI + NR, 3)), np.empty((NI + NR, 3)), np.empty((NI + NR, 2))
        WK, VP = np.empty(NI + NR, dtype=np.bool_), np.empty(NI + NR, dtype=np.int64)
        for k, p in enumerate(pieces):
            jit.gather_piece(p.V, p.N, p.weak, p.U, p.W, p.pid, p.Li, p.Lr, p.m, int_base[k], ring_base[k],
                             V, N, WK, UV, VP)  # fmt: skip
    else:
        V, N, WK, UV, VP = _gather(pieces)
    # triangles: those touching the ring go last (only they can change); the interior
    # ones are written once, straight into the final array
    n_in = sum(p.c * len(p.tmpl_in) for p in pieces)
    n_edge = sum(p.c * len(p.tmpl_edge) for p in pieces)
    T = np.empty((n_in + n_edge, 3), dtype=np.int64)
    FP = np.empty(n_in + n_edge, dtype=np.int64)
    at = 0
    for k, p in enumerate(pieces):
        size = p.c * len(p.tmpl_in)
        p.triangles(False, int_base[k], ring_base[k], out=T[at : at + size])
        FP[at : at + size] = np.repeat(p.pid, len(p.tmpl_in))
        at += size
    T_edge = [p.triangles(True, int_base[k], ring_base[k]) for k, p in enumerate(pieces)]
    F_edge = [np.repeat(p.pid, len(p.tmpl_edge)) for p in pieces]
    E0 = np.concatenate(T_edge)  # before welding
    FE = np.concatenate(F_edge)
    # weld ring vertices: collapsed edges first, then coincident points (close pairs)
    rep = np.arange(NR)
    pins = [p.pins + (ring_base[k] - NI) for k, p in enumerate(pieces) if len(p.pins)]
    if pins:
        pins = np.concatenate(pins)
        rep[pins[:, 0]] = pins[:, 1]
    present = np.zeros(NR, dtype=bool)
    present[rep] = True
    cand = np.flatnonzero(present)  # np.unique(rep), without the sort
    pairs = close_pairs(V[NI + cand], weld_tol)
    if len(pairs):
        # every candidate becomes the first (smallest) candidate of its welded group
        lab = components(cand.size, pairs[:, 0], pairs[:, 1])
        remap = np.arange(NR)
        remap[cand] = cand[lab]
        rep = remap[rep]
    if jit is not None and NI + NR < 2_000_000:
        count, E0, kept = jit.weld_triangles(E0, FE, rep, NI, NR, T[n_in:], FP[n_in:])
        T, FP = T[: n_in + count], FP[: n_in + count]
    else:
        T, FP, E0, kept = _weld_triangles(E0, FE, rep, NI, NR, T, FP, n_in)
    UV_pre = UV
    if kept.size != NR:
        # move the kept ring vertices down over the dropped ones (interior ones stay put)
        nv = NI + kept.size
        UV = UV.copy()  # the pre-weld parameters stay available for corner_uv
        for X in (V, N, UV, VP, WK):
            X[NI:nv] = X[NI + kept]
        V, N, UV, VP, WK = V[:nv], N[:nv], UV[:nv], VP[:nv], WK[:nv]
    if WK.any():
        fix_weak_normals(N, WK, UV, VP, cell_index)
    mesh = Tessellation._build(V, T, N, UV, VP, FP, (UV_pre, n_in, E0), max_dev, tol)
    return mesh, bool(len(pins) or len(pairs)), V, T

