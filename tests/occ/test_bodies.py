"""End-to-end checks of closed spline bodies: construct -> tessellate -> booleans, OCC, STEP, STL.

Bodies are exact rational NURBS patch sets made by ``splinekit.construct``
(``revolve`` of a circle, a half circle and a rectangle of lines: a torus, a
sphere and a capped cylinder of three patches) and a Catmull-Clark torus. Each
is checked three ways that do not share code: against closed forms (volume,
distance to the exact surface), against OpenCascade working on the exact
patches (``splinekit.occ.to_shape`` -> ``BRepGProp``, ``BRepAlgoAPI``), and
for watertightness with manifold3d directly (``manifold3d.Manifold`` of the
raw arrays, not through ``splinekit.interop.booleans``).

Bounds
------
``max_deviation`` (``delta``) of a tessellation is the tessellator's largest
distance between an exact surface point and its flat-triangle point, sampled
at triangle centres and edge midpoints. Over one small triangle the surface
is quadratic to leading order, so the error vector at barycentric point
``b`` is ``e(b) = c01 b0 b1 + c02 b0 b2 + c12 b1 b2`` (it vanishes at the
corners). The edge midpoints give ``|cij| / 4 <= delta``; hence

* anywhere in a triangle ``|e| <= max|cij| * max(b0 b1 + b0 b2 + b1 b2) =
  max|cij| / 3 <= 4 delta / 3`` -- checked here with closed-form distances at
  random points of every triangle, which makes ``delta`` itself a checked
  quantity rather than a number taken on trust;
* the mean of ``|e|`` over a triangle is at most ``sum |cij| * mean(bi bj) =
  sum |cij| / 12 <= max|cij| / 4 <= delta``. The region between a closed
  surface and its mesh has volume ``integral |normal distance| dA`` (first
  order), so the exact solid ``S`` and the meshed solid ``M`` satisfy
  ``vol(S symmetric-difference M) <= area * delta``, and in particular
  ``|V_mesh - V_exact| <= area * delta``.
* Booleans are pointwise set operations, so ``op(A, B)`` and ``op(A', B')``
  differ only inside ``(A sym-diff A') u (B sym-diff B')``:
  ``|V_mesh_op - V_occ_op| <= area_A delta_A + area_B delta_B`` (plus the
  same for a third operand of ``union_all``).

OCC volumes use ``BRepGProp.VolumeProperties_s(shape, props, 1e-9)`` (adaptive
integration to a relative error of 1e-9). The default, non-adaptive call is
off by 0.1 % to 1 % on these rational solids (the torus: 9.8836 for 9.8696;
the unit sphere: 4.2276 for 4.1888), as much as or more than the tessellation
error at tolerance 1e-3, so it cannot serve as the reference here.
"""

from __future__ import annotations

import functools
from pathlib import Path

import manifold3d
import numpy as np
import pytest
from OCP.BRepAlgoAPI import BRepAlgoAPI_Common, BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.GProp import GProp_GProps
from OCP.TopAbs import TopAbs_ShapeEnum
from OCP.TopExp import TopExp
from OCP.TopTools import TopTools_IndexedMapOfShape

import splinekit as sk
from exporters import export_mesh, export_step, export_stl, import_step, import_stl
from splinekit.construct import arc, circle, line, revolve
from splinekit.errors import NotManifoldError, ParameterError
from splinekit.interop.booleans import difference, intersection, union, union_all
from splinekit.interop.occ import to_shape  # splinekit.occ is this module
from splinekit.mesh.primitives import torus as torus_cage
from splinekit.tessellation import Tessellation, tessellate

TOL = 1e-3  # chordal tolerance (model units) for the single bodies; they are 2 to 5 units across
BOOL_TOL = 2e-3  # coarser for the booleans: the bound scales with it, the cost with 1 / TOL
OCC_EPS = 1e-9  # relative accuracy requested from OCC's adaptive volume integration
Z = np.array([0.0, 0.0, 1.0])
# Profiles lie in the xz half-plane x >= 0 of their centre; a plane normal of -y makes arc angles
# run from +x towards +z, so every profile runs upward on its outer side, and revolving it
# counter-clockwise about +z gives S_u x S_v pointing out of the body (positive mesh volume).
PROFILE_NORMAL = np.array([0.0, -1.0, 0.0])


