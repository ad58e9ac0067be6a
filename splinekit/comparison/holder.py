"""What every representation answers in a comparison: :class:`Holder` and the mesh-backed base
:class:`MeshHolder` (triangle meshes, subdivision meshes, meshed zero sets).

A holder is built from a :class:`~splinekit.comparison.shape.Shape` (and its
:class:`~splinekit.comparison.shape.Reference`) at one resolution. It keeps its defining arrays
in :attr:`Holder.arrays` (``bytes`` is their total ``nbytes``); acceleration structures (k-d
trees, bounding-volume hierarchies) are built during the build, counted in its time and not in
its bytes. Queries take ``(n, 3)`` points near the surface. A query or operation that does not
apply is absent from the class and named in :attr:`Holder.not_applicable` with the reason.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..mesh.components import genus
from ..pointcloud.meshdistance import MeshDistance

__all__ = ["Holder", "MeshHolder", "bend", "unbend"]


def bend(points, radius: float) -> np.ndarray:
    """Bend ``(n, 3)`` points about the line ``x = 0, z = -radius`` (parallel to y): the plane
    ``z = 0`` wraps onto the cylinder of that radius, ``x`` becoming arc length. Smooth and
    invertible for ``z > -radius`` (:func:`unbend`)."""
    p = np.asarray(points, dtype=float)
    theta = p[:, 0] / radius
    r = radius + p[:, 2]
    return np.column_stack([r * np.sin(theta), p[:, 1], r * np.cos(theta) - radius])


def unbend(points, radius: float) -> np.ndarray:
    """The inverse of :func:`bend` (for warping implicit functions: ``F(unbend(x))``)."""
    p = np.asarray(points, dtype=float)
    theta = np.arctan2(p[:, 0], p[:, 2] + radius)
    r = np.hypot(p[:, 0], p[:, 2] + radius)
    return np.column_stack([radius * theta, p[:, 1], r - radius])


class Holder:
    """One representation of a shape at one resolution (module notes).

    Class attributes: ``name``; ``resolution_name`` (what the resolution counts);
    ``default_resolutions``; ``not_applicable`` (query or operation -> why not).
    Instance attributes: ``resolution``; ``linear`` (a linear resolution N: samples per
    length, for the growth fits); ``arrays`` (name -> the arrays held).
    """

    name = ""
    resolution_name = ""
    default_resolutions: tuple = ()
    not_applicable: dict = {}

    @property
    def nbytes(self) -> int:
        return int(sum(a.nbytes for a in self.arrays.values()))

    def applies(self, what: str) -> bool:
        return what not in self.not_applicable

    @staticmethod
    def estimate_bytes(shape, reference, resolution) -> float:
        """Peak bytes the build at ``resolution`` allocates, about (checked against the budget)."""
        return 0.0


class MeshHolder(Holder):
    """A representation whose surface is a closed polygon mesh ``self.mesh`` (set by the build,
    then :meth:`_index` builds the distance structure and vertex tree)."""

    def _index(self, mesh):
        self.mesh = mesh
        self.tree = MeshDistance.of_mesh(mesh)
        self.tree.query(mesh.vertices[:1])  # builds the search structure now (build time, not query time)
        self._vertex_tree = cKDTree(np.asarray(mesh.vertices))
        corners = np.asarray(mesh.vertices)[self.tree.tris]
        n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        self._triangle_normals = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        self._corners = corners

    # -- queries ---------------------------------------------------------------------------
    def point(self, triangle, barycentric) -> np.ndarray:
        """Points from parameters: triangle index ``(n,)`` and barycentric coordinates ``(n, 3)``."""
        return np.einsum("nk,nkd->nd", barycentric, self._corners[triangle])

    def random_parameters(self, n, rng):
        tri = rng.integers(0, len(self._corners), n)
        b = rng.dirichlet(np.ones(3), n)
        return tri, b

    def inside(self, points) -> np.ndarray:
        return self.tree.signed(points)[0] < 0

    def closest(self, points) -> np.ndarray:
        return self.tree.query(points)[1]

    def normal(self, points) -> np.ndarray:
        return self._triangle_normals[self.tree.query(points)[2]]

    def distance(self, points) -> np.ndarray:
        """Unsigned distance ``(n,)`` from points to this representation's surface."""
        return self.tree.query(points)[0]

    def surface_points(self, n, rng) -> np.ndarray:
        """Points on this representation's surface: vertices and triangle centres (where a flat
        triangle is farthest from a curved surface), ``n`` of them at most."""
        pts = np.vstack([np.asarray(self.mesh.vertices), self._corners.mean(axis=1)])
        return pts if len(pts) <= n else pts[rng.choice(len(pts), n, replace=False)]

    def mean_curvature(self, points) -> np.ndarray:
        """``|H|`` (discrete, cotangent Laplacian) at the mesh vertex nearest each point."""
        H = np.abs(np.asarray(self.mesh.mean_curvature))
        return H[self._vertex_tree.query(points)[1]]

    def volume(self) -> float:
        return float(self.mesh.volume)

    def genus(self):
        return genus(self.mesh)

    def render_mesh(self):
        return self.mesh

    def bent_distance(self, exact_points, radius) -> np.ndarray:
        """Bend the vertices; distances ``(n,)`` from the bent exact points to the bent mesh."""
        bent = self.mesh.with_vertices(bend(self.mesh.vertices, radius))
        return MeshDistance.of_mesh(bent).query(bend(exact_points, radius))[0]
