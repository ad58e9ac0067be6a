"""Point classification: (u, v) points against a face's trims, 3-D points against a solid.

Both return ``int8`` arrays of :class:`Location` codes: ``INSIDE = 1``, ``ON = 0``, ``OUTSIDE = -1``.

Faces (:func:`contains_uv`)
    Winding of the trims' Bézier pieces, halved where a point is close (:mod:`.trims`). A point
    is ON when its ``(u, v)`` distance to a trim is at most ``tolerance / speed``, ``speed`` the
    surface's largest parametric speed, so every ON point is within ``tolerance`` in 3-D.

Solids (:func:`contains`)
    A bounding-box prefilter, then the side of the solid's closed tessellation: its exact signed
    distance, one nearest-triangle search per point (:mod:`splinekit.tessellation.inside`, which
    shows why that sign is the solid's beyond the tessellation's deviation). Points within the
    deviation plus the tolerance of the mesh are decided exactly from their closest boundary point:
    on a face (the surface's closest point, when it lies inside the face's trims) the sign of the
    outward normal, on an edge the sum of the two faces' normals there; ON when that distance is
    within the tolerance.

    When the tessellation is not closed (or fails), the slow path: the generalized winding number
    of the boundary on a coarse triangle mesh of each face (solid angles of the triangles; 1
    inside, 0 outside), points near those meshes settled exactly as above. Profiled on a box with
    a through hole, that path spent 5.7 s of 7.5 s per 100,000 points in the winding numbers
    (every point against every triangle of the faces whose box holds it), and a filleted box
    (26 faces) about 40 s; the mesh path took 0.33 s and 0.96 s on them once its mesh was cached
    (load average 15 on 2 cores: benchmarks/bench_contains.py).
"""

from __future__ import annotations

import importlib

import numpy as np

from .. import limits
from .._validate import as_float_array
from ..closest import project
from ..errors import ParameterError
from .coarse_mesh import face_cap, face_mesh, point_triangle_distance, winding_numbers
from .trims import INSIDE, ON, OUTSIDE, Location, classify_uv, trim_pieces, uv_tolerance

__all__ = ["Location", "INSIDE", "ON", "OUTSIDE", "contains_uv", "contains", "uv_tolerance"]


def contains_uv(face, uv, tolerance: float | None = None) -> np.ndarray:
    """Classify parameter points against the face's trims.

    Parameters
    ----------
    uv : (n, 2) or (2,) array_like
    tolerance : float, optional
        3-D distance (model units) within which a point counts as ON a trim (default the face's
        tolerance); converted to ``(u, v)`` by :func:`uv_tolerance`.

    Returns an ``int8`` array ``(n,)`` (or a scalar for one point) of :class:`Location` codes.
    """
    arr = as_float_array(uv, "uv")
    single = arr.ndim == 1
    pts = arr.reshape(1, -1) if single else arr
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ParameterError(f"uv must have shape (n, 2), got {arr.shape}")
    if not np.isfinite(pts).all():
        raise ParameterError("uv has non-finite values")
    out = classify_uv(trim_pieces(face), pts, uv_tolerance(face, tolerance))
    return out[0] if single else out


# -- solids ---------------------------------------------------------------------------------------
def _near_mesh(solid, Q, tol):
    """Boolean mask ``(n,)``: points within ``3 deviation + 2 tol`` of a face's mesh (where the
    mesh's winding number may differ from the exact one, or the point may be ON)."""
    from scipy.spatial import cKDTree  # on use: scipy.spatial takes ~0.15 s to import, ten times all of brep

    near = np.zeros(len(Q), dtype=bool)
    for f in solid.faces:
        P, T, dev = face_mesh(f)
        if len(T) == 0:
            continue
        band = 3.0 * dev + 2.0 * tol
        # the mesh lies in the box of the surface's control points: only points near it count
        sel = np.flatnonzero(_box_distance(Q, f.surface.control_points.reshape(-1, 3)) <= band)
        if sel.size == 0:
            continue
        A, B, C = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
        cen = (A + B + C) / 3.0
        R = float(np.max([np.linalg.norm(X - cen, axis=1).max() for X in (A, B, C)]))
        lists = cKDTree(cen).query_ball_point(Q[sel], band + R)
        counts = np.fromiter((len(x) for x in lists), dtype=np.intp, count=len(sel))
        if not counts.any():
            continue
        qi = np.repeat(sel, counts)
        ti = np.fromiter((j for x in lists for j in x), dtype=np.intp, count=int(counts.sum()))
        limits.check(len(ti) * 8 * 30, "point/triangle distance pairs")
        d = point_triangle_distance(Q[qi], A[ti], B[ti], C[ti])
        near[qi[d <= band]] = True
    return near


