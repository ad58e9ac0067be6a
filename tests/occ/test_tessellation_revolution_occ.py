"""Faces of revolution on the fast path (latitude strips: the sphere corners and torus fillets
of build123d parts) against independent yardsticks.

Yardsticks: closed-form volumes and areas (a box of side ``a`` with every edge rounded by ``r`` is
the Minkowski sum of a box of side ``L = a - 2 r`` and a ball: ``V = L^3 + 6 L^2 r + 3 pi L r^2 +
4/3 pi r^3``, ``A = 6 L^2 + 6 pi L r + 4 pi r^2``), OCC's GProp at raised precision where no closed
form is at hand, the faces' own evaluators and normals (:func:`test_tessellation_fast._check`),
the exact spheres of the corners, BRepMesh's triangle count at the same measured deviation and
the general path's meshes.
"""

from __future__ import annotations

import functools
import math
import pickle

import numpy as np
import pytest
from _gprop import volume_area
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_tessellation_brep import measured_deviation
from test_tessellation_fast import _check
from test_tessellation_fast_occ import occ_triangles_at

import splinekit as sk
from splinekit import _kernels
from splinekit.tessellation import fast_mesh, latitude
from splinekit.tessellation.revolution import Revolutions
from splinekit.tessellation.trimmed import _Prepared, _tessellate_trimmed

bd = pytest.importorskip("build123d")


def rounded_box(a, r):
    """Closed-form ``(volume, area)`` of a cube of side ``a`` with every edge rounded by ``r``."""
    L = a - 2.0 * r
    volume = L**3 + 6 * L * L * r + 3 * math.pi * L * r * r + 4 / 3 * math.pi * r**3
    return volume, 6 * L * L + 6 * math.pi * L * r + 4 * math.pi * r * r


def _solid(part):
    from splinekit.interop.occ_brep import brep_from_shape

    got = brep_from_shape(part.wrapped)
    return got[0] if isinstance(got, list) else got


def _parts():
    box = lambda r: bd.fillet(bd.Box(20, 20, 20).edges(), r)  # noqa: E731
    return {
        # 6 planes, 12 quarter cylinders, 8 sphere octants with a pole each
        "filleted box": (lambda: box(3.0), rounded_box(20.0, 3.0)),
        "filleted box with a hole": (lambda: box(3.0) - bd.Cylinder(4, 20),
                                     (rounded_box(20.0, 3.0)[0] - math.pi * 16 * 20,
                                      rounded_box(20.0, 3.0)[1] - 2 * math.pi * 16 + 2 * math.pi * 4 * 20)),  # fmt: skip
        # a cylinder with both circular edges rounded: two torus fillets (a full turn, a seam)
        "filleted cylinder": (lambda: bd.fillet(bd.Cylinder(5, 10).edges(), 1.0), None),
        # a plate with its vertical edges rounded, then its top edges: torus corners
        "rounded plate": (lambda: bd.fillet(bd.fillet(bd.Box(30, 20, 10).edges().filter_by(bd.Axis.Z), 4).edges()
                                            .group_by(bd.Axis.Z)[-1], 2), None),  # fmt: skip
    }


PARTS = _parts()


@functools.cache
def _built(name):
    """The part's splinekit solid and its ``(volume, area)`` (built once: the fillets, the
    conversion and GProp take seconds)."""
    make, exact = PARTS[name]
    part = make()
    return _solid(part), exact if exact is not None else volume_area(part.wrapped)


def _make(name):
    """A fresh copy of the part's solid (nothing cached on its faces), its volume and area."""
    solid, (volume, area) = _built(name)
    return pickle.loads(pickle.dumps(solid)), volume, area


def _plan(solid):
    return solid.faces[0]._cache["tessellate"].memo.get("fast")


@pytest.mark.parametrize("rel", [1e-1, 1e-2, 1e-3, 1e-4, 1e-5])
@pytest.mark.parametrize("name", sorted(PARTS))
def test_mixed_path_keeps_every_guarantee(name, rel):
    solid, volume, area = _make(name)
    mesh = sk.tessellate(solid, rel, relative=True)
    plan = _plan(solid)
    assert plan is not None and plan.lat is not None  # faces of revolution on the fast path
    # closed, outward, volume within the tolerance-implied bound, max_deviation the true value of the
    # faces' own evaluators at the barycentric (u, v), corner (u, v) and vertex normals exact
    _check(solid, mesh, volume, area)
    again = sk.tessellate(solid, rel, relative=True)
    assert np.array_equal(again.faces, mesh.faces) and np.array_equal(again.vertices, mesh.vertices)


