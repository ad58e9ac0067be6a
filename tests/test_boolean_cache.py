"""The manifold3d object of a mesh is built once (PolyMesh.derived) and reused by later booleans.

Checked against manifold3d called directly on fresh objects (independent of the cache), by
counting the conversions, and on the cases a cache could get wrong: a mesh wound inside out, a
mesh that fails its checks, a result fed back as an operand, a copied or pickled mesh.
"""

from __future__ import annotations

import copy
import pickle

import manifold3d as m3
import numpy as np
import pytest

from splinekit.errors import NotManifoldError
from splinekit.interop import booleans
from splinekit.mesh import PolyMesh
from splinekit.mesh.primitives import icosphere


@pytest.fixture
def builds(monkeypatch):
    """Counts the operand conversions (booleans._build calls)."""
    calls = []
    real = booleans._build

    def counting(V, T, name):
        calls.append(name)
        return real(V, T, name)

    monkeypatch.setattr(booleans, "_build", counting)
    return calls


def pair():
    a = icosphere(2)
    b = PolyMesh(a.vertices * 0.8 + [0.5, 0.1, 0.0], np.array(a.faces))
    return a, b


def manifold_of(mesh):
    """A manifold3d object built here from the mesh's arrays (no splinekit cache involved)."""
    return m3.Manifold(m3.Mesh64(vert_properties=np.array(mesh.vertices), tri_verts=np.array(mesh.faces, dtype=np.uint64)))


def direct(a, b, op):
    ma, mb = manifold_of(a), manifold_of(b)
    return {"union": ma + mb, "difference": ma - mb, "intersection": ma ^ mb}[op]


@pytest.mark.parametrize("op", ["union", "difference", "intersection"])
def test_repeated_booleans_convert_each_mesh_once_and_match_manifold3d(builds, op):
    a, b = pair()
    fn = getattr(booleans, op)
    results = [fn(a, b) for _ in range(3)]
    assert len(builds) == 2  # a and b, once each
    ref = direct(a, b, op)
    for r in results:
        assert r.n_faces == ref.num_tri() and r.n_vertices == ref.num_vert()
        assert r.volume == pytest.approx(ref.volume(), rel=1e-12)
        assert r == results[0]


def test_a_result_used_as_an_operand_is_not_converted_back(builds):
    a, b = pair()
    u = booleans.union(a, b)
    chained = booleans.difference(u, b)
    assert len(builds) == 2  # u brought its own Manifold
    ref = direct(a, b, "union") - manifold_of(b)
    assert chained.volume == pytest.approx(ref.volume(), rel=1e-12)
    # the same chain on a fresh, uncached copy of the union
    fresh = PolyMesh(np.array(u.vertices), np.array(u.faces))
    assert booleans.difference(fresh, b).volume == pytest.approx(chained.volume, rel=1e-12)


def test_inside_out_mesh_is_cached_reoriented(builds):
    a, b = pair()
    flipped = PolyMesh(b.vertices, np.array(b.faces)[:, ::-1])
    first = booleans.union(a, flipped)
    second = booleans.union(a, flipped)
    assert first == second and first.volume > 0
    assert first.volume == pytest.approx(booleans.union(a, b).volume, rel=1e-12)


def test_a_failing_mesh_caches_nothing_and_fails_again():
    a = icosphere(1)
    open_mesh = PolyMesh(a.vertices, np.array(a.faces)[1:])
    for _ in range(2):
        with pytest.raises(NotManifoldError, match="not closed"):
            booleans.union(a, open_mesh)
    assert "_derived" not in open_mesh.__dict__ or not open_mesh.__dict__["_derived"]


def test_copies_do_not_carry_the_cache(builds):
    a, b = pair()
    booleans.union(a, b)
    for clone in (copy.deepcopy(a), pickle.loads(pickle.dumps(a))):
        assert clone == a and "_derived" not in clone.__dict__
    booleans.union(pickle.loads(pickle.dumps(a)), b)
    assert len(builds) == 3


def test_what_the_cache_relies_on_meshes_and_results_are_read_only():
    a, b = pair()
    u = booleans.union(a, b)
    for mesh in (a, u):
        for arr in (mesh.vertices, mesh.face_indices, mesh.face_offsets):
            assert not arr.flags.writeable
            with pytest.raises(ValueError):
                arr[0] = arr[0]
        with pytest.raises(AttributeError):
            mesh.topology = None