def _solid_mesh(solid):
    """All faces' meshes as one ``(V, T)`` (cached on the solid)."""
    if "mesh" not in solid._cache:
        meshes = [face_mesh(f) for f in solid.faces]
        offsets = np.cumsum([0] + [len(m[0]) for m in meshes])
        solid._cache["mesh"] = (np.concatenate([m[0] for m in meshes]),
                                np.concatenate([m[1] + o for m, o in zip(meshes, offsets)]))
    return solid._cache["mesh"]


def _solid_winding_numbers(solid, Q, tol):
    """Winding numbers ``(n,)`` of the solid's boundary at ``Q``: per face, its mesh for the points
    inside the box of its control points and, where it has fewer triangles, its cap (the same
    value, exactly) for the points outside."""
    w = np.zeros(len(Q))
    for f in solid.faces:
        P, T, _ = face_mesh(f)
        cV, cT = face_cap(f)
        if len(cT) >= len(T):
            w += winding_numbers(Q, P, T)
            continue
        cp = f.surface.control_points.reshape(-1, 3)
        margin = tol + 1e-9 * float(np.ptp(cp, axis=0).max())
        near = np.all((Q >= cp.min(axis=0) - margin) & (Q <= cp.max(axis=0) + margin), axis=1)
        w[near] += winding_numbers(Q[near], P, T)
        w[~near] += winding_numbers(Q[~near], cV, cT)
    return w


def _bounding_box(solid):
    """Box of every face's control points (contains the solid by the convex-hull property)."""
    pts = np.concatenate([f.surface.control_points.reshape(-1, 3) for f in solid.faces])
    return pts.min(axis=0), pts.max(axis=0)


def contains(solid, points, tolerance: float | None = None) -> np.ndarray:
    """Classify 3-D points against a solid: ``int8`` :class:`Location` codes ``(n,)``.

    Parameters
    ----------
    points : (n, 3) or (3,) array_like
    tolerance : float, optional
        Distance (model units) within which a point is ON the boundary; default the largest face
        tolerance.
    """
    arr = as_float_array(points, "points")
    single = arr.ndim == 1
    P = arr.reshape(1, -1) if single else arr
    if P.ndim != 2 or P.shape[1] != 3:
        raise ParameterError(f"points must have shape (n, 3), got {arr.shape}")
    if not np.isfinite(P).all():
        raise ParameterError("points have non-finite values")
    faces = solid.faces
    tol = max(f.tolerance for f in faces) if tolerance is None else float(tolerance)
    out = np.full(len(P), np.int8(OUTSIDE))
    lo, hi = _bounding_box(solid)
    cand = np.flatnonzero(np.all((P >= lo - tol) & (P <= hi + tol), axis=1))
    if cand.size == 0:
        return out[0] if single else out
    Q = P[cand]
    sides = _mesh_sides(solid, Q, tol)
    if sides is not None:
        codes, near, bound = sides
        near = np.flatnonzero(near)
    else:  # no closed tessellation: winding numbers of the faces' coarse meshes (slow)
        w = _solid_winding_numbers(solid, Q, tol)
        codes = np.where(np.rint(w) % 2 == 1, np.int8(INSIDE), np.int8(OUTSIDE))
        near = np.flatnonzero(_near_mesh(solid, Q, tol))
        bound = None
    out[cand] = codes
    # near the mesh, its chord error may decide wrongly: settle those points exactly
    if near.size:
        out[cand[near]] = _closest_feature_side(solid, Q[near], tol, codes[near], project,
                                                None if bound is None else bound[near])
    return out[0] if single else out


def _mesh_sides(solid, Q, tol):
    """:func:`splinekit.tessellation.inside.mesh_sides`: ``(codes, near, bound)`` or None.

    The tessellation sits below brep in the layer order (it meshes brep's faces), so it is found
    at run time, as brep's ``fuse``/``cut`` find interop, instead of imported here."""
    return importlib.import_module("splinekit.tessellation.inside").mesh_sides(solid, Q, tol)