# -- bodies ---------------------------------------------------------------------------------------
class Body:
    """A closed body: its NURBS patches, closed-form volume, closed-form distance and genus;
    ``curved`` is False when part of it is flat (there the deviation is all tangential)."""

    def __init__(self, name, patches, volume, distance, genus, curved=True):
        self.name, self.patches, self.volume, self.distance, self.genus = name, patches, volume, distance, genus
        self.curved = curved

    def __repr__(self):
        return self.name


def _axial(points, center):
    """``(rho, z)``: distance from the z axis through ``center`` and height above ``center``."""
    d = np.asarray(points) - center
    return np.hypot(d[:, 0], d[:, 1]), d[:, 2]


def torus_body(R, r, center=(0.0, 0.0, 0.0)):
    c = np.asarray(center, float)
    patch = revolve(circle(c + [R, 0, 0], PROFILE_NORMAL, r), c, Z)

    def distance(p):
        rho, z = _axial(p, c)
        return np.abs(np.hypot(rho - R, z) - r)

    return Body(f"torus(R={R}, r={r})", [patch], 2 * np.pi**2 * R * r**2, distance, genus=1)


def sphere_body(r, center=(0.0, 0.0, 0.0)):
    c = np.asarray(center, float)
    patch = revolve(arc(c, PROFILE_NORMAL, r, -np.pi / 2, np.pi / 2), c, Z)  # south pole to north pole

    def distance(p):
        return np.abs(np.linalg.norm(np.asarray(p) - c, axis=1) - r)

    return Body(f"sphere(r={r})", [patch], 4 / 3 * np.pi * r**3, distance, genus=0)


def cylinder_body(R, H, center=(0.0, 0.0, 0.0)):
    """Bottom disc, side and top disc: the rectangle profile (axis -> rim -> up -> axis)
    revolved one line at a time, so the three patches share their rim circles exactly."""
    c = np.asarray(center, float)
    corners = c + np.array([[0, 0, 0], [R, 0, 0], [R, 0, H], [0, 0, H]], float)
    patches = [revolve(line(corners[i], corners[i + 1]), c, Z) for i in range(3)]

    def distance(p):
        rho, z = _axial(p, c)
        out = np.maximum(rho - R, 0.0)
        side = np.hypot(rho - R, z - np.clip(z, 0.0, H))
        return np.minimum(side, np.minimum(np.hypot(out, z), np.hypot(out, z - H)))

    return Body(f"cylinder(R={R}, H={H})", patches, np.pi * R**2 * H, distance, genus=0, curved=False)


BODIES = {
    "torus": torus_body(2.0, 0.5),
    "sphere": sphere_body(1.0),
    "cylinder": cylinder_body(1.0, 2.0),
    # placed copies for the booleans
    "ball_on_tube": sphere_body(1.0, (2.0, 0.0, 0.3)),  # overlaps the torus tube at (2, 0, 0)
    "ball": sphere_body(1.2, (0.5, 0.3, 0.2)),
    "post": cylinder_body(0.8, 2.0, (0.4, 0.2, -1.3)),  # pokes out of "ball" below and above
    "pin": cylinder_body(0.7, 2.0, (-2.0, 0.1, -1.0)),  # cuts right through the tube at (-2, 0, 0)
}
SINGLE = ["torus", "sphere", "cylinder"]
PAIRS = [("torus", "ball_on_tube"), ("ball", "post"), ("torus", "pin")]


@functools.cache
def mesh_of(name, tol=TOL) -> Tessellation:
    return tessellate(BODIES[name].patches, tol)


@functools.cache
def solid_of(name):
    return to_shape(BODIES[name].patches)


