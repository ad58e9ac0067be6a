"""from_mesh's sign pass on a dense grid: the compiled check that lets it skip the component
labelling (splinekit/implicit/_frommesh_kernels.py) against numpy, and from_mesh with the check
against from_mesh without it: the same grid bit for bit on clean meshes (where the labelling is
skipped) and on self-intersecting or inconsistently oriented ones (where it must run)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from _compiled import compiled_or_skip
from test_sdf_grid import star_mesh

from splinekit import _kernels
from splinekit.implicit import frommesh
from splinekit.mesh import PolyMesh, primitives

pytest.importorskip("numba")


@pytest.fixture(scope="module")
def kern():
    return compiled_or_skip(frommesh.SIGN_KERNELS)


@settings(max_examples=60, deadline=None)
@given(shape=st.tuples(st.integers(1, 6), st.integers(1, 6), st.integers(1, 6)), seed=st.integers(0, 2**32 - 1),
       gap=st.sampled_from([0.0, 0.3, 0.7, 2.0]), special=st.sampled_from([None, np.inf, -np.inf, np.nan, -0.0]))
def test_the_check_counts_what_numpy_counts(kern, shape, seed, gap, special):
    rng = np.random.default_rng(seed)
    d = np.round(rng.standard_normal(shape), 1)  # ties with the gap and zeros of both signs
    if special is not None:
        d.flat[rng.integers(d.size)] = special
    out = np.empty_like(d)
    bad = kern.settle_signs(d, gap, out)
    far = np.abs(d) > gap
    neg = d < 0
    want = int((~np.isfinite(d)).sum())
    for ax in range(3):
        a, b = [slice(None)] * 3, [slice(None)] * 3
        a[ax], b[ax] = slice(1, None), slice(None, -1)
        a, b = tuple(a), tuple(b)
        fin = np.isfinite(d[b])  # a pair is counted from its finite first sample
        want += int((fin & far[a] & far[b] & (neg[a] != neg[b])).sum())
    assert bad == want
    expect = np.where(neg, -np.abs(d), np.abs(d))
    assert np.array_equal(out.view(np.uint64), expect.view(np.uint64))


def overlapping_spheres():
    a = primitives.icosphere(2)
    V = np.asarray(a.vertices)
    F = np.asarray(a.faces)
    return PolyMesh(np.concatenate([V, V + [0.9, 0.2, 0.0]]), np.concatenate([F, F + len(V)]))


def shell_inside_a_sphere():
    # a smaller sphere inside, oriented outwards like the outer one: not the boundary of a solid
    a = primitives.icosphere(2)
    V = np.asarray(a.vertices)
    F = np.asarray(a.faces)
    return PolyMesh(np.concatenate([V, 0.5 * V]), np.concatenate([F, F + len(V)]))


@pytest.mark.parametrize("make, skips", [
    (lambda: primitives.icosphere(2), True), (lambda: primitives.torus(nu=16, nv=8, R=1.0, r=0.3), True),
    (star_mesh, True), (overlapping_spheres, False), (shell_inside_a_sphere, False)],
    ids=["icosphere", "torus", "star", "overlapping spheres", "shell inside a sphere"])
def test_from_mesh_with_and_without_the_check(make, skips, monkeypatch):
    mesh = make()
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1")
    monkeypatch.setattr(_kernels, "MIN_WORK", 0)
    calls = []
    component_signs = frommesh._component_signs
    monkeypatch.setattr(frommesh, "_component_signs", lambda *a: calls.append(1) or component_signs(*a))
    fast = frommesh.from_mesh(mesh, 20).values
    assert (not calls) == skips  # labelled only where some far neighbours differ in sign
    load = _kernels.load
    monkeypatch.setattr(_kernels, "load", lambda name, *a, **k: None if name == frommesh.SIGN_KERNELS else load(name, *a, **k))
    full = frommesh.from_mesh(mesh, 20).values
    assert calls
    assert np.array_equal(fast.view(np.uint64), full.view(np.uint64))
