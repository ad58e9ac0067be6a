"""Level sets: constant-speed growth, mean-curvature flow against r(t) = sqrt(r0^2 - 4t),
topology change, reinitialization, speeds of every kind, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from splinekit.errors import ParameterError, SplineKitError
from splinekit.implicit.sampled import SampledSDF
from splinekit.levelset import LevelSet
from splinekit.mesh import PolyMesh

BOX = ((-1.0,) * 3, (1.0,) * 3)


def ball(r, c=(0.0, 0.0, 0.0)):
    c = np.asarray(c, dtype=float)
    return lambda p: np.linalg.norm(p - c, axis=1) - r


def mesh_radius(ls):
    """Radius of the ball with the volume of the front's mesh (checked closed)."""
    m = ls.to_mesh()
    checked = PolyMesh(m.vertices, m.faces)
    assert checked.is_closed
    return (3 * checked.volume / (4 * np.pi)) ** (1 / 3)


def axis_radius(ls):
    """Mean distance from the centre of the zero crossings along the six half-axes
    through the grid's centre sample (linear interpolation of phi)."""
    phi = ls.phi
    c = np.array(phi.shape) // 2
    out = []
    for ax in range(3):
        for sgn in (1, -1):
            idx = [int(c[0]), int(c[1]), int(c[2])]
            line = []
            k = c[ax]
            while 0 <= k < phi.shape[ax]:
                idx[ax] = k
                line.append(phi[tuple(idx)])
                k += sgn
            line = np.array(line)
            j = int(np.argmax(line >= 0))
            t = line[j - 1] / (line[j - 1] - line[j])
            out.append((j - 1 + t) * ls.spacing)
    return float(np.mean(out))


def n_components(mesh):
    E = np.asarray(mesh.edges)
    n = mesh.n_vertices
    return connected_components(coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(n, n)), directed=False)[0]


# -- motion ---------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scheme, bound", [("godunov", 0.5), ("weno5", 0.15)])
def test_sphere_grows_at_constant_speed(scheme, bound):
    ls = LevelSet.from_implicit(ball(0.4), BOX, 41)  # h = 0.05
    h = ls.spacing
    out = ls.advance(0.3, 1.0, scheme=scheme)
    assert out.time == pytest.approx(0.3)
    # radius from phi along the axes (grid-aligned, so exact at t = 0) and from the mesh volume
    assert abs(axis_radius(out) - 0.7) < bound * h
    assert abs(mesh_radius(out) - mesh_radius(ls) - 0.3) < bound * h


def test_sphere_shrinks_under_negative_speed():
    ls = LevelSet.from_implicit(ball(0.7), BOX, 41)
    out = ls.advance(0.3, -1.0)
    assert abs(axis_radius(out) - 0.4) < 0.5 * ls.spacing


def test_first_order_error_halves_with_the_voxel():
    # (along the axes the scheme is exact for a sphere: measure by volume)
    errs = []
    for n in (21, 41):
        ls = LevelSet.from_implicit(ball(0.4), BOX, n)
        errs.append(abs(mesh_radius(ls.advance(0.3, 1.0)) - mesh_radius(ls) - 0.3))
    assert errs[1] < 0.65 * errs[0]


def test_mean_curvature_flow_follows_the_closed_form():
    # r(t) = sqrt(r0^2 - 4 t) for a sphere in 3-D (kappa = 2 / r)
    r0, t = 0.6, 0.05
    ls = LevelSet.from_implicit(ball(r0), BOX, 31)
    h = ls.spacing
    out = ls.advance(t, 0.0, curvature=1.0)
    exact = np.sqrt(r0**2 - 4 * t)
    assert abs(axis_radius(out) - exact) < 0.2 * h
    assert abs(mesh_radius(out) - mesh_radius(ls) - (exact - r0)) < 0.2 * h
    # and the motion is real: far more than the error bound
    assert r0 - axis_radius(out) > 2.5 * h


def test_two_spheres_merge_into_one_component():
    u = lambda p: np.minimum(ball(0.3, (-0.4, 0, 0))(p), ball(0.3, (0.4, 0, 0))(p))
    ls = LevelSet.from_implicit(u, ((-1, -0.6, -0.6), (1, 0.6, 0.6)), 41)
    m0 = ls.to_mesh()
    assert n_components(m0) == 2 and m0.euler_characteristic == 4
    m1 = ls.advance(0.15, 1.0).to_mesh()
    assert n_components(m1) == 1 and PolyMesh(m1.vertices, m1.faces).euler_characteristic == 2


def test_speed_as_array_and_function_match_the_constant():
    ls = LevelSet.from_implicit(ball(0.4), BOX, 21)
    ref = ls.advance(0.2, 0.8)
    arr = ls.advance(0.2, np.full(ls.shape, 0.8))
    fun = ls.advance(0.2, lambda p, t: np.full(len(p), 0.8))
    assert np.array_equal(ref.phi, arr.phi) and np.array_equal(ref.phi, fun.phi)


def test_external_field_moves_only_where_it_is_nonzero():
    # speed 1 on the +x side, 0 on the -x side: the front moves right only
    ls = LevelSet.from_implicit(ball(0.4), BOX, 41)
    out = ls.advance(0.2, lambda p, t: (p[:, 0] > 0).astype(float))
    P = ls.points().reshape(-1, 3)
    right, left = P[:, 0] > 0.15, P[:, 0] < -0.15
    delta = (ls.phi - out.phi).ravel()
    near = np.abs(ls.phi.ravel()) < 0.1
    assert np.allclose(delta[left & near], 0.0, atol=1e-15)
    assert np.abs(delta[right & near] - 0.2).max() < 0.05