def occ_volume(shape) -> float:
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props, OCC_EPS)
    return props.Mass()


def count(shape, kind) -> int:
    found = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, getattr(TopAbs_ShapeEnum, f"TopAbs_{kind}"), found)
    return found.Extent()


def manifold(mesh) -> manifold3d.Manifold:
    """manifold3d's own view of the raw arrays (no splinekit checks in between)."""
    V = np.array(mesh.vertices, dtype=np.float64, order="C")
    T = np.array(np.asarray(mesh.faces).reshape(-1, 3), dtype=np.uint64, order="C")
    return manifold3d.Manifold(manifold3d.Mesh64(vert_properties=V, tri_verts=T))


def assert_closed_body(mesh, genus, what):
    """Closed, oriented outward, edge-manifold for manifold3d, of the given genus."""
    assert mesh.is_triangle_mesh and mesh.is_closed, f"{what}: the mesh has boundary edges"
    m = manifold(mesh)
    assert m.status() == manifold3d.Error.NoError, f"{what}: manifold3d reports {m.status()}"
    assert m.genus() == genus, f"{what}: genus {m.genus()}, expected {genus}"
    assert mesh.volume > 0, f"{what}: inward-facing mesh (volume {mesh.volume})"


def corners(mesh) -> np.ndarray:
    """``(F, 3, 3)`` corner positions of each triangle, independent of the vertex numbering."""
    return mesh.vertices[np.asarray(mesh.faces)]


def valid(shape) -> bool:
    return BRepCheck_Analyzer(shape).IsValid()


# -- 1. single bodies -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", SINGLE)
def test_tessellation_is_a_closed_manifold_of_the_right_genus(name):
    body, mesh = BODIES[name], mesh_of(name)
    assert_closed_body(mesh, body.genus, name)
    assert mesh.euler_characteristic == 2 - 2 * body.genus
    assert 0 < mesh.max_deviation <= TOL


@pytest.mark.parametrize("name", list(BODIES))
def test_max_deviation_bounds_the_closed_form_distance(name):
    # Random points of every triangle (barycentric, uniform); their closed-form distance to the
    # exact surface is at most 4/3 max_deviation (module notes). 1e-12 covers rounding in the
    # distance formulas (coordinates are O(1)).
    body, mesh = BODIES[name], mesh_of(name)
    rng = np.random.default_rng(7)
    b = rng.dirichlet(np.ones(3), size=(mesh.n_faces, 4))  # (F, 4, 3)
    P = np.einsum("fkc,fcd->fkd", b, mesh.vertices[np.asarray(mesh.faces)]).reshape(-1, 3)
    d = body.distance(P)
    assert d.max() <= 4 / 3 * mesh.max_deviation + 1e-12, (d.max(), mesh.max_deviation)
    # vertices lie on the surface (they are exact surface points)
    assert body.distance(mesh.vertices).max() <= 1e-12
    if body.curved:
        # and the bound is not vacuous: the sampled error is a sizeable part of it. (Not on the
        # cylinder: max_deviation includes the tangential error of the rational discs, which
        # drives their refinement, and the side shares their rim vertices, so its normal error
        # ends up ~500 times below max_deviation.)
        assert d.max() >= 0.25 * mesh.max_deviation


@pytest.mark.parametrize("name", list(BODIES))
def test_exact_occ_solid_is_valid_and_has_the_closed_form_volume(name):
    body, solid = BODIES[name], solid_of(name)
    assert solid.ShapeType() == TopAbs_ShapeEnum.TopAbs_SOLID
    assert valid(solid)
    assert count(solid, "FACE") == len(body.patches)
    assert count(solid, "SHELL") == 1
    # the patches are exact, so only the integration error (relative OCC_EPS) remains; 1e-7 leaves room
    assert occ_volume(solid) == pytest.approx(body.volume, rel=1e-7)


