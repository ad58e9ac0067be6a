"""splinekit.brep.links: close point pairs (checked against all pairs by brute force) and
connected components (checked against scipy's), and the tessellator's edge pairing, which now
uses them through splinekit.brep.topology.pair_by_samples (checked against the edges' keys)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

import splinekit as sk
from splinekit.brep import Shell, Solid, TrimmedFace, box_with_hole, plate_with_holes
from splinekit.brep import links
from splinekit.brep.links import close_pairs, first_use_labels, kd_pairs, link_components
from splinekit.brep.topology import pair_by_samples
from splinekit.errors import ParameterError
from splinekit.tessellation.batch import CurveBatch, SurfaceBatch
from splinekit.tessellation.edges import edge_uses, group_uses


def _brute_pairs(X, r, slack=0.0):
    d = np.linalg.norm(X[:, None] - X[None], axis=-1)
    i, j = np.nonzero(np.triu(d <= r + slack, k=1))
    return {(int(a), int(b)) for a, b in zip(i, j)}


def _as_set(pairs):
    return {(int(min(a, b)), int(max(a, b))) for a, b in pairs}


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000), st.integers(0, 300), st.floats(1e-3, 0.3))
def test_close_pairs_are_all_pairs_within_r(seed, n, r):
    rng = np.random.default_rng(seed)
    X = rng.random((n, 3))
    X[: n // 3] = np.round(X[: n // 3], 1)  # many coincident and grid-aligned points
    # grid-aligned points can lie exactly r apart, where |d| <= r and d.d <= r^2 may round apart:
    # every pair clearly within r must be found, and none clearly beyond it
    found = _as_set(close_pairs(X, r))
    rounding = 1e-12
    assert _brute_pairs(X, r, -rounding) <= found <= _brute_pairs(X, r, rounding)


def test_close_pairs_falls_back_to_the_tree_and_agrees(monkeypatch):
    # every point on one plane across the sweep: the sort would compare all pairs
    Q = np.linalg.qr(np.column_stack([links.SWEEP, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]))[0]
    X = np.random.default_rng(3).random((400, 2)) @ Q[:, 1:].T
    calls = []
    monkeypatch.setattr(links, "kd_pairs", lambda X, r: calls.append(len(X)) or kd_pairs(X, r))
    assert _as_set(close_pairs(X, 0.1)) == _brute_pairs(X, 0.1)
    assert calls == [400]


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000), st.integers(1, 200), st.integers(0, 300))
def test_link_components_match_scipy(seed, n, k):
    rng = np.random.default_rng(seed)
    a, b = rng.integers(0, n, k), rng.integers(0, n, k)
    lab = link_components(n, a, b)
    count, ref = connected_components(coo_matrix((np.ones(k), (a, b)), shape=(n, n)), directed=False)
    # the same partition, each labelled by its smallest node, numbered densely in that order
    assert np.array_equal(lab, np.array([np.flatnonzero(ref == ref[i])[0] for i in range(n)]))
    dense = first_use_labels(lab)
    assert dense.max() + 1 == count and np.array_equal(dense, ref)  # scipy numbers components by first node too


def _keyless(faces):
    return [TrimmedFace(f.surface, [[e.with_key(None) for e in lp] for lp in f.boundary_loops()], f.reversed,
                        tolerance=f.tolerance) for f in faces]


def _groups(faces):
    uses = edge_uses(faces)
    return uses, group_uses(uses, 1e-6, CurveBatch([u.edge.pcurve for u in uses]), SurfaceBatch([f.surface for f in faces]))


def test_tessellator_pairs_keyless_uses_into_the_keyed_edges():
    for solid in (box_with_hole(20.0, 4.0), plate_with_holes(40.0, 30.0, 5.0, [(10, 10, 4), (28, 20, 5)])):
        faces = list(solid.faces)
        uses, keyed = _groups(faces)
        assert all(len(g) == 2 for g in keyed if not uses[g[0]].edge.degenerate)
        _, loose = _groups(_keyless(faces))
        assert sorted(map(sorted, loose)) == sorted(map(sorted, keyed))
        mesh = sk.tessellate(Solid(Shell(_keyless(faces))), 1e-2)
        assert mesh.is_closed and abs(mesh.volume - solid.volume()) < 1e-2 * solid.volume()


@pytest.mark.parametrize("points, tol, match", [
    (np.full((4, 3, 3), np.nan), 1e-6, "finite"),
    (np.zeros((4, 3, 3)), -1.0, "tol"),
    (np.zeros((4, 3, 3)), np.inf, "tol"),
    (np.zeros((4, 3, 3)), np.ones(3), "tol"),
    (np.zeros((4,)), 1e-6, r"\(n, k, 3\)"),
    (np.zeros((4, 2, 3)), 1e-6, "k odd"),
])
def test_pair_by_samples_refuses_bad_input(points, tol, match):
    with pytest.raises(ParameterError, match=match):
        pair_by_samples(points, tol)
