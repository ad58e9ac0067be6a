"""The trimming loops of a face set as flat point arrays (step 3 of :mod:`.trimmed`), checked,
and the faces' scaled parameter planes laid side by side.

The per-use bookkeeping that does not depend on the tolerance (which group each use belongs to,
the next use in its loop, where each loop starts) is a :class:`LoopTable`, built once per face
set; each call then only gathers the uses' samples and checks every loop at once.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .edges import _face_name

__all__ = ["Layout", "LoopTable", "gather_loops"]

UV_GAP = 0.25
"""Largest gap (scaled grid steps) between one edge's last (u, v) and the next edge's first."""


class LoopTable:
    """Tolerance-independent indices of the edge uses ``uses`` (face after face, loop after
    loop, as :func:`.edges.edge_uses` lists them) grouped by ``groups``: per use its group
    ``group_of``, face ``face``, loop within the face ``loop``, position ``pos`` and the next
    use of its loop ``next_use``; per loop its first use ``first``, use count ``count``, face
    ``loop_face`` and index within the face ``loop_index``."""

    def __init__(self, faces, uses, groups):
        n = len(uses)
        self.faces = faces
        self.group_of = np.empty(n, dtype=np.int64)
        if groups:
            self.group_of[np.concatenate(groups)] = np.repeat(np.arange(len(groups)), [len(m) for m in groups])
        self.face, self.loop, self.pos = np.array([(u.f, u.loop, u.pos) for u in uses], dtype=np.int64).reshape(n, 3).T.copy()
        new = np.ones(n, dtype=bool)
        new[1:] = (self.face[1:] != self.face[:-1]) | (self.loop[1:] != self.loop[:-1])
        self.first = np.flatnonzero(new)
        self.count = np.diff(np.append(self.first, n))
        loop_of = np.cumsum(new) - 1
        last = self.first[loop_of] + self.count[loop_of] - 1
        self.next_use = np.where(np.arange(n) == last, self.first[loop_of], np.arange(n) + 1)
        self.loop_face = self.face[self.first]
        self.loop_index = self.loop[self.first]
        self.group_list = self.group_of.tolist()


def gather_loops(table, samples, vid_of_group, scales):
    """The loops' points, loop after loop (last point of a loop not repeated): ``(face (n,),
    uv (n, 2), xyz (n, 3), vid (n,), use (n,), sizes (L,))`` with ``use`` the edge use each
    point belongs to (a corner belongs to the use that starts there) and ``sizes`` the points
    per loop. Checked: closed in 3-D and in ``(u, v)``, the outer loop counter-clockwise and the
    inner loops clockwise; else ParameterError naming the face, loop and edge."""
    uvs, xyzs, vids = [], [], []
    for k, g in enumerate(table.group_list):
        smp = samples[g]
        uv, vid = smp.uv[k], vid_of_group[g]
        xyz = np.broadcast_to(smp.points[:1], (len(uv), 3)) if smp.degenerate else smp.points
        s = smp.params[k]
        if s[-1] < s[0]:  # this use runs against the group's samples
            uv, vid, xyz = uv[::-1], vid[::-1], xyz[::-1]
        uvs.append(uv)
        xyzs.append(xyz)
        vids.append(vid)
    lens = np.array([len(v) for v in vids], dtype=np.int64)
    UV, XYZ, VID = np.concatenate(uvs), np.concatenate(xyzs), np.concatenate(vids)
    end = np.cumsum(lens) - 1
    start = end - lens + 1
    nxt = table.next_use
    # closure: each edge must end where the next one starts, in 3-D and in (u, v)
    open_ = np.flatnonzero(VID[end] != VID[start[nxt]])
    # (a corner at a pole may jump in u: the gap must only stay well below the grid step)
    d = (UV[end] - UV[start[nxt]]) * scales[table.face]
    jump = np.flatnonzero(np.hypot(d[:, 0], d[:, 1]) > UV_GAP)
    if open_.size or jump.size:
        k = int(open_[0] if open_.size else jump[0])
        f, l, j, n = int(table.face[k]), int(table.loop[k]), int(table.pos[k]), int(table.pos[nxt[k]])
        name = _face_name(table.faces[f], f)
        if open_.size:
            gap = float(np.linalg.norm(XYZ[end[k]] - XYZ[start[nxt[k]]]))
            raise ParameterError(f"{name}: loop {l} is not closed: edge {j} ends {gap:.3g} away from where edge {n} starts")
        raise ParameterError(f"{name}: loop {l} is not closed in (u, v): edge {j} ends at {UV[end[k]].tolist()}, "
                             f"edge {n} starts at {UV[start[nxt[k]]].tolist()}")  # fmt: skip
    keep = np.ones(len(VID), dtype=bool)
    keep[end] = False
    UV, XYZ, VID = UV[keep], XYZ[keep], VID[keep]
    use = np.repeat(np.arange(len(lens)), lens - 1)
    sizes = np.add.reduceat(lens - 1, table.first)
    small = np.flatnonzero(sizes < 2 + (table.count == 1))
    lstart = np.cumsum(sizes) - sizes
    if small.size:
        m = int(small[0])
        f = int(table.loop_face[m])
        raise ParameterError(f"{_face_name(table.faces[f], f)}: loop {int(table.loop_index[m])} encloses no area")
    after = np.arange(len(UV)) + 1
    after[lstart + sizes - 1] = lstart
    area = 0.5 * np.add.reduceat(UV[:, 0] * UV[after, 1] - UV[after, 0] * UV[:, 1], lstart)
    outer = table.loop_index == 0
    wrong = np.flatnonzero(np.where(outer, area <= 0, area >= 0))
    if wrong.size:
        m = int(wrong[0])
        f = int(table.loop_face[m])
        want = "counter-clockwise (outer loop)" if outer[m] else "clockwise (inner loop)"
        raise ParameterError(f"{_face_name(table.faces[f], f)}: loop {int(table.loop_index[m])} faces the wrong way: "
                             f"it must run {want} in (u, v), material on its left")  # fmt: skip
    return table.face[use], UV, XYZ, VID, use, sizes


class Layout:
    """The faces' scaled parameter planes side by side: face ``f``'s point ``uv`` sits at
    ``(uv - lo[f]) * scale[f] + (x0[f], 0)``; ``lo``, ``hi``: the bounding box of the face's
    outer loop (``uv`` ``(n, 2)`` the loops' points, ``sizes`` per loop, ``table`` their
    :class:`LoopTable`)."""

    GAP = 4.0

    def __init__(self, uv, sizes, table, scales):
        self.scale = scales
        lstart = np.cumsum(sizes) - sizes
        lo, hi = np.minimum.reduceat(uv, lstart), np.maximum.reduceat(uv, lstart)
        outer = table.loop_index == 0
        self.lo = np.empty((len(scales), 2))
        self.hi = np.empty((len(scales), 2))
        self.lo[table.loop_face[outer]] = lo[outer]
        self.hi[table.loop_face[outer]] = hi[outer]
        width = (self.hi[:, 0] - self.lo[:, 0]) * scales[:, 0]
        self.x0 = np.concatenate([[0.0], np.cumsum(width + self.GAP)[:-1]])

    def place(self, fidx, uv):
        out = (uv - self.lo[fidx]) * self.scale[fidx]
        out[:, 0] += self.x0[fidx]
        return out

    def unplace(self, fidx, P):
        """The inverse of :meth:`place`."""
        out = P.copy()
        out[:, 0] -= self.x0[fidx]
        return out / self.scale[fidx] + self.lo[fidx]
