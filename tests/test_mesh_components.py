"""splinekit.mesh.components: joining meshes, their connected pieces and the genus of closed
meshes, against the closed-form topology of the primitives (a sphere and a box have genus 0,
a torus genus 1) and against splinekit.brep's own topology of an exact torus."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from splinekit import PolyMesh, brep, tessellate
from splinekit.errors import ParameterError
from splinekit.mesh import primitives
from splinekit.mesh.components import concatenate, face_components, genus

SHAPES = {
    "sphere": (lambda: primitives.icosphere(1), 0),
    "box": (lambda: primitives.box(2.0), 0),  # quads
    "torus": (lambda: primitives.torus(12, 6), 1),
}


def test_concatenate_keeps_every_face_with_its_vertices():
    parts = [primitives.torus(8, 4), primitives.icosphere(0), primitives.box(1.0, center=(5, 0, 0))]
    joined = concatenate(parts)
    assert joined.n_vertices == sum(p.n_vertices for p in parts)
    assert joined.n_faces == sum(p.n_faces for p in parts)
    np.testing.assert_array_equal(joined.vertices, np.concatenate([p.vertices for p in parts]))
    start = 0
    face = 0
    for p in parts:  # each face is the part's face, its indices shifted by the vertices before it
        for f in range(p.n_faces):
            np.testing.assert_array_equal(joined.faces[face + f], np.asarray(p.faces[f]) + start)
        start += p.n_vertices
        face += p.n_faces
    assert joined.is_closed
    assert joined.area == pytest.approx(sum(p.area for p in parts), rel=1e-14)
    assert joined.volume == pytest.approx(sum(p.volume for p in parts), rel=1e-13)
    assert joined.euler_characteristic == sum(p.euler_characteristic for p in parts)


def test_concatenate_of_one_mesh_is_that_mesh_and_bad_input_is_refused():
    m = primitives.icosphere(0)
    assert concatenate([m]) is m
    with pytest.raises(ParameterError, match="at least one"):
        concatenate([])
    with pytest.raises(ParameterError, match=r"meshes\[1\]"):
        concatenate([m, "not a mesh"])
    flat = PolyMesh(np.zeros((3, 2)), [[0, 1, 2]])
    with pytest.raises(ParameterError, match="dimensions"):
        concatenate([m, flat])


@pytest.mark.parametrize("name", list(SHAPES))
def test_genus_of_the_primitives(name):
    make, expected = SHAPES[name]
    mesh = make()
    assert face_components(mesh)[0] == 1
    assert genus(mesh) == expected


def test_genus_of_an_open_mesh_is_none_and_its_pieces_are_counted():
    sheet = primitives.grid(3, 3)
    assert genus(sheet) is None
    count, labels = face_components(concatenate([sheet, primitives.grid(2, 2)]))
    assert count == 2 and labels.shape == (9 + 4,)
    assert set(labels[:9]) == {labels[0]} and set(labels[9:]) == {labels[9]} and labels[0] != labels[9]


def test_isolated_vertices_do_not_change_the_genus():
    sphere = primitives.icosphere(1)
    extra = PolyMesh(np.vstack([sphere.vertices, [[9.0, 9.0, 9.0]]]), sphere.faces)
    assert face_components(extra)[0] == 1 and genus(extra) == 0


def test_genus_of_a_tessellated_exact_torus_matches_the_brep_topology():
    solid = brep.torus(3.0, 1.0)
    mesh = tessellate(solid, 0.05)
    assert mesh.is_closed
    assert genus(mesh) == solid.genus == 1


@settings(max_examples=25, deadline=None)
@given(st.lists(st.sampled_from(list(SHAPES)), min_size=1, max_size=6))
def test_genus_and_pieces_add_up_over_joined_meshes(names):
    """A union of disjoint closed surfaces: pieces and handles are the sums of its parts'."""
    mesh = concatenate([SHAPES[n][0]() for n in names])
    assert face_components(mesh)[0] == len(names)
    assert genus(mesh) == sum(SHAPES[n][1] for n in names)


@pytest.mark.parametrize("function", [face_components, genus])
def test_components_refuse_what_is_not_a_mesh(function):
    with pytest.raises(ParameterError, match="needs a PolyMesh"):
        function("not a mesh")
