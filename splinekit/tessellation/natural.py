"""Faces bounded by their natural domain, meshed by the patch-set machinery.

A face whose one loop runs along the four sides of its surface's parameter rectangle, and
none of whose edges is shared with another face (only seams, where the face meets itself, and
degenerate pole edges: a whole sphere, a whole torus, a closed B-spline body of one face), needs
no trims: no constrained triangulation in ``(u, v)``, no trim clearance, no Triangle call. Its
surface is meshed as an untrimmed patch (:func:`.surfaces.tessellate_patches`: structured
grids, poles collapsed, the seam welded where its two sides coincide, so a closed face gives a
closed mesh), with the same deviation yardstick (triangle centres and edge midpoints, the surface
at the barycentric ``(u, v)`` against the flat point). The face's own orientation decides the
mesh's: a reversed face's triangles and normals are flipped; nothing is turned "outward" by
volume, as the patch path does for loose patch sets.

:func:`natural_faces` tells which faces of a set qualify; :func:`tessellate_natural` meshes them;
:func:`concatenate` joins that mesh with the trimmed path's mesh of the other faces (they share
no edges, hence no vertices).
"""

from __future__ import annotations

import numpy as np

from ..surfaces import BezierSurface
from .result import Tessellation
from .surfaces import tessellate_patches

__all__ = ["concatenate", "natural_faces", "tessellate_natural"]

SIDE_RTOL = 1e-12
"""How far (relative to the domain's range) a pcurve's control point may lie off a side of the
domain rectangle and still count as on it."""


def _on_one_side(pcurve, domain) -> bool:
    """Whether every control point of the 2-D ``pcurve`` lies on one side of the rectangle
    ``domain`` ``((u0, u1), (v0, v1))`` (then the curve runs along that side)."""
    P = np.asarray(pcurve.control_points, dtype=np.float64)
    for axis in (0, 1):
        lo, hi = domain[axis]
        slack = SIDE_RTOL * max(hi - lo, 1.0)
        for end in (lo, hi):
            if np.all(np.abs(P[:, axis] - end) <= slack):
                return True
    return False


def natural_faces(faces, uses, table) -> np.ndarray:
    """``(len(faces),)`` bool: faces with one loop lying on their domain's sides whose edges are
    used by no other face (``uses``: the face set's :class:`.edges.EdgeUse` list; ``table``: its
    :class:`.loops.LoopTable`, which gives each use's face and edge group)."""
    ok = np.array([len(face.boundary_loops()) == 1 for face in faces], dtype=bool)
    # shared edges first: in a closed solid every face has one, and no pcurve need be looked at;
    # a group is shared when its uses' faces differ (all groups in one pass)
    G = int(table.group_of.max()) + 1 if table.group_of.size else 0
    lo, hi = np.full(G, len(faces)), np.full(G, -1)
    np.minimum.at(lo, table.group_of, table.face)
    np.maximum.at(hi, table.group_of, table.face)
    ok[table.face[lo[table.group_of] != hi[table.group_of]]] = False
    for i in np.flatnonzero(ok[table.face]).tolist():
        u = uses[i]
        if ok[u.f] and not _on_one_side(u.edge.pcurve, faces[u.f].surface.domain):
            ok[u.f] = False
    return ok


def surfaces_of(faces) -> list:
    """The faces' surfaces as spline surfaces (the patch path's input; Bézier ones converted)."""
    return [f.surface.to_bspline() if isinstance(f.surface, BezierSurface) else f.surface for f in faces]


def tessellate_natural(surfaces, reversed_, tol: float, angle_tol, size: float) -> Tessellation:
    """The mesh of natural-domain faces (their ``surfaces``, ``reversed_`` ``(k,)`` bool) by the
    patch path: ``face_patch`` / ``vertex_patch`` index these faces; reversed faces flipped."""
    mesh = tessellate_patches(surfaces, tol, angle_tol, size, orient=False)
    if not reversed_.any():
        return mesh
    F = np.array(mesh.faces)
    corner = np.array(mesh.corner_uv)
    flip = reversed_[mesh.face_patch]
    F[flip] = F[flip][:, ::-1]
    corner[flip] = corner[flip][:, ::-1]
    normals = np.array(mesh.normals)
    normals[reversed_[mesh.vertex_patch]] *= -1.0
    return Tessellation._build(mesh.vertices, F, normals, mesh.uv, mesh.vertex_patch, mesh.face_patch, corner,
                               mesh.max_deviation, mesh.tolerance)  # fmt: skip


def concatenate(parts, tol: float) -> Tessellation:
    """One :class:`Tessellation` of meshes that share no vertices: ``parts`` is a list of
    ``(mesh, face_index)`` with ``face_index`` mapping each mesh's patch indices to the face set's."""
    V, F, N, UV, VP, FP, CU = [], [], [], [], [], [], []
    base = 0
    for mesh, index in parts:
        V.append(mesh.vertices)
        F.append(np.asarray(mesh.faces) + base)
        N.append(mesh.normals)
        UV.append(mesh.uv)
        VP.append(index[mesh.vertex_patch])
        FP.append(index[mesh.face_patch])
        CU.append(mesh.corner_uv)
        base += mesh.n_vertices
    dev = max(mesh.max_deviation for mesh, _ in parts)
    return Tessellation._build(np.concatenate(V), np.concatenate(F), np.concatenate(N), np.concatenate(UV),
                               np.concatenate(VP), np.concatenate(FP), np.concatenate(CU), dev, tol)  # fmt: skip