def _closest_feature_side(solid, Q, tol, fallback, project, bound=None):
    """Location codes of points ``Q`` near the boundary from their closest boundary point: a
    face's interior foot (sign of the outward normal) or an edge (sign of the two faces' normals
    summed). Points whose closest feature is a vertex keep ``fallback`` (the mesh's answer).
    ``bound`` ``(n,)``: upper bounds of the points' distances to the boundary (faces and edges
    whose box is farther are skipped); by default from the coarse meshes' vertices."""
    n = len(Q)
    best = np.full(n, np.inf)
    side = np.zeros(n)
    faces = solid.faces
    if bound is None:
        # the mesh's vertices lie on the boundary: their nearest one bounds the closest distance
        V, _ = _solid_mesh(solid)
        from scipy.spatial import cKDTree  # on use: scipy.spatial takes ~0.15 s to import, ten times all of brep
        bound = cKDTree(V).query(Q)[0] * (1.0 + 1e-9) + tol
    for f in faces:
        sel = np.flatnonzero(_box_distance(Q, f.surface.control_points.reshape(-1, 3)) < np.minimum(best, bound))
        if sel.size == 0:
            continue
        pr = project(f.surface, Q[sel])
        uv = np.asarray(pr.parameters).reshape(len(sel), 2)
        ok = contains_uv(f, uv) != OUTSIDE
        better = ok & (pr.distances < best[sel])
        if better.any():
            nrm = f.normals(uv[better, 0], uv[better, 1])
            idx = sel[better]
            best[idx] = pr.distances[better]
            side[idx] = np.einsum("ij,ij->i", Q[idx] - pr.points[better], nrm)
    vertex = np.zeros(n, dtype=bool)
    for shell in solid.shells:
        topo = shell.topology
        sf = shell.faces
        for g in topo.edges:
            if g.degenerate:
                continue
            fi, li, ei = g.uses[0]
            e = sf[fi].boundary_loops()[li][ei]
            if e.curve is None:
                continue
            sel = np.flatnonzero(_box_distance(Q, e.curve.control_points) < np.minimum(best, bound))
            if sel.size == 0:
                continue
            pr = project(e.curve, Q[sel])
            hit = pr.distances < best[sel]
            if not hit.any():
                continue
            better = sel[hit]
            t = np.asarray(pr.parameters).reshape(len(sel))[hit]
            feet = pr.points[hit]
            dist = pr.distances[hit]
            a, b = e.domain
            at_end = (np.abs(t - a) <= 1e-9 * max(1.0, abs(b - a))) | (np.abs(t - b) <= 1e-9 * max(1.0, abs(b - a)))
            nsum = np.zeros((len(better), 3))
            for (fj, lj, ej) in g.uses:
                use = sf[fj].boundary_loops()[lj][ej]
                # the other use's (u, v) at the same 3-D point: through its own curve's parameter
                uvu = _use_uv(sf[fj], use, t if use is e else None, feet, project)
                nsum += sf[fj].normals(uvu[:, 0], uvu[:, 1])
            best[better] = dist
            side[better] = np.einsum("ij,ij->i", Q[better] - feet, nsum)
            vertex[better] = at_end
    result = np.where(side > 0, np.int8(OUTSIDE), np.int8(INSIDE))
    result[vertex] = fallback[vertex]
    result[best <= tol] = ON
    result[~np.isfinite(best)] = fallback[~np.isfinite(best)]
    return result


def _box_distance(Q, pts):
    """Distances ``(n,)`` from points ``Q`` to the bounding box of ``pts`` (a lower bound of the
    distance to a curve or surface with these control points)."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    return np.linalg.norm(np.maximum(lo - Q, 0.0) + np.maximum(Q - hi, 0.0), axis=1)


def _use_uv(face, use, t, points, project):
    """``(u, v)`` ``(n, 2)`` on ``face`` of ``points`` lying on the edge ``use``: from the edge
    parameter ``t`` when known, else by projecting onto the use's 3-D curve, or (no curve) onto
    the face's surface."""
    if t is None and use.curve is not None:
        t = np.asarray(project(use.curve, points).parameters).reshape(len(points))
    if t is not None:
        return use.pcurve.evaluate(t)
    return np.asarray(project(face.surface, points).parameters).reshape(len(points), 2)
