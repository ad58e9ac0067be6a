"""Normals where ``Su x Sv`` vanishes (collapsed cell edges such as the poles of a sphere).

:class:`CellIndex` finds the Bézier cell of a mesh vertex from its patch and (u, v);
:func:`fix_weak_normals` replaces the vertex's normal by the limit normal of its cell.
"""

from __future__ import annotations

import numpy as np

from .. import _kernels
from .batch import _bernstein, _bernstein_d

__all__ = ["CellIndex", "fix_weak_normals"]


class CellIndex:
    """Finds the Bézier cell (and its local parameters) of points given by patch and (u, v)."""

    def __init__(self, cellsets, offsets, first, n_cells, nsv, box_of):
        self.cellsets, self.offsets = cellsets, offsets
        self.first, self.n_cells, self.nsv, self.box_of = first, n_cells, nsv, box_of
        self.set_of = np.repeat(np.arange(len(cellsets)), np.diff(offsets))
        self.any_multi = bool((n_cells > 1).any())
        self._corners = None  # (C, 4, 3) limit normals at the cells' corners, made at first use

    def corner_normals(self) -> np.ndarray:
        """``(C, 4, 3)`` limit normals at every cell's corners ``(s, t)`` = (0, 0), (0, 1), (1, 0),
        (1, 1) (:func:`_limit_normals`), computed once: a pole's welded vertex is a corner of
        its cells at every tolerance, so the normals there need no evaluation per call."""
        if self._corners is None:
            C = int(self.offsets[-1])
            g = np.repeat(np.arange(C), 4)
            s = np.tile([0.0, 0.0, 1.0, 1.0], C)
            t = np.tile([0.0, 1.0, 0.0, 1.0], C)
            out = np.empty((4 * C, 3))
            _limit_normals(out, np.arange(4 * C), g, s, t, self)
            self._corners = out.reshape(C, 4, 3)
        return self._corners

    def locate(self, P, u, v):
        """Global cell ``(k,)`` and local ``(s, t)`` of the points ``(P[i], u[i], v[i])``."""
        g = self.first[P]  # right for single-cell patches
        for p in np.unique(P[self.n_cells[P] > 1]) if self.any_multi else ():
            sel = np.flatnonzero(P == p)
            ns_v = self.nsv[p]
            ns_u = self.n_cells[p] // ns_v
            box = self.box_of[self.first[p] : self.first[p] + self.n_cells[p]]
            bu = np.append(box[::ns_v, 0], box[-1, 1])
            bv = np.append(box[:ns_v, 2], box[-1, 3])
            iu = np.clip(np.searchsorted(bu, u[sel], side="right") - 1, 0, ns_u - 1)
            iv = np.clip(np.searchsorted(bv, v[sel], side="right") - 1, 0, ns_v - 1)
            g[sel] = self.first[p] + iu * ns_v + iv
        box = self.box_of[g]
        return g, (u - box[:, 0]) / (box[:, 1] - box[:, 0]), (v - box[:, 2]) / (box[:, 3] - box[:, 2])


def _partial_tables(s, t, p, q):
    """Bernstein values and first derivatives ``(2, p + 1, k)``, ``(2, q + 1, k)`` at the
    local parameters ``s``, ``t`` ``(k,)`` (the batch evaluator's unchecked recurrences: a
    handful of points per call, where the checked public form's argument handling dominates)."""
    return np.stack([_bernstein(p, s), _bernstein_d(p, s)]), np.stack([_bernstein(q, t), _bernstein_d(q, t)])