@pytest.mark.parametrize("name", SINGLE)
def test_tessellation_volume_matches_occ_within_area_times_deviation(name):
    body, mesh = BODIES[name], mesh_of(name)
    v_occ = occ_volume(solid_of(name))
    bound = mesh.area * mesh.max_deviation + OCC_EPS * v_occ  # module notes; plus OCC's integration error
    assert abs(mesh.volume - v_occ) <= bound, (mesh.volume, v_occ, bound)
    # not vacuous: the bound is under 1 % of the volume, and the closed form agrees as well
    assert bound < 0.01 * body.volume
    assert abs(mesh.volume - body.volume) <= bound


@pytest.mark.parametrize("binary", [True, False], ids=["binary", "ascii"])
@pytest.mark.parametrize("name", SINGLE)
def test_stl_round_trip_stays_watertight_with_the_same_volume(tmp_path, name, binary):
    body, mesh = BODIES[name], mesh_of(name)
    path = export_stl(tmp_path / f"{name}.stl", mesh, binary=binary)
    if binary:  # the format dispatcher writes the same file for the .stl suffix
        again = export_mesh(tmp_path / f"{name}-again.stl", mesh)
        assert Path(again).read_bytes() == Path(path).read_bytes()
    back = import_stl(path)
    # Vertices shared in memory are equal, so they stay equal after rounding and merge again
    # (renumbered in order of first appearance; triangles and their corners keep their order).
    assert back.n_vertices == mesh.n_vertices and back.n_faces == mesh.n_faces
    assert_closed_body(back, body.genus, f"{name} after STL")
    if binary:
        # float32 moves each coordinate by at most half an ulp, |x| 2^-24, so a vertex by at most
        # sqrt(3) max|x| 2^-24 =: eps. dV/dv_i = (1/3) sum of the area vectors of the triangles at
        # v_i, so |dV| <= eps * (1/3) * sum_i sum_{f at i} A_f = eps * area (to first order).
        eps = np.sqrt(3.0) * np.abs(mesh.vertices).max() * 2.0**-24
        assert abs(back.volume - mesh.volume) <= mesh.area * eps
        assert np.abs(corners(back) - corners(mesh)).max() <= eps
    else:
        # ASCII STL holds the shortest round-trip text of each float64: the same numbers
        assert np.array_equal(corners(back), corners(mesh))
        assert back.volume == pytest.approx(mesh.volume, rel=1e-12)


@pytest.mark.parametrize("name", SINGLE)
def test_step_round_trip_gives_the_same_valid_solid(tmp_path, name):
    import build123d

    body, solid = BODIES[name], solid_of(name)
    path = export_step(tmp_path / f"{name}.step", [body.patches])  # one object: the patch set
    imported = build123d.import_step(path)
    shape = imported.wrapped
    assert count(shape, "SOLID") == 1
    assert valid(shape)
    assert count(shape, "FACE") == count(solid, "FACE") == len(body.patches)
    # reals go to the file with 16 significant digits: the volume moves by ~1e-15 relative;
    # allow the integration's requested accuracy
    assert occ_volume(shape) == pytest.approx(occ_volume(solid), rel=OCC_EPS)
    # splinekit's own reader returns the solid with its faces; rebuilt it bounds the same volume
    (item,) = import_step(path)
    assert len(item.geometry.faces) == len(body.patches)
    rebuilt = to_shape(item.geometry)
    assert rebuilt.ShapeType() == TopAbs_ShapeEnum.TopAbs_SOLID and valid(rebuilt)
    assert occ_volume(rebuilt) == pytest.approx(body.volume, rel=1e-7)
    # the former per-face reading is still there: one exact surface per face, sewn again
    items = import_step(path, surfaces=True)
    assert len(items) == len(body.patches)
    resewn = to_shape([item.geometry for item in items])
    assert resewn.ShapeType() == TopAbs_ShapeEnum.TopAbs_SOLID and valid(resewn)
    assert occ_volume(resewn) == pytest.approx(body.volume, rel=1e-7)