def test_zero_duration_and_no_speed_keep_phi():
    ls = LevelSet.from_implicit(ball(0.4), BOX, 11, time=2.0)
    assert np.array_equal(ls.advance(0.0, 1.0).phi, ls.phi)
    # even where the time step underflows to 0 (0 / 0 steps): nothing to do
    assert np.array_equal(ls.advance(0.0, 0.0, curvature=1e308).phi, ls.phi)
    out = ls.advance(1.0, 0.0)
    assert np.array_equal(out.phi, ls.phi) and out.time == 3.0


# -- reinitialization ------------------------------------------------------------------------------------------------
def test_reinitialize_restores_unit_gradient_near_the_front():
    f = lambda p: (np.linalg.norm(p, axis=1) - 0.5) * (1 + (p**2).sum(1)) * 3
    ls = LevelSet.from_implicit(f, BOX, 41)
    h = ls.spacing
    g0 = np.linalg.norm(np.stack(np.gradient(ls.phi, h)), axis=0)
    r = ls.reinitialize()
    P = r.points().reshape(-1, 3)
    true = np.linalg.norm(P, axis=1) - 0.5
    band = (np.abs(true) < 0.3) & (np.abs(true) > 2 * h)
    g = np.linalg.norm(np.stack(np.gradient(r.phi, h)), axis=0).ravel()
    assert np.abs(g0.ravel()[band] - 1).min() > 1.5  # far from a distance before
    assert np.abs(g[band] - 1).max() < 0.15
    assert np.abs(r.phi.ravel() - true)[np.abs(true) < 0.3].max() < 0.5 * h  # the front stays put
    assert np.array_equal(np.sign(r.phi), np.sign(ls.phi))


def test_reinitialize_is_exact_for_a_plane():
    n = np.array([0.0, 0.0, 1.0])
    ls = LevelSet.from_implicit(lambda p: 5.0 * (p @ n - 0.13), BOX, 15)
    r = ls.reinitialize()
    P = r.points().reshape(-1, 3)
    assert np.allclose(r.phi.ravel(), P @ n - 0.13, atol=1e-12)


def test_to_sdf_and_repr():
    ls = LevelSet.from_implicit(ball(0.5), BOX, 11)
    s = ls.to_sdf("cubic")
    assert isinstance(s, SampledSDF) and s.interpolation == "cubic"
    assert np.allclose(s(ls.points().reshape(-1, 3)), ls.phi.ravel(), atol=1e-14)
    assert "LevelSet" in repr(ls)
    with pytest.raises(ValueError):
        ls.phi[0, 0, 0] = 1.0


# -- bad input --------------------------------------------------------------------------------------------------
def test_bad_input():
    ls = LevelSet.from_implicit(ball(0.5), BOX, 11)
    cases = [
        lambda: LevelSet(np.zeros((2, 5, 5)), (0, 0, 0), 1.0),
        lambda: LevelSet(np.zeros((5, 5)), (0, 0, 0), 1.0),
        lambda: LevelSet(np.full((4, 4, 4), np.nan), (0, 0, 0), 1.0),
        lambda: LevelSet(np.zeros((4, 4, 4)), (0, 0, 0), (1.0, 2.0, 1.0)),
        lambda: LevelSet(np.zeros((4, 4, 4)), (0, 0, 0), -1.0),
        lambda: LevelSet(np.zeros((4, 4, 4)), (0, 0), 1.0),
        lambda: LevelSet.from_implicit(ball(0.5), BOX, 0),
        lambda: LevelSet.from_implicit(ball(0.5), BOX, 10**6),
        lambda: ls.advance(-1.0, 1.0),
        lambda: ls.advance(np.nan, 1.0),
        lambda: ls.advance(1.0, 1.0, scheme="eno9"),
        lambda: ls.advance(1.0, 1.0, cfl=0.0),
        lambda: ls.advance(1.0, 1.0, cfl=1.5),
        lambda: ls.advance(1.0, curvature=-1.0),
        lambda: ls.advance(1.0, np.ones((3, 3, 3))),
        lambda: ls.advance(1.0, np.inf),
        lambda: ls.advance(1.0, lambda p, t: np.ones(3)),
        lambda: ls.advance(1.0, lambda p, t: 1 / 0),
        lambda: ls.advance(1e9, 1.0),  # too many steps: refused, not run
        lambda: ls.advance(1.0, lambda p, t: np.full(len(p), 1.0 + 10 * t)),  # speed outgrows the step
        lambda: LevelSet(np.ones((4, 4, 4)), (0, 0, 0), 1.0).reinitialize(),
        lambda: ls.reinitialize(max_passes=0),
        # a huge speed or curvature: dt underflows and the step count is infinite, refused
        lambda: ls.advance(1.0, 1e308),
        lambda: ls.advance(1.0, 0.0, curvature=1e308),
        lambda: LevelSet(np.zeros((4, 4, 4)), (0, 0, 0), 1e308),
    ]
    for i, case in enumerate(cases):
        with pytest.raises(SplineKitError):
            case()
            pytest.fail(f"case {i} did not raise")
    with pytest.raises(ParameterError, match="MAX_STEPS"):
        ls.advance(1e9, 1.0)
    with pytest.raises(ParameterError, match="MAX_STEPS"):
        ls.advance(1.0, 1e308)


def test_reinitialize_survives_samples_near_the_float_limit():
    # phi - other would overflow; the crossing is still halfway between the two slabs
    phi = np.where(np.arange(5)[:, None, None] < 2, -1e308, 1e308) * np.ones((5, 4, 4))
    r = LevelSet(phi, (0, 0, 0), 0.1).reinitialize()
    assert np.allclose(r.phi[:, 0, 0], [-0.15, -0.05, 0.05, 0.15, 0.25], atol=1e-15)
