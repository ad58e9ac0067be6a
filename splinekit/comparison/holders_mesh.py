"""Mesh representations: a triangle mesh at a chordal tolerance, and a Catmull-Clark cage refined
``L`` times, as it is (the control mesh) or with its vertices moved to the limit surface."""

from __future__ import annotations

import numpy as np

from ..mesh.polymesh import PolyMesh
from ..subdiv import SubdivisionSurface
from ..tessellation import tessellate
from ..pointcloud.meshdistance import MeshDistance
from .holder import MeshHolder, bend

__all__ = ["SubdivisionCage", "SubdivisionLimit", "TriangleMesh"]

_BYTES_PER_TRIANGLE = 600  # peak of the tessellator per output triangle, about (measured on the mug)
_BYTES_PER_QUAD = 800      # refinement stencils and topology per output quad, about


def _plain(mesh) -> PolyMesh:
    """The mesh's vertices and faces only (a tessellation also carries uv, normals, patch ids)."""
    return PolyMesh(np.asarray(mesh.vertices), np.asarray(mesh.faces))


def _mesh_arrays(mesh) -> dict:
    return {"vertices": mesh.vertices, "face_indices": mesh.face_indices, "face_offsets": mesh.face_offsets}


class TriangleMesh(MeshHolder):
    """The exact patches tessellated (:func:`splinekit.tessellate`) at chordal tolerance
    ``resolution`` x the bounding-box diagonal; holds vertices and triangles."""

    name = "triangle mesh"
    resolution_name = "tolerance / diagonal"
    default_resolutions = (1e-2, 3e-3, 1e-3)
    not_applicable = {}

    def __init__(self, shape, reference, resolution):
        self.resolution = float(resolution)
        tolerance = self.resolution * reference.diagonal
        self.tessellation = tessellate(list(shape.patches), tolerance)
        self._index(_plain(self.tessellation))
        self.arrays = _mesh_arrays(self.mesh)
        # chord height t ~ h^2 kappa / 8: the edge length h, and so the samples per length, go as 1/sqrt(t)
        self.linear = 1.0 / np.sqrt(self.resolution)

    @staticmethod
    def estimate_bytes(shape, reference, resolution):
        return 20.0 / float(resolution) * _BYTES_PER_TRIANGLE


def _refined(surface: SubdivisionSurface, levels: int):
    """``(control mesh refined `levels` times, the SubdivisionSurface of that mesh)`` with the
    creases' remaining sharpness carried along (the same limit surface)."""
    if levels == 0:
        return surface.mesh, surface
    refinement = surface.refinement(levels)
    fine = refinement.mesh(surface.mesh.vertices)
    remaining = refinement.edge_sharpness[-1]
    return fine, SubdivisionSurface(fine, "catmull-clark", creases=remaining if remaining.any() else None)


class SubdivisionCage(MeshHolder):
    """The Catmull-Clark control cage refined ``resolution`` times, vertices as they are: the
    mesh a modeller edits; it converges to the limit surface as it is refined."""

    name = "subdivision cage"
    resolution_name = "levels"
    default_resolutions = (0, 1, 2)
    not_applicable = {}
    _limit = False

    def __init__(self, shape, reference, resolution):
        self.resolution = int(resolution)
        self.surface = shape.subdivision
        self._index(self._mesh_of(self.surface))
        self.arrays = _mesh_arrays(self.mesh)
        self.linear = 2.0**self.resolution

    def _mesh_of(self, surface):
        """The mesh this representation holds for ``surface`` at its level."""
        mesh, fine_surface = _refined(surface, self.resolution)
        return mesh.with_vertices(fine_surface.limit_points()) if self._limit else mesh

    @staticmethod
    def estimate_bytes(shape, reference, resolution):
        return shape.subdivision.mesh.n_faces * 4.0 ** int(resolution) * _BYTES_PER_QUAD

    def bent_distance(self, exact_points, radius):
        """Bend the cage (what a modeller moves), refine, compare with the bent exact surface."""
        cage = self.surface.mesh
        bent = SubdivisionSurface(cage.with_vertices(bend(cage.vertices, radius)), "catmull-clark",
                                  creases=_sharp_edges(self.surface))
        return MeshDistance.of_mesh(self._mesh_of(bent)).query(bend(exact_points, radius))[0]


class SubdivisionLimit(SubdivisionCage):
    """The cage refined ``resolution`` times with every vertex on the exact limit surface
    (limit masks): a quad mesh whose vertices are exact and whose faces are chords. Points
    from parameters are exact limit points (:meth:`SubdivisionSurface.evaluate`)."""

    name = "subdivision limit"
    _limit = True

    def random_parameters(self, n, rng):
        face = rng.integers(0, self.surface.mesh.n_faces, n)
        return face, rng.random((n, 2))

    def point(self, face, uv):
        return self.surface.evaluate(face, uv[:, 0], uv[:, 1])[0]


def _sharp_edges(surface: SubdivisionSurface):
    """The control mesh's edge sharpness, per edge (None when no edge is sharp)."""
    sharpness = surface.refinement(0).edge_sharpness[0]
    return sharpness if np.any(sharpness) else None