# -- 2. booleans of spline bodies against OCC ---------------------------------------------------------
MESH_OPS = {"union": union, "difference": difference, "intersection": intersection}
OCC_OPS = {"union": BRepAlgoAPI_Fuse, "difference": BRepAlgoAPI_Cut, "intersection": BRepAlgoAPI_Common}


@functools.cache
def occ_boolean_volume(a, b, op):
    maker = OCC_OPS[op](solid_of(a), solid_of(b))
    assert maker.IsDone()
    shape = maker.Shape()
    assert valid(shape), f"OCC's {op} of {a} and {b} is invalid"
    return occ_volume(shape)


def deviation_volume(*names):
    """``sum area * max_deviation``: bounds the volume between the exact bodies and their meshes."""
    return sum(mesh_of(n, BOOL_TOL).area * mesh_of(n, BOOL_TOL).max_deviation for n in names)


@pytest.mark.parametrize("op", list(MESH_OPS))
@pytest.mark.parametrize("pair", PAIRS, ids=["-".join(p) for p in PAIRS])
def test_boolean_of_tessellations_matches_occ_on_the_exact_solids(pair, op):
    a, b = pair
    result = MESH_OPS[op](mesh_of(a, BOOL_TOL), mesh_of(b, BOOL_TOL))
    assert result.is_closed and manifold(result).status() == manifold3d.Error.NoError
    assert result.volume > 0
    v_occ = occ_boolean_volume(a, b, op)
    bound = deviation_volume(a, b) + OCC_EPS * v_occ  # module notes
    assert abs(result.volume - v_occ) <= bound, (result.volume, v_occ, bound)
    # the bound must be tight enough to tell the three operations (and the operands) apart
    others = [occ_boolean_volume(a, b, o) for o in MESH_OPS if o != op]
    others += [BODIES[a].volume, BODIES[b].volume]
    assert all(abs(v - v_occ) > 2 * bound for v in others), (others, v_occ, bound)


@pytest.mark.parametrize("pair", PAIRS, ids=["-".join(p) for p in PAIRS])
def test_mesh_booleans_satisfy_inclusion_exclusion(pair):
    # |A u B| + |A n B| = |A| + |B| and |A \ B| = |A| - |A n B| for the meshes themselves: the
    # three results are cut from the same triangles, so only rounding of the crossing points
    # separates them (relative 1e-9 is far above it and far below any real mismatch)
    A, B = mesh_of(pair[0], BOOL_TOL), mesh_of(pair[1], BOOL_TOL)
    u, i, d = union(A, B).volume, intersection(A, B).volume, difference(A, B).volume
    assert u + i == pytest.approx(A.volume + B.volume, rel=1e-9)
    assert d == pytest.approx(A.volume - i, rel=1e-9, abs=1e-9 * A.volume)


def test_union_all_of_three_spline_bodies_matches_occ():
    names = ["torus", "ball_on_tube", "pin"]
    result = union_all([mesh_of(n, BOOL_TOL) for n in names])
    assert_closed_body(result, 1, "union_all")  # the ring survives: the ball and the pin only add to it
    shape = solid_of(names[0])
    for n in names[1:]:
        maker = BRepAlgoAPI_Fuse(shape, solid_of(n))
        assert maker.IsDone()
        shape = maker.Shape()
    assert valid(shape)
    v_occ = occ_volume(shape)
    bound = deviation_volume(*names) + OCC_EPS * v_occ
    assert abs(result.volume - v_occ) <= bound, (result.volume, v_occ, bound)
    chained = union(union(mesh_of(names[0], BOOL_TOL), mesh_of(names[1], BOOL_TOL)), mesh_of(names[2], BOOL_TOL))
    assert chained.volume == pytest.approx(result.volume, rel=1e-9)


# -- 3. a Catmull-Clark body ------------------------------------------------------------------------------
CAGE = {"nu": 8, "nv": 6, "R": 1.5, "r": 0.6}


@functools.cache
def cc_surface():
    return sk.SubdivisionSurface(torus_cage(**CAGE), "catmull-clark")


