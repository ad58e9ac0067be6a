"""The Chaikin crease rule (OpenSubdiv's CREASE_CHAIKIN), checked on values
worked out by hand."""

import numpy as np
import pytest

import splinekit as sk
from splinekit.errors import ParameterError
from splinekit.mesh import primitives


def _chain_grid():
    """A 4 x 3 quad grid with a crease chain along x at the first interior
    row: sharpness 1, 2, 3 from the boundary inwards."""
    g = primitives.grid(4, 3)
    bumpy = g.vertices.copy()
    bumpy[:, 2] = np.random.default_rng(3).normal(scale=0.2, size=len(bumpy))
    g = g.with_vertices(bumpy)  # a flat grid would hide every rule difference
    # vertex (i, j) is i * 4 + j: the chain runs through vertices 1, 5, 9, 13
    chain = {(1, 5): 1.0, (5, 9): 2.0, (9, 13): 3.0}
    return g, chain


@pytest.mark.parametrize("scheme", ["catmull-clark", "loop"])
def test_chaikin_child_sharpness_by_hand(scheme):
    g, chain = _chain_grid()
    mesh = g if scheme == "catmull-clark" else sk.PolyMesh(
        g.vertices, np.concatenate([g.faces[:, [0, 1, 2]], g.faces[:, [0, 2, 3]]])
    )
    r = sk.Refinement(mesh, scheme, 1, creases=chain, crease_method="chaikin")
    t0, t1 = r.topologies
    V = t0.n_vertices
    child = r.edge_sharpness[1]

    def half(a, b):
        e = int(t0.find_edges([[a, b]])[0])
        return float(child[int(t1.find_edges([[a, V + e]])[0])])

    # vertex 5 joins s = 1 and s = 2: 3/4 * 1 + 1/4 * 2 - 1 = 0.25 and 3/4 * 2 + 1/4 * 1 - 1 = 0.75
    assert half(5, 1) == pytest.approx(0.25)
    assert half(5, 9) == pytest.approx(0.75)
    # vertex 9 joins 2 and 3: 3/4 * 2 + 1/4 * 3 - 1 = 1.25 and 3/4 * 3 + 1/4 * 2 - 1 = 1.75
    assert half(9, 5) == pytest.approx(1.25)
    assert half(9, 13) == pytest.approx(1.75)
    # the chain ends (vertex 1 on the boundary, whose other edges are infinitely
    # sharp, and vertex 13) have one semi-sharp edge: uniform decrement
    assert half(1, 5) == pytest.approx(0.0)
    assert half(13, 9) == pytest.approx(2.0)
    uniform = sk.Refinement(mesh, scheme, 1, creases=chain).edge_sharpness[1]
    assert float(uniform[int(t1.find_edges([[5, V + int(t0.find_edges([[1, 5]])[0])]])[0])]) == 0.0


def test_chaikin_differs_from_uniform_only_where_creases_meet():
    g, chain = _chain_grid()
    a = sk.subdivide(g, "catmull-clark", 3, creases=chain, crease_method="chaikin")
    b = sk.subdivide(g, "catmull-clark", 3, creases=chain)
    assert a.n_vertices == b.n_vertices
    assert np.abs(a.vertices - b.vertices).max() > 1e-6
    single = {(5, 9): 2.0}
    np.testing.assert_array_equal(
        sk.subdivide(g, "catmull-clark", 3, creases=single, crease_method="chaikin").vertices,
        sk.subdivide(g, "catmull-clark", 3, creases=single).vertices,
    )


def test_chaikin_is_refused_for_doo_sabin_and_bad_names():
    g, chain = _chain_grid()
    with pytest.raises(ParameterError, match="chaikin"):
        sk.Refinement(g, "doo-sabin", 1, creases=chain, crease_method="chaikin")
    with pytest.raises(ParameterError, match="crease_method"):
        sk.subdivide(g, "catmull-clark", 1, crease_method="smooth")
