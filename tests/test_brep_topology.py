"""Topology of B-reps: edge pairing (by key and geometrically), vertices, free edges, Euler
characteristic, genus and closedness.

Independent references: OpenCascade's own topology of the same primitives built with build123d
(vertex / non-degenerate edge / face counts from ``TopExp``, in tests/occ/), the Euler-Poincaré formula with the
genus known from the shape (a box or sphere has none, a torus or a box with a through hole one),
and hand-counted open shells.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from splinekit.brep import (Shell, Solid, TrimmedFace, box, box_with_hole, cone, cylinder, plate_with_holes,
                            sphere, torus)
from splinekit.brep.topology import pair_by_samples
from splinekit.construct import arc, line
from splinekit.surfaces import BSplineSurface

sizes = st.floats(0.5, 50.0)


def _counts(solid):
    return len(solid.vertices), solid.topology.n_edges, len(solid.faces)


@settings(max_examples=15, deadline=None)
@given(sizes, sizes, sizes)
def test_genus_zero_primitives(a, b, c):
    for s in (box(a, b, c), cylinder(a, b), cone(a, c, b), cone(a, 0.0, b), sphere(a)):
        assert s.is_closed and s.euler_characteristic == 2 and s.genus == 0, s.name
        assert s.free_edges == ()


@settings(max_examples=15, deadline=None)
@given(sizes, st.floats(0.05, 0.95), st.floats(0.05, 0.45))
def test_genus_one_primitives(R, ratio, hole):
    for s in (torus(R, ratio * R), box_with_hole(R, hole * R)):
        assert s.is_closed and s.euler_characteristic == 0 and s.genus == 1, s.name


def test_plate_with_three_holes_has_genus_three():
    p = plate_with_holes(30, 20, 5, [(5, 5, 2), (20, 10, 4), (10, 14, 2)])
    assert p.is_closed and p.genus == 3 and p.euler_characteristic == -4
    # V: 8 corners + one seam vertex at each end of each hole; E: 12 + 3 per hole; F: 6 + 1 per hole
    assert _counts(p) == (8 + 6, 12 + 9, 6 + 3)


def _keyless(solid):
    faces = [TrimmedFace(f.surface, [[e.with_key(None) for e in lp] for lp in f.loops], f.reversed, name=f.name)
             for f in solid.faces]
    return Shell(faces)


@pytest.mark.parametrize("make", [lambda: box(1, 2, 3), lambda: cylinder(2, 5), lambda: sphere(1),
                                  lambda: torus(3, 1), lambda: box_with_hole(20, 4)])
def test_geometric_pairing_finds_the_keyed_edges(make):
    solid = make()
    keyed, geometric = solid.outer_shell, _keyless(solid)
    assert sorted(g.uses for g in keyed.edges) == sorted(g.uses for g in geometric.edges)
    assert geometric.is_closed and geometric.euler_characteristic == keyed.euler_characteristic


def test_geometric_pairing_tells_edges_with_the_same_ends_apart():
    """A disk bounded by two half circles, glued to its mirror image: four uses of two edges with
    the same end points; only the mid points tell the edges apart."""
    plane = BSplineSurface(1, 1, [-1, -1, 1, 1], [-1, -1, 1, 1],
                           np.array([[[-1, -1, 0], [-1, 1, 0]], [[1, -1, 0], [1, 1, 0]]], float))
    upper = arc((0.0, 0.0), None, 1.0, 0.0, np.pi)
    lower = arc((0.0, 0.0), None, 1.0, np.pi, 2 * np.pi)
    disk = TrimmedFace(plane, [[upper, lower]])
    shell = Shell([disk, disk.flipped()])
    assert len(shell.edges) == 2 and all(len(g.uses) == 2 for g in shell.edges)
    assert shell.is_closed and shell.euler_characteristic == 2  # a flat pillow: a sphere
    assert len(shell.vertices) == 2


def test_open_shells_and_faces():
    b = box(1, 1, 1)
    open_box = Shell(b.faces[:5])
    assert not open_box.is_closed and len(open_box.free_edges) == 4
    assert open_box.topology.n_boundaries == 1 and open_box.genus == 0 and open_box.euler_characteristic == 1
    top = box_with_hole(20, 4).faces[1]  # an annulus-like face: two boundary curves
    assert not top.is_closed and top.euler_characteristic == 0 and top.topology.n_boundaries == 2 and top.genus == 0
    assert len(top.vertices) == 5
    s = sphere(2).faces[0]  # one face closed on itself through its seam and poles
    assert s.is_closed and s.euler_characteristic == 2
    # a face with the same orientation twice is not a closed shell
    assert not Shell([b.faces[0], b.faces[0]]).is_closed


def test_natural_domain_sphere_face_pairs_its_seam_geometrically():
    s = TrimmedFace(sphere(2).faces[0].surface)
    assert s.is_closed and len(s.vertices) == 2 and s.topology.n_edges == 1 and s.genus == 0


def test_topology_is_cached_and_pairing_scales():
    holes = [(2 + 3 * i, 2 + 3 * j, 1) for i in range(10) for j in range(10)]
    p = plate_with_holes(31, 31, 2, holes)
    t = time.perf_counter()
    assert p.genus == 100 and p.is_closed
    first = time.perf_counter() - t
    t = time.perf_counter()
    assert p.genus == 100
    assert time.perf_counter() - t < max(first / 10, 1e-3)
    assert first < 10.0


# -- pairing keyless uses by their samples (splinekit.brep.topology.pair_by_samples) ------------------
def _partition(labels) -> set:
    """The groups of a labelling as a set of frozensets of indices (label numbers do not matter)."""
    groups: dict = {}
    for i, label in enumerate(np.asarray(labels).tolist()):
        groups.setdefault(label, set()).add(i)
    return {frozenset(g) for g in groups.values()}


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 30))
def test_pair_by_samples_finds_the_edges_it_was_built_from(seed, n_edges):
    """Edges are random polylines far apart; each is used once or twice (the second use reversed
    or not, moved by less than the tolerance): the groups are exactly the edges, whatever the
    order of the uses. The truth is the construction, not the function."""
    rng = np.random.default_rng(seed)
    tol = 1e-3
    starts = np.arange(n_edges)[:, None] * np.array([10.0, 0.0, 0.0])  # edges 10 apart
    uses, truth = [], []
    for e in range(n_edges):
        pts = starts[e] + np.cumsum(rng.uniform(-1.0, 1.0, (5, 3)), axis=0)
        uses.append(pts)
        truth.append(e)
        if rng.random() < 0.7:  # a second use of the same edge
            other = pts + rng.uniform(-0.4, 0.4, (5, 3)) * tol
            uses.append(other[::-1] if rng.random() < 0.5 else other)
            truth.append(e)
    order = rng.permutation(len(uses))
    labels = pair_by_samples(np.array(uses)[order], tol)
    assert _partition(labels) == _partition(np.array(truth)[order])
    # numbered 0, 1, 2, ... in order of each group's first use
    assert np.array_equal(labels[np.sort(np.unique(labels, return_index=True)[1])], np.arange(labels.max() + 1))


def test_pair_by_samples_needs_every_sample_within_the_larger_tolerance():
    a = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0]])
    same_ends = a.copy()
    same_ends[1, 1] = 0.5  # same ends and mid point, another quarter point: a different edge
    assert _partition(pair_by_samples(np.stack([a, same_ends]), 0.1)) == {frozenset({0}), frozenset({1})}
    near = a + [0.0, 0.15, 0.0]  # 0.15 apart everywhere: one edge only with a tolerance of 0.15 on one side
    assert _partition(pair_by_samples(np.stack([a, near]), [0.1, 0.1])) == {frozenset({0}), frozenset({1})}
    assert _partition(pair_by_samples(np.stack([a, near]), [0.1, 0.15])) == {frozenset({0, 1})}
    assert pair_by_samples(np.zeros((0, 5, 3)), 0.1).shape == (0,)


def test_brep_objects_survive_pickling():
    """Solids travel to worker processes (Dask, multiprocessing): a pickled solid comes back with
    the same topology, orientation, names and closed-form volume."""
    import pickle

    solid = plate_with_holes(40.0, 30.0, 5.0, [(10.0, 10.0, 3.0), (28.0, 18.0, 4.0)])
    back = pickle.loads(pickle.dumps(solid))
    assert type(back) is Solid and back is not solid
    assert (len(back.faces), len(back.edges), len(back.vertices)) == (len(solid.faces), len(solid.edges), len(solid.vertices))
    assert [f.reversed for f in back.faces] == [f.reversed for f in solid.faces]
    assert [f.name for f in back.faces] == [f.name for f in solid.faces]
    assert [e.key for f in back.faces for lp in f.loops for e in lp] == [e.key for f in solid.faces for lp in f.loops for e in lp]
    exact = (40.0 * 30.0 - np.pi * (3.0 ** 2 + 4.0 ** 2)) * 5.0
    assert back.volume() == pytest.approx(exact, rel=1e-10)
    assert back.genus == 2
