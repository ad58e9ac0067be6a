"""Representations on the surface itself: the exact patches (refined by knot insertion, the same
surface with more control points) and a point cloud of exact samples with their normals."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..brep import Shell, Solid, TrimmedFace
from ..closest import project
from ..diffgeom import curvature
from ..pointcloud.analysis import curvature as cloud_curvature
from ..surfaces import BSplineSurface, NurbsSurface
from .holder import Holder, bend

__all__ = ["ExactPatches", "PointCloud"]


def _as_spline(p):
    """A Bézier patch as the equal B-spline / NURBS patch (knot insertion needs knots)."""
    if hasattr(p, "refine"):
        return p
    knots_u = [0.0] * (p.degree_u + 1) + [1.0] * (p.degree_u + 1)
    knots_v = [0.0] * (p.degree_v + 1) + [1.0] * (p.degree_v + 1)
    if p.weights is None:
        return BSplineSurface(p.degree_u, p.degree_v, knots_u, knots_v, p.control_points)
    return NurbsSurface(p.degree_u, p.degree_v, knots_u, knots_v, p.control_points, p.weights)


def _with_points(p, points):
    """Patch ``p`` with its Cartesian control points replaced (weights kept)."""
    if p.weights is None:
        return BSplineSurface(p.degree_u, p.degree_v, p.knots_u, p.knots_v, points)
    return NurbsSurface(p.degree_u, p.degree_v, p.knots_u, p.knots_v, points, p.weights)


def _refine(p, spans: int):
    """``p`` with every knot span split into ``spans`` equal spans in each direction (the same surface)."""
    p = _as_spline(p)
    if spans == 1:
        return p
    t = np.arange(1, spans) / spans

    def inside(knots, degree):
        breaks = np.unique(knots[degree:len(knots) - degree])
        return (breaks[:-1, None] + np.diff(breaks)[:, None] * t).ravel()

    return p.refine(inside(p.knots_u, p.degree_u), "u").refine(inside(p.knots_v, p.degree_v), "v")


def _by_patch(patch, fn, n_out):
    """``out[i] = fn(patch_index, selection)`` for each patch index present: one batched call per patch."""
    out = np.empty((len(patch), n_out)) if n_out else np.empty(len(patch))
    order = np.argsort(patch, kind="stable")
    bounds = np.flatnonzero(np.diff(patch[order])) + 1
    for sel in np.split(order, bounds):
        if sel.size:
            out[sel] = fn(int(patch[sel[0]]), sel)
    return out


def patch_set_genus(patches, tolerance: float) -> float:
    """Genus of a closed, connected set of patches sewn where corners and edge midpoints
    coincide within ``tolerance``: ``chi = V - E + F`` with ``V`` the distinct corners, ``E``
    the distinct edges that do not collapse to a point (a sphere's poles), ``F`` the patches;
    ``genus = (2 - chi) / 2``. Assumes patches meet edge to edge (no T-junctions)."""
    corners_uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    mids_uv = np.array([[0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5]])
    corners, mids, ends = [], [], []
    for p in patches:  # eight points per patch
        (u0, u1), (v0, v1) = p.domain
        uv = np.vstack([corners_uv, mids_uv])
        pts = p.evaluate(u0 + (u1 - u0) * uv[:, 0], v0 + (v1 - v0) * uv[:, 1])
        corners.append(pts[:4])
        mids.append(pts[4:])
        ends.append(np.stack([pts[:4], np.roll(pts[:4], -1, axis=0)], axis=1))
    corners, mids, ends = np.concatenate(corners), np.concatenate(mids), np.concatenate(ends)

    def distinct(points):  # groups of points closer than the tolerance, chained
        pairs = cKDTree(points).query_pairs(tolerance, output_type="ndarray")
        graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points),) * 2)
        return connected_components(graph, directed=False)[0]

    collapsed = (np.linalg.norm(ends[:, 0] - mids, axis=1) <= tolerance) & (np.linalg.norm(ends[:, 1] - mids, axis=1) <= tolerance)
    chi = distinct(corners) - distinct(mids[~collapsed]) + len(patches)
    return (2 - chi) / 2


class ExactPatches(Holder):
    """The exact patches with every knot span split into ``resolution`` spans per direction by
    knot insertion: the same surface, more control points. Holds control points, weights and
    knots. Closest points: the patch of the nearest reference triangle, then Newton point
    inversion on it (:func:`splinekit.project`); inside/outside: the side of the exact normal at
    that closest point (right for points nearer the surface than its thinnest part; the B-rep
    ray classification, :meth:`splinekit.brep.Solid.contains`, is right everywhere but spends
    about 35 s setting up on the mug's 536 patches). Accuracy is measured at the reference
    samples' own parameters (knot insertion keeps the parametrization)."""

    name = "exact patches"
    resolution_name = "spans per knot span"
    default_resolutions = (1, 2, 4)
    not_applicable = {}
    query_points = 50  # one Newton projection per patch touched: the slowest queries here

    def __init__(self, shape, reference, resolution):
        self.resolution = int(resolution)
        self.reference = reference
        self.patches = [_refine(p, self.resolution) for p in shape.patches]
        parts = {"control_points": [p.control_points.ravel() for p in self.patches],
                 "knots": [np.concatenate([p.knots_u, p.knots_v]) for p in self.patches],
                 "weights": [p.weights.ravel() for p in self.patches if p.weights is not None]}
        self.arrays = {k: np.concatenate(v) if v else np.empty(0) for k, v in parts.items()}
        self.solid = Solid([Shell([TrimmedFace(p) for p in self.patches])])
        self.linear = float(self.resolution)

    @staticmethod
    def estimate_bytes(shape, reference, resolution):
        return len(shape.patches) * (int(resolution) + 3) ** 2 * 24.0 * 4

    # -- queries ---------------------------------------------------------------------------
    def random_parameters(self, n, rng):
        return rng.integers(0, len(self.patches), n), rng.random((n, 2))

    def _uv(self, patch, uv):
        (u0, u1), (v0, v1) = self.patches[patch].domain
        return u0 + (u1 - u0) * uv[:, 0], v0 + (v1 - v0) * uv[:, 1]

    def point(self, patch, uv):
        """Points from parameters: patch index ``(n,)`` and ``(u, v)`` in the unit square ``(n, 2)``."""
        return _by_patch(patch, lambda i, s: self.patches[i].evaluate(*self._uv(i, uv[s])), 3)

    def inside(self, points):
        close, normal = self._project(points)
        return np.einsum("nd,nd->n", points - close, normal) < 0

    def _project(self, points):
        """``(closest points (n, 3), unit normals (n, 3))``: Newton on the patch of the nearest
        reference triangle."""
        tri = self.reference.distance.query(points)[2]
        patch = np.asarray(self.reference.mesh.face_patch)[tri]
        out = np.empty((len(points), 6))

        def one(i, s):
            pr = project(self.patches[i], points[s])
            d = self.patches[i].derivatives(pr.parameters[:, 0], pr.parameters[:, 1], 1)
            n = np.cross(d[1, 0], d[0, 1])
            n *= self.reference.flip / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
            return np.hstack([pr.points, n])

        out = _by_patch(patch, one, 6)
        return out[:, :3], out[:, 3:]

    def closest(self, points):
        return self._project(points)[0]

    def normal(self, points):
        return self._project(points)[1]

    def _at_reference(self, fn, n_out):
        ref = self.reference
        return _by_patch(ref.patch, lambda i, s: fn(self.patches[i], ref.uv[s, 0], ref.uv[s, 1]), n_out)

    def distance(self, points):
        """At the reference samples only: ``|S(u, v) - S_refined(u, v)|`` at the same parameters
        (knot insertion keeps the parametrization), an upper bound of the distance."""
        return np.linalg.norm(self._at_reference(lambda p, u, v: p.evaluate(u, v), 3) - self.reference.points, axis=1)

    def surface_points(self, n, rng):
        return self.point(*self.random_parameters(n, rng))

    def reference_normals(self):
        """Exact unit normals at the reference samples' parameters."""
        def normals(p, u, v):
            d = p.derivatives(u, v, 1)
            n = np.cross(d[1, 0], d[0, 1])
            return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)

        return self.reference.flip * self._at_reference(normals, 3)

    def mean_curvature(self, points):
        """``|H|`` from the exact second fundamental form at the reference samples' parameters."""
        return self._at_reference(lambda p, u, v: np.abs(curvature(p, u, v).mean), 0)

    def volume(self):
        return abs(float(Shell([TrimmedFace(p) for p in self.patches]).volume(1e-8)))

    def genus(self):
        """Genus of the patch set from its own corners and edges (:func:`patch_set_genus`)."""
        return patch_set_genus(self.patches, 1e-6 * self.reference.diagonal)

    def bent_distance(self, exact_points, radius):
        """Bend the control points (the usual approximation: a bend is not a projective map, so
        the bent patches are not the bent surface); ``|bend(S) - S_bent|`` at the same parameters."""
        bent = [_with_points(p, bend(p.control_points.reshape(-1, 3), radius).reshape(p.control_points.shape))
                for p in self.patches]
        ref = self.reference
        got = _by_patch(ref.patch, lambda i, s: bent[i].evaluate(ref.uv[s, 0], ref.uv[s, 1]), 3)
        return np.linalg.norm(got - bend(ref.points, radius), axis=1)


class PointCloud(Holder):
    """``resolution`` points drawn uniformly by area on the exact patches, with exact outward
    normals. Closest point, normal and inside/outside come from the nearest sample (a k-d tree);
    the cloud has no surface between its samples."""

    name = "point cloud"
    resolution_name = "points"
    default_resolutions = (1000, 4000, 16000)
    not_applicable = {
        "point": "no parametrization: the samples are unordered",
        "volume": "bounds no volume without a reconstruction",
        "genus": "no connectivity, so no topology, without a reconstruction",
        "render": "the renderer draws surfaces; a cloud needs a reconstruction first (splinekit.convert.points_to_mesh)",
        "boolean": "no inside/outside region to combine without a reconstruction",
    }

    def __init__(self, shape, reference, resolution):
        self.resolution = int(resolution)
        rng = np.random.default_rng(0)
        # patch by area (the reference weights), then uniform parameters within it
        w = np.bincount(reference.patch, weights=reference.weights, minlength=len(shape.patches))
        patch = rng.choice(len(shape.patches), self.resolution, p=w / w.sum())
        uv = rng.random((self.resolution, 2))

        def one(i, s):
            p = shape.patches[i]
            (u0, u1), (v0, v1) = p.domain
            c = curvature(p, u0 + (u1 - u0) * uv[s, 0], v0 + (v1 - v0) * uv[s, 1])
            return np.hstack([c.points, reference.flip * c.normal])

        data = _by_patch(patch, one, 6)
        self.arrays = {"points": np.ascontiguousarray(data[:, :3]), "normals": np.ascontiguousarray(data[:, 3:])}
        self.tree = cKDTree(self.arrays["points"])
        self.linear = float(np.sqrt(self.resolution))

    @staticmethod
    def estimate_bytes(shape, reference, resolution):
        return int(resolution) * 400.0

    def _nearest(self, points):
        return self.tree.query(points)

    def inside(self, points):
        _, i = self._nearest(points)
        return np.einsum("nd,nd->n", points - self.arrays["points"][i], self.arrays["normals"][i]) < 0

    def closest(self, points):
        return self.arrays["points"][self._nearest(points)[1]]

    def normal(self, points):
        return self.arrays["normals"][self._nearest(points)[1]]

    def distance(self, points):
        return self._nearest(points)[0]

    def surface_points(self, n, rng):
        pts = self.arrays["points"]
        return pts if len(pts) <= n else pts[rng.choice(len(pts), n, replace=False)]

    def mean_curvature(self, points):
        """``|H|`` of a quadric fitted to the neighbours of the nearest sample (PCA frame)."""
        est = cloud_curvature(self.arrays["points"], normals=self.arrays["normals"])
        return np.abs(est.mean)[self._nearest(points)[1]]

    def bent_distance(self, exact_points, radius):
        """Bending moves every sample exactly (a pointwise map): the cloud's error is unchanged;
        measured as the distance from the bent exact points to the bent samples."""
        return cKDTree(bend(self.arrays["points"], radius)).query(bend(exact_points, radius))[0]