@pytest.mark.parametrize("rel", [1e-1, 1e-4])
@pytest.mark.parametrize("name", ["filleted box", "filleted cylinder"])
def test_numpy_and_compiled_latitude_strips_agree(name, rel, monkeypatch):
    pytest.importorskip("numba")
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    a = sk.tessellate(_make(name)[0], rel, relative=True)
    monkeypatch.setenv("SPLINEKIT_NUMBA", "1")
    solid, volume, area = _make(name)
    b = sk.tessellate(solid, rel, relative=True)
    assert _kernels.get(latitude.KERNELS) is not None
    _check(solid, b, volume, area)
    # the same vertices, the same triangles (the same zipper rule), the same measured deviation
    assert (a.n_faces, a.n_vertices) == (b.n_faces, b.n_vertices)
    assert np.abs(a.vertices - b.vertices).max() <= 1e-12 * np.abs(a.vertices).max()
    assert np.abs(a.normals - b.normals).max() <= 1e-12
    assert {tuple(sorted(t)) for t in a.faces.tolist()} == {tuple(sorted(t)) for t in b.faces.tolist()}
    assert math.isclose(a.max_deviation, b.max_deviation, rel_tol=1e-9)


@pytest.mark.parametrize("rel", [1e-1, 1e-3, 1e-5])
def test_sphere_corners_on_their_exact_spheres(rel):
    # every vertex of a corner face lies on the sphere of radius 3 about (+-7, +-7, +-7), and its
    # normal is the radial direction (poles included)
    solid, _, _ = _make("filleted box")
    mesh = sk.tessellate(solid, rel, relative=True)
    plan = _plan(solid)
    corner = np.isin(mesh.face_patch, plan.lat.face)
    F = np.asarray(mesh.faces)[corner]
    V = mesh.vertices[np.unique(F)]
    c = 7.0 * np.sign(V)
    assert np.abs(np.linalg.norm(V - c, axis=1) - 3.0).max() <= 1e-12
    assert np.abs(mesh.normals[np.unique(F)] - (V - c) / 3.0).max() <= 1e-12


@pytest.mark.parametrize("rel", [1e-1, 1e-2, 1e-3])
@pytest.mark.parametrize("name", ["filleted box", "filleted box with a hole", "filleted cylinder", "rounded plate"])
def test_no_more_triangles_than_brepmesh_at_equal_deviation(name, rel):
    solid, _, _ = _make(name)
    mesh = sk.tessellate(solid, rel, relative=True)
    assert _plan(solid).lat is not None
    ours = measured_deviation(mesh, solid.faces)
    assert mesh.n_faces <= occ_triangles_at(solid, ours)


@pytest.mark.parametrize("rel", [1e-1, 1e-3, 1e-4])
@pytest.mark.parametrize("name", ["filleted box", "filleted cylinder"])
def test_no_more_triangles_than_the_general_path(name, rel):
    solid, volume, area = _make(name)
    fast = sk.tessellate(solid, rel, relative=True)
    prep = _Prepared.of(solid.faces, solid.faces[0]._cache["diagonal"][1])
    general = _tessellate_trimmed(prep, fast.tolerance, 0.5)
    assert general.is_closed and general.max_deviation <= fast.tolerance * (1 + 1e-9)
    assert abs(general.volume - volume) <= area * fast.tolerance
    assert fast.n_faces <= general.n_faces


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(r=st.floats(0.5, 9.0), rel=st.sampled_from([1e-1, 1e-2, 1e-3, 1e-4]))
def test_random_fillet_radii_and_tolerances(r, rel):
    solid = _solid(bd.fillet(bd.Box(20, 20, 20).edges(), r))
    volume, area = rounded_box(20.0, r)
    mesh = sk.tessellate(solid, rel, relative=True)
    assert _plan(solid).lat is not None
    assert mesh.is_closed and mesh.euler_characteristic == 2
    dev = measured_deviation(mesh, solid.faces)
    assert dev <= mesh.tolerance * (1 + 1e-9) and abs(mesh.max_deviation - dev) <= 1e-9 * mesh.tolerance
    assert 0 < mesh.volume and abs(mesh.volume - volume) <= area * mesh.tolerance


def test_mutations_fail_the_checks(monkeypatch):
    # the numpy path with a defect planted: each must be caught by _check
    monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    volume, area = rounded_box(20.0, 3.0)

    def caught():
        solid = _make("filleted box")[0]
        mesh = sk.tessellate(solid, 1e-3, relative=True)
        with pytest.raises(AssertionError):
            _check(solid, mesh, volume, area)

    with monkeypatch.context() as m:  # strips zipped the wrong way round
        zip_rows = latitude.zip_rows
        m.setattr(latitude, "zip_rows", lambda *a: (lambda T, q: (T[:, [0, 2, 1]], q))(*zip_rows(*a)))
        caught()
    with monkeypatch.context() as m:  # normals of the faces of revolution inward
        normals = Revolutions.normals
        m.setattr(Revolutions, "normals", lambda self, *a: -normals(self, *a))
        caught()
    with monkeypatch.context() as m:  # a boundary row cut into one segment more than its arc
        row_counts = fast_mesh.row_counts

        def wrong(lp, n, *a):
            got = row_counts(lp, n, *a)
            if got is None:
                return None
            n, rows = got
            rows = rows.copy()
            rows[0] += 1
            return n, rows

        m.setattr(fast_mesh, "row_counts", wrong)
        solid = _make("filleted box")[0]
        sk.tessellate(solid, 1e-2, relative=True)  # builds the plan
        # its samples are another arc's: the fast path's own measurement refuses the mesh
        assert fast_mesh.fast_tessellation(_plan(solid), 1e-3 * solid.faces[0]._cache["diagonal"][1], 0.5) is None
