"""Limit normals at boundary vertices against an independent reference: the
normal of the limit-point fan of a finely refined mesh, which converges to the
true normal as the fan shrinks. The exact masks must be what it converges to:
its distance from them shrinks by a constant factor per level."""

import numpy as np
import pytest

import splinekit as sk
from splinekit.mesh import primitives
from splinekit.subdiv.limit import limit_matrix
from splinekit.subdiv.surface import _fan_normals


def _bent_grid(triangles: bool):
    g = primitives.grid(5, 4)
    V = g.vertices.copy()
    V[:, 2] = np.sin(1.3 * V[:, 0]) + 0.3 * V[:, 1] ** 2
    faces = g.faces
    if triangles:
        faces = np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])
    return sk.PolyMesh(V, faces)


def _fan_reference(surface, level):
    r = surface.refinement(level)
    L = limit_matrix(r.topology, r.edge_sharpness[-1], r.vertex_sharpness[-1], surface.scheme)
    f = _fan_normals(r.topology, L @ r.apply(surface.mesh.vertices))[: surface.mesh.n_vertices]
    return f / np.linalg.norm(f, axis=1, keepdims=True)


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
@pytest.mark.parametrize("boundary", ["edge-and-corner", "edge-only"])
def test_boundary_normals_are_the_limit_of_refined_fans(scheme, boundary):
    mesh = _bent_grid(scheme == "loop")
    s = sk.SubdivisionSurface(mesh, scheme, boundary=boundary)
    n = s.limit_normals()
    b = mesh.boundary_vertices
    errors = [np.linalg.norm(n - _fan_reference(s, lv), axis=1)[b].max() for lv in (3, 5)]
    # the fan error at least halves per level (measured: 2x at valence-3 Loop boundaries, 4x elsewhere)
    assert errors[1] < 0.3 * errors[0]
    assert errors[1] < 2e-3


def test_crease_normals_on_a_creased_cube_average_the_two_sides():
    cube = primitives.box()
    creases = {tuple(e): np.inf for e in cube.edges}
    s = sk.SubdivisionSurface(cube, "catmull-clark", creases=creases)
    # all edges sharp: every vertex is a corner of three flat faces; the sum of the
    # three face normals points along the diagonal
    n = s.limit_normals()
    expected = cube.vertices / np.linalg.norm(cube.vertices, axis=1, keepdims=True)
    np.testing.assert_allclose(n, expected, atol=1e-12)