def _cell_partials(nets, s, t, p, q):
    """``(S, Su, Sv, Suv)`` ``(k, 3)`` of Bézier cells ``nets`` ``(k, p + 1, q + 1, 4)`` at
    local parameters ``s, t`` ``(k,)`` (rational quotient rule)."""
    Bu, Bv = _partial_tables(s, t, p, q)
    A = [[np.einsum("ik,jk,kijc->kc", Bu[a], Bv[b], nets) for b in range(2)] for a in range(2)]
    w = A[0][0][:, 3:]
    S = A[0][0][:, :3] / w
    Su = (A[1][0][:, :3] - A[1][0][:, 3:] * S) / w
    Sv = (A[0][1][:, :3] - A[0][1][:, 3:] * S) / w
    Suv = (A[1][1][:, :3] - A[1][0][:, 3:] * Sv - A[0][1][:, 3:] * Su - A[1][1][:, 3:] * S) / w
    return S, Su, Sv, Suv


def _cross(a, b):
    """Row-wise cross product of ``(k, 3)`` arrays (``np.cross`` costs more on small inputs)."""
    return np.column_stack([
        a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
        a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
        a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
    ])  # fmt: skip


def fix_weak_normals(N, weak, UV, VP, cells: CellIndex):
    """Limit normals where ``Su x Sv`` vanishes (a collapsed edge such as a pole): the
    direction ``Su x Suv + Suv x Sv`` (the limit of ``Su x Sv / v`` at ``v -> 0``),
    oriented like the normal at a point slightly inside the cell. Points at a cell's corner
    (where welding leaves a pole's vertex) take the cell's cached corner normals."""
    idx = np.flatnonzero(weak)
    g, s, t = cells.locate(VP[idx], UV[idx, 0], UV[idx, 1])
    rs, rt = np.rint(s), np.rint(t)
    corner = (np.abs(s - rs) <= 1e-12) & (np.abs(t - rt) <= 1e-12) & (np.abs(rs - 0.5) == 0.5) & (np.abs(rt - 0.5) == 0.5)
    at = np.flatnonzero(corner)
    if at.size:
        N[idx[at]] = cells.corner_normals()[g[at], (2 * rs[at] + rt[at]).astype(np.int64)]
    rest = np.flatnonzero(~corner)
    if rest.size:
        _limit_normals(N, idx[rest], g[rest], s[rest], t[rest], cells)


def _limit_normals(N, rows, g, s, t, cells: CellIndex):
    """Write into ``N[rows]`` the limit normals of cells ``g`` at local ``(s, t)`` (all ``(k,)``),
    see :func:`fix_weak_normals`."""
    sets = cells.set_of[g]
    jit = _kernels.get("splinekit.tessellation._kernels")
    for k in np.unique(sets):
        sel = np.flatnonzero(sets == k)
        cs = cells.cellsets[k]
        nets = cs.nets[g[sel] - cells.offsets[k]]
        s_in, t_in = s[sel] + 1e-3 * (0.5 - s[sel]), t[sel] + 1e-3 * (0.5 - t[sel])
        if jit is not None:
            Bu, Bv = _partial_tables(np.concatenate([s[sel], s_in]), np.concatenate([t[sel], t_in]), cs.p, cs.q)
            N[rows[sel]] = jit.limit_normals(nets, np.ascontiguousarray(Bu), np.ascontiguousarray(Bv))
            continue
        # the points and the points slightly inside, in one evaluation
        _, Su, Sv, Suv = _cell_partials(np.concatenate([nets, nets]), np.concatenate([s[sel], s_in]),
                                        np.concatenate([t[sel], t_in]), cs.p, cs.q)  # fmt: skip
        h = sel.size
        alt = _cross(Su[:h], Suv[:h]) + _cross(Suv[:h], Sv[:h])
        ref = _cross(Su[h:], Sv[h:])
        alt[np.einsum("ij,ij->i", alt, ref) < 0] *= -1.0
        size = np.linalg.norm(alt, axis=1)
        tiny = size <= 1e-14 * (np.linalg.norm(ref, axis=1) + 1e-300)
        alt[tiny] = ref[tiny]
        N[rows[sel]] = alt / np.maximum(np.linalg.norm(alt, axis=1), 1e-300)[:, None]
