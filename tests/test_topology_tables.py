"""Topology's edge table and face checks against a plain per-half-edge reference (a dict).

The edge table is built with one stable sort (edges, each half-edge's edge and each edge's two
half-edges together) and faces of up to six sides are checked for repeated vertices without a
sort; these tests compare both with loops that follow the definitions, on meshes whose faces and
vertex labels are shuffled (so the sort sees no runs) and on open and mixed-polygon meshes.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from splinekit.errors import MeshTopologyError
from splinekit.mesh import PolyMesh, Topology
from splinekit.mesh.primitives import box, icosphere, torus


def reference_tables(n_vertices, idx, offsets):
    """Edges (sorted by (low, high)), the edge of each half-edge and each edge's half-edges in
    half-edge order, by a dict over half-edges."""
    halfedges_of = {}
    for f in range(len(offsets) - 1):
        face = idx[offsets[f]:offsets[f + 1]]
        for c in range(len(face)):
            a, b = int(face[c]), int(face[(c + 1) % len(face)])
            halfedges_of.setdefault((min(a, b), max(a, b)), []).append(int(offsets[f]) + c)
    edges = sorted(halfedges_of)
    halfedge_edge = np.empty(len(idx), dtype=np.int64)
    pairs = []
    for e, key in enumerate(edges):
        hs = halfedges_of[key]
        halfedge_edge[hs] = e
        pairs.append((hs[0], hs[1] if len(hs) > 1 else -1))
    return np.array(edges, dtype=np.int64).reshape(-1, 2), halfedge_edge, np.array(pairs, dtype=np.int64).reshape(-1, 2)


def shuffled(mesh, seed, drop=0):
    """The faces of ``mesh`` in a random order under a random relabelling of the vertices, with
    ``drop`` faces removed (an open mesh), as (n_vertices, flat indices, offsets)."""
    rng = np.random.default_rng(seed)
    n = mesh.n_vertices
    label = rng.permutation(n)
    sizes = np.diff(mesh.face_offsets)
    order = rng.permutation(mesh.n_faces)[: mesh.n_faces - drop]
    parts = [label[mesh.face_indices[mesh.face_offsets[f]:mesh.face_offsets[f + 1]]] for f in order]
    offsets = np.concatenate([[0], np.cumsum(sizes[order])]).astype(np.int64)
    return n, np.concatenate(parts).astype(np.int64), offsets


def mixed():
    """A cube with one quad split into two triangles (faces of 3 and 4 sides)."""
    cube = box()
    faces = [list(f) for f in cube.faces[1:]] + [[cube.faces[0][0], cube.faces[0][1], cube.faces[0][2]],
                                                 [cube.faces[0][0], cube.faces[0][2], cube.faces[0][3]]]
    return PolyMesh(cube.vertices, faces)


MESHES = {"icosphere": icosphere(2), "torus": torus(9, 7), "box": box(), "mixed": mixed()}


@settings(max_examples=25, deadline=None)
@given(name=st.sampled_from(sorted(MESHES)), seed=st.integers(0, 2**32 - 1), drop=st.integers(0, 5))
def test_edge_table_matches_the_reference(name, seed, drop):
    n, idx, offsets = shuffled(MESHES[name], seed, drop)
    t = Topology(n, idx, offsets, check=True)
    edges, halfedge_edge, pairs = reference_tables(n, idx, offsets)
    np.testing.assert_array_equal(t.edges, edges)
    np.testing.assert_array_equal(t.halfedge_edge, halfedge_edge)
    np.testing.assert_array_equal(t.edge_halfedges, pairs)
    assert t.is_closed == (drop == 0)


def test_empty_and_single_face_tables():
    t = Topology(3, np.zeros(0, dtype=np.int64), np.zeros(1, dtype=np.int64))
    assert t.edges.shape == (0, 2) and t.edge_halfedges.shape == (0, 2)
    t = Topology(4, [3, 1, 2], [0, 3])
    np.testing.assert_array_equal(t.edges, [[1, 2], [1, 3], [2, 3]])
    np.testing.assert_array_equal(t.edge_halfedges, [[1, -1], [0, -1], [2, -1]])


@pytest.mark.parametrize("k", [3, 4, 5, 6, 7])
def test_a_repeated_vertex_is_found_in_every_corner_pair(k):
    """Uniform faces of up to six sides take the pairwise comparison, seven the sort: both name
    the first face that repeats a vertex, for every pair of corners."""
    base = np.arange(4 * k, dtype=np.int64).reshape(4, k)
    for i in range(k):
        for j in range(i + 1, k):
            faces = base.copy()
            faces[2, j] = faces[2, i]
            with pytest.raises(MeshTopologyError, match=f"face 2 uses vertex {faces[2, i]} more than once"):
                Topology(4 * k, faces.ravel(), np.arange(5) * k)
