"""Which faces of a face set the fast tessellation plan (:mod:`.fast_plan`) can mesh, recognised
in one batch: planes (affine faces), right circular cylinders and faces of revolution with a
circular profile (sphere and torus pieces, :mod:`.revolution`), each checked against the face's
own evaluator; and the cylinders' loops as rectangles in ``(u, v)``.
"""

from __future__ import annotations

import math

import numpy as np

from .arcs import REL, CircleMap, _cross, _norm
from .revolution import revolution_nets, revolution_of

__all__ = ["CYLINDER", "PLANE", "REVOLUTION", "curved_faces", "cylinder_loops"]

PLANE, CYLINDER, REVOLUTION = 0, 1, 2
"""Face kinds of a plan (``FastPlan.kind``)."""


def _mask(n, index):
    """``(n,)`` bool, True at ``index`` (``np.isin`` against ``arange(n)`` without its sort)."""
    out = np.zeros(n, dtype=bool)
    out[index] = True
    return out


class _Cylinder:
    """A right circular cylinder face: ``S(u, v) = C(u) + (v - v0) D`` with ``C`` a circle
    (``cmap``: its :class:`.arcs.CircleMap`) whose axis is along ``D``."""

    __slots__ = ("cmap", "axis", "sign")


def _cylinder_net(surface, scale):
    """``(knots, P, W)`` of the circle of ``surface`` at its first ``v`` if ``surface`` may be a
    right circular cylinder (rational quadratic in ``u``, linear in ``v`` along one direction with
    equal weights), else None. Its :class:`.arcs.CircleMap` then goes to :func:`_cylinder`."""
    if surface.degree_v != 1 or surface.degree_u != 2 or surface.weights is None:
        return None
    P = np.asarray(surface.control_points)
    W = np.asarray(surface.weights)
    if P.shape[1] != 2 or np.abs(W[:, 1] - W[:, 0]).max() > 1e-14 * W.max():
        return None
    D = P[:, 1] - P[:, 0]
    if np.abs(D - D[0]).max() > REL * scale:
        return None
    return surface.knots_u, P[:, 0], W[:, 0]


def _cylinder(surface, cmap, mid):
    """The :class:`_Cylinder` of ``surface`` (passed by :func:`_cylinder_net`) whose first circle
    has the map ``cmap`` (or None: not a circle), or None (``mid``: its ``(S, Su, Sv)`` ``(3,)``
    each at the middle of its domain)."""
    if cmap is None:
        return None
    P = np.asarray(surface.control_points)
    D = P[0, 1] - P[0, 0]
    axis = D / math.sqrt(D.dot(D))  # np.linalg.norm's own formula for a vector
    if _norm(_cross(axis, cmap.circle.normal)) > REL:
        return None
    c = _Cylinder()
    c.cmap, c.axis = cmap, axis
    # which way Su x Sv points: outward (from the axis) or inward
    S, Su, Sv = mid
    radial = S - cmap.circle.centre
    radial -= (radial @ axis) * axis
    c.sign = 1.0 if _cross(Su, Sv) @ radial > 0 else -1.0
    return c