@functools.cache
def cc_mesh():
    return tessellate(cc_surface(), BOOL_TOL)


def test_catmull_clark_torus_tessellates_to_a_closed_genus_one_mesh():
    mesh = cc_mesh()
    assert_closed_body(mesh, 1, "Catmull-Clark torus")
    assert mesh.euler_characteristic == 0
    # Every cage vertex is regular (valence 4), so its limit point is the bicubic B-spline value
    # (16 v + 4 (edge neighbours) + (diagonal neighbours)) / 36, and it is a patch corner, so a
    # vertex of the tessellation. Built here from the cage grid (vertex i * nv + j).
    G = np.asarray(torus_cage(**CAGE).vertices).reshape(CAGE["nu"], CAGE["nv"], 3)
    edge = sum(np.roll(G, s, axis=ax) for ax in (0, 1) for s in (1, -1))
    diag = sum(np.roll(np.roll(G, s, axis=0), t, axis=1) for s in (1, -1) for t in (1, -1))
    limit = ((16 * G + 4 * edge + diag) / 36).reshape(-1, 3)
    gap = np.linalg.norm(limit[:, None, :] - mesh.vertices[None, :, :], axis=2).min(axis=1)
    assert gap.max() <= 1e-12


def test_catmull_clark_torus_volume_and_union_with_a_sphere_match_occ():
    ss, mesh = cc_surface(), cc_mesh()
    patches, info = ss.to_bsplines()
    assert info["approximate"] == 0  # all regular: the patches are the exact limit surface
    solid = to_shape(patches)
    assert solid.ShapeType() == TopAbs_ShapeEnum.TopAbs_SOLID and valid(solid)
    v_cc = occ_volume(solid)
    assert abs(mesh.volume - v_cc) <= mesh.area * mesh.max_deviation + OCC_EPS * v_cc

    ball = sphere_body(0.7, (1.5, 0.0, 0.4))  # overlaps the tube at (1.5, 0, 0) and pokes out above it
    ball_mesh = tessellate(ball.patches, BOOL_TOL)
    result = union(mesh, ball_mesh)
    assert_closed_body(result, 1, "Catmull-Clark torus u sphere")
    maker = BRepAlgoAPI_Fuse(solid, to_shape(ball.patches))
    assert maker.IsDone() and valid(maker.Shape())
    v_occ = occ_volume(maker.Shape())
    bound = mesh.area * mesh.max_deviation + ball_mesh.area * ball_mesh.max_deviation + OCC_EPS * v_occ
    assert abs(result.volume - v_occ) <= bound, (result.volume, v_occ, bound)
    # it is a real union: larger than either body, smaller than their sum
    assert max(v_cc, ball.volume) + 2 * bound < v_occ < v_cc + ball.volume - 2 * bound


# -- bad input ------------------------------------------------------------------------------------------------
def test_open_patch_set_is_open_everywhere():
    # the cylinder without its top disc: an open tessellation, an OCC shell (not a solid),
    # and a boolean refusal naming a boundary edge
    patches = BODIES["cylinder"].patches[:2]
    mesh = tessellate(patches, TOL)
    assert not mesh.is_closed
    assert len(mesh.boundary_edges) > 0
    assert to_shape(patches).ShapeType() == TopAbs_ShapeEnum.TopAbs_SHELL
    with pytest.raises(NotManifoldError, match="boundary edge"):
        union(mesh, mesh_of("sphere"))
    with pytest.raises(NotManifoldError, match="boundary edge"):
        union(patches, BODIES["sphere"].patches, tolerance=BOOL_TOL)


@pytest.mark.parametrize("tol", [0.0, -1e-3, float("nan"), float("inf")])
def test_bad_tolerance_is_refused_along_the_pipeline(tol):
    patches = BODIES["sphere"].patches
    with pytest.raises(ParameterError, match="tolerance"):
        tessellate(patches, tol)
    with pytest.raises(ParameterError, match="tolerance"):
        union(patches, BODIES["torus"].patches, tolerance=tol)