def curved_faces(prep, size):
    """``(kind, cyl, rev)`` of the faces that are not affine: each a right circular cylinder
    (``cyl[f]``: :class:`_Cylinder`) or a face of revolution with a circular profile (``rev[f]``:
    :class:`.revolution.Revolution`, its closed form checked against the surface's evaluator on
    a grid); None if some face is neither. The circle maps of all faces are built in one batch
    (:meth:`.arcs.CircleMap.batch`), the grid checks evaluated in one call."""
    faces, batch = prep.faces, prep.batch
    kind = np.full(len(faces), PLANE)
    cyl, rev = {}, {}
    curved = np.flatnonzero(~prep.affine).tolist()
    if not curved:
        return kind, cyl, rev
    # the circles each face needs: a cylinder's first circle, or a revolution's two isocurves
    nets, wants = [], []
    for f in curved:
        net = _cylinder_net(faces[f].surface, size)
        if net is not None:
            wants.append((f, CYLINDER, len(nets)))
            nets.append(net)
            continue
        pair = revolution_nets(faces[f].surface)
        if pair is None:
            return None
        wants.append((f, REVOLUTION, len(nets)))
        nets.extend(pair)
    maps = CircleMap.batch(nets, size)
    cf = np.array([f for f, k, _ in wants if k == CYLINDER], dtype=np.int64)
    if cf.size:
        dom = np.array([faces[f].surface.domain for f in cf])  # (n, 2, 2)
        S, Su, Sv = batch.partials(cf, 0.5 * (dom[:, 0, 0] + dom[:, 0, 1]), 0.5 * (dom[:, 1, 0] + dom[:, 1, 1]))
    grids, q = [], 0
    for f, k, i in wants:
        if k == CYLINDER:
            c = _cylinder(faces[f].surface, maps[i], (S[q], Su[q], Sv[q]))
            q += 1
            if c is None:  # linear in v: no face of revolution with a circular profile either
                return None
            kind[f], cyl[f] = CYLINDER, c
            continue
        found = revolution_of(faces[f].surface, maps[i], maps[i + 1], size)
        if found is None:
            return None
        kind[f], rev[f] = REVOLUTION, found[0]
        grids.append((f, found[1], found[2], found[3]))
    if grids:
        f = np.concatenate([np.full(u.size, f) for f, u, _, _ in grids])
        want = batch.evaluate(f, np.concatenate([g[1] for g in grids]), np.concatenate([g[2] for g in grids]))
        got = np.concatenate([g[3] for g in grids])
        if np.abs(got - want).max() > REL * size:
            return None
    return kind, cyl, rev


def cylinder_loops(plan, prep, uv0, uv1) -> bool:
    """Whether every cylinder face has one loop that is a rectangle in ``(u, v)``: circle arcs
    along ``v = v_lo`` (u increasing, the bottom), a ruling at ``u = u_hi``, arcs along
    ``v = v_hi`` (u decreasing, the top) and a ruling at ``u = u_lo``. Keeps per face the loop's
    uses rotated to start at the bottom: ``cyl_faces[f] = (uses, n_bottom)``. All cylinders at
    once (their uses are consecutive, face after face)."""
    plan.cyl_faces = {}
    faces = np.array(sorted(plan.cyl), dtype=np.int64)
    if faces.size == 0:
        return True
    on = _mask(len(plan.faces), faces)[plan.use_face]
    use = np.flatnonzero(on)
    if (prep.table.loop[use] != 0).any():
        return False
    fu = plan.use_face[use]
    first = np.flatnonzero(np.concatenate([[True], fu[1:] != fu[:-1]]))
    n = np.diff(np.append(first, use.size))
    block = np.repeat(np.arange(first.size), n)
    a, b = uv0[use], uv1[use]
    lo = np.minimum.reduceat(np.minimum(a, b), first)[block]
    hi = np.maximum.reduceat(np.maximum(a, b), first)[block]
    eps = 1e-9 * (hi - lo)
    arc = plan.arc_of[plan.use_group[use]] >= 0

    def at(c, d):
        return (np.abs(a[:, d] - c[:, d]) <= eps[:, d]) & (np.abs(b[:, d] - c[:, d]) <= eps[:, d])

    bottom = arc & at(lo, 1) & (b[:, 0] > a[:, 0])
    top = arc & at(hi, 1) & (b[:, 0] < a[:, 0])
    right = ~arc & at(hi, 0) & (b[:, 1] > a[:, 1])
    left = ~arc & at(lo, 0) & (b[:, 1] < a[:, 1])
    label = np.select([bottom, right, top, left], [0, 1, 2, 3], -1)
    count = np.stack([np.bincount(block, label == k, first.size) for k in range(4)], axis=1)
    if (label < 0).any() or (count[:, 1] != 1).any() or (count[:, 3] != 1).any():
        return False
    # each loop rotated to start at its bottom: the bottoms, the right ruling, the tops, the left ruling
    nb, nt = count[:, 0].astype(np.int64), count[:, 2].astype(np.int64)
    start = (np.flatnonzero(label == 1) - first - nb) % n
    j = np.arange(use.size) - first[block]
    order = first[block] + (start[block] + j) % n[block]
    lab = label[order]
    want = np.where(j < nb[block], 0, np.where(j == nb[block], 1, np.where(j <= nb[block] + nt[block], 2, 3)))
    if (lab != want).any():
        return False
    for k, f in enumerate(faces.tolist()):
        plan.cyl_faces[f] = (use[order[first[k] : first[k] + n[k]]], int(nb[k]))
    return True
