"""Mesh booleans (splinekit.interop.booleans, through manifold3d) against exact OCC solids.

Every operand is a convex solid (sphere, cylinder, box) built twice: exactly in
OpenCascade (``BRepPrimAPI_Make*``, booleans with ``BRepAlgoAPI_Fuse/Cut/Common``,
volume and area with ``BRepGProp``), and as a triangle mesh built here whose
vertices lie exactly on the solid's surface (a rotated, scaled icosphere; a
cylinder from two rings of ``n`` vertices and two cap centres; a box from its
corners). The mesh booleans must match OCC within bounds derived from the
meshes' chordal deviation.

Bounds
------
For operand ``i`` let ``delta_i`` be the largest distance from its mesh to its
exact surface (an icosphere: ``r - min over triangles of the centre-to-plane
distance``; a cylinder of ``n`` segments: ``r (1 - cos(pi / n))``; a box: 0),
``area_i`` the exact surface area and ``kappa_i`` the largest principal
curvature (``1/r``; 0 for a box).

* Volume. The inscribed mesh ``P_i`` of a convex solid ``S_i`` lies inside it,
  and every point of ``S_i \\ P_i`` is within ``delta_i`` of ``dS_i``, so
  ``vol(S_i \\ P_i) <= area_i * delta_i`` (the inner parallel body of a convex
  set loses volume at most at the rate of its surface area). A boolean is a
  pointwise set operation, so its exact and meshed results differ only where
  some operand does: ``|V_mesh - V_occ| <= sum_i area_i * delta_i``.
* Area. Radial projection of a mesh triangle onto its surface changes area by
  a factor within ``[1 - kappa delta, (1 - kappa delta)**-2]`` (sphere; the
  cylinder's chords and cap polygons are closer), so each operand's surface
  area is off by at most ``2 kappa_i delta_i area_i``. Where the two surfaces
  cross at angle ``alpha`` along curves of total length ``L``, moving them by
  ``delta_a`` and ``delta_b`` along their normals moves the crossing curve by at
  most ``(delta_a + delta_b) / sin(alpha)`` inside each surface, which changes
  the area kept on the two sides by at most ``2 L (delta_a + delta_b) / sin(alpha)``.
  So ``|A_mesh - A_occ| <= sum_i 2 kappa_i delta_i area_i + 2 L (delta_a + delta_b) / sin(alpha)``
  to first order in ``delta`` (here ``kappa delta < 1e-3``, so the neglected
  second-order terms are far below the slack the bound leaves). ``L`` and
  ``alpha`` are computed in closed form for each configuration below.

Both get an absolute floor of ``1e-7 * (scale of the values)`` for OCC's
numerical integration. The algebraic properties (inclusion-exclusion of
volume and area, commutativity, n-ary = chained union) hold for the meshes
themselves, up to rounding (1e-9 relative).
"""

from __future__ import annotations

import re
import subprocess
import sys
from dataclasses import dataclass

import manifold3d
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from OCP.BRepAlgoAPI import BRepAlgoAPI_Common, BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
from OCP.BRepGProp import BRepGProp
from OCP.BRepPrimAPI import (
    BRepPrimAPI_MakeBox,
    BRepPrimAPI_MakeCylinder,
    BRepPrimAPI_MakeSphere,
)
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt
from OCP.GProp import GProp_GProps

from splinekit.errors import (
    BackendError,
    MeshTopologyError,
    MissingDependencyError,
    NotManifoldError,
    ParameterError,
    SplineKitError,
)
from splinekit.interop import booleans
from splinekit.interop.booleans import (
    difference,
    from_manifold,
    intersection,
    to_manifold,
    union,
    union_all,
)
from splinekit.mesh import PolyMesh, Topology
from splinekit.mesh.primitives import icosphere

OCC_FLOOR = 1e-7  # relative slack for OCC's numerical volume / area integration
ALGEBRA_RTOL = 1e-9  # identities that hold for the meshes themselves


# -- operands: exact (OCC) and meshed ---------------------------------------------------------
def rotation(seed: int) -> np.ndarray:
    """A fixed proper rotation (det +1), so meshes are not aligned with the axes or each other."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


@dataclass
class Sphere:
    radius: float
    center: tuple
    level: int = 5
    seed: int = 0

    def occ(self):
        return BRepPrimAPI_MakeSphere(gp_Pnt(*self.center), self.radius).Shape()

    def mesh(self) -> PolyMesh:
        unit = icosphere(self.level)
        return PolyMesh(np.asarray(self.center) + self.radius * unit.vertices @ rotation(self.seed).T, unit.faces)

    def deviation(self) -> float:
        m = self.mesh()
        T = m.vertices[m.faces] - np.asarray(self.center)
        n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
        d = np.abs(np.einsum("ij,ij->i", n, T[:, 0])) / np.linalg.norm(n, axis=1)
        return self.radius - d.min()

    @property
    def area(self):
        return 4 * np.pi * self.radius**2

    @property
    def kappa(self):
        return 1 / self.radius


@dataclass
class Cylinder:
    """Axis parallel to z through ``(cx, cy)``, from ``z0`` to ``z1``."""

    radius: float
    cx: float
    cy: float
    z0: float
    z1: float
    segments: int = 512

    def occ(self):
        ax = gp_Ax2(gp_Pnt(self.cx, self.cy, self.z0), gp_Dir(0, 0, 1))
        return BRepPrimAPI_MakeCylinder(ax, self.radius, self.z1 - self.z0).Shape()

    def mesh(self) -> PolyMesh:
        n = self.segments
        t = 2 * np.pi * np.arange(n) / n
        ring = np.column_stack([self.cx + self.radius * np.cos(t), self.cy + self.radius * np.sin(t)])
        V = np.vstack([
            np.column_stack([ring, np.full(n, self.z0)]),  # bottom ring 0..n-1
            np.column_stack([ring, np.full(n, self.z1)]),  # top ring n..2n-1
            [[self.cx, self.cy, self.z0], [self.cx, self.cy, self.z1]],  # cap centres 2n, 2n+1
        ])
        i = np.arange(n)
        j = (i + 1) % n
        F = np.vstack([
            np.column_stack([i, j, n + j]),  # side, outward normals
            np.column_stack([i, n + j, n + i]),
            np.column_stack([np.full(n, 2 * n), j, i]),  # bottom cap, normal -z
            np.column_stack([np.full(n, 2 * n + 1), n + i, n + j]),  # top cap, normal +z
        ])
        return PolyMesh(V, F)

    def deviation(self) -> float:
        return self.radius * (1 - np.cos(np.pi / self.segments))

    @property
    def area(self):
        return 2 * np.pi * self.radius * (self.radius + self.z1 - self.z0)

    @property
    def kappa(self):
        return 1 / self.radius


@dataclass
class Box:
    lo: tuple
    hi: tuple

    def occ(self):
        return BRepPrimAPI_MakeBox(gp_Pnt(*self.lo), gp_Pnt(*self.hi)).Shape()

    def mesh(self) -> PolyMesh:
        # quads (fan-triangulated by the boolean): exercises the polygon path
        bits = (np.arange(8)[:, None] >> np.array([2, 1, 0])) & 1
        V = np.where(bits, self.hi, self.lo).astype(float)
        F = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
        return PolyMesh(V, F)

    def deviation(self) -> float:
        return 0.0

    @property
    def area(self):
        a, b, c = np.subtract(self.hi, self.lo)
        return 2 * (a * b + b * c + c * a)

    kappa = 0.0


def props(shape):
    v, a = GProp_GProps(), GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, v)
    BRepGProp.SurfaceProperties_s(shape, a)
    return v.Mass(), a.Mass()


OCC_OPS = {"union": BRepAlgoAPI_Fuse, "difference": BRepAlgoAPI_Cut, "intersection": BRepAlgoAPI_Common}
MESH_OPS = {"union": union, "difference": difference, "intersection": intersection}


def sphere_sphere_crossing(r1, c1, r2, c2):
    """``(L, sin alpha)`` of two crossing spheres: the circle's length and the angle of the surfaces."""
    d = float(np.linalg.norm(np.subtract(c2, c1)))
    x = (d * d + r1 * r1 - r2 * r2) / (2 * d)
    cos = (r1 * r1 + r2 * r2 - d * d) / (2 * r1 * r2)  # between the outward normals on the circle
    return 2 * np.pi * np.sqrt(r1 * r1 - x * x), np.sqrt(1 - cos * cos)


# (name, a, b, L, sin(alpha)): L and alpha in closed form (module docstring)
S_UNIT = Sphere(1.0, (0.0, 0.0, 0.0), seed=1)
CASES = [
    ("sphere-sphere", S_UNIT, Sphere(0.8, (1.1, 0.13, 0.07), seed=2),
     *sphere_sphere_crossing(1.0, (0, 0, 0), 0.8, (1.1, 0.13, 0.07))),
    # plane x = 0.4 cuts the unit sphere in a circle of radius sqrt(0.84); sphere normal . x = 0.4 there
    ("sphere-box", S_UNIT, Box((0.4, -2.5, -2.7), (3.0, 2.6, 2.4)), 2 * np.pi * np.sqrt(0.84), np.sqrt(0.84)),
    # coaxial: two circles of radius 0.5 at z = 0.1 +- sqrt(0.75); sphere normal . radial = 0.5
    ("cylinder-sphere", Cylinder(0.5, 0.0, 0.0, -1.5, 1.6), Sphere(1.0, (0.0, 0.0, 0.1), seed=3),
     2 * 2 * np.pi * 0.5, np.sqrt(0.75)),
    # plane z = 0.3 across the axis: one circle, right angle
    ("cylinder-box-across", Cylinder(0.5, 0.0, 0.0, -1.0, 1.0), Box((-2.0, -2.0, 0.3), (2.0, 2.0, 3.0)),
     2 * np.pi * 0.5, 1.0),
    # plane x = 0.2 along the axis: two lines of length 2 on the side (cylinder normal . x = 0.4)
    # and two chords of length 2 sqrt(0.21) on the caps (at right angles)
    ("cylinder-box-along", Cylinder(0.5, 0.0, 0.0, -1.0, 1.0), Box((0.2, -2.0, -2.0), (3.0, 2.0, 2.0)),
     2 * 2.0 + 2 * 2 * np.sqrt(0.21), np.sqrt(1 - 0.16)),
    # boxes are exact: the bounds are the OCC floor alone
    ("box-box", Box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)), Box((0.5, 0.25, -0.5), (1.5, 1.25, 0.7)), 0.0, 1.0),
]


def assert_closed_solid(m: PolyMesh):
    """Closed triangle 2-manifold, consistently and outward oriented."""
    assert m.is_closed and m.is_triangle_mesh
    assert m.vertices.shape[1] == 3 and np.isfinite(m.vertices).all()
    PolyMesh(m.vertices, m.faces)  # re-checked: edges with at most 2 faces, consistent orientation
    assert m.volume > 0


@pytest.mark.parametrize("op", ["union", "difference", "intersection", "difference-reversed"])
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_boolean_matches_occ(case, op):
    name, a, b, L, sin_alpha = case
    if op == "difference-reversed":
        op, a, b = "difference", b, a
    ma, mb = a.mesh(), b.mesh()
    result = MESH_OPS[op](ma, mb)
    assert_closed_solid(result)

    v_occ, a_occ = props(OCC_OPS[op](a.occ(), b.occ()).Shape())
    da, db = a.deviation(), b.deviation()
    v_bound = a.area * da + b.area * db + OCC_FLOOR * max(v_occ, 1.0)
    a_bound = (2 * a.kappa * da * a.area + 2 * b.kappa * db * b.area + 2 * L * (da + db) / sin_alpha
               + OCC_FLOOR * max(a_occ, 1.0))
    dv, dA = abs(result.volume - v_occ), abs(result.area - a_occ)
    assert dv <= v_bound, f"{name} {op}: volume {result.volume} vs OCC {v_occ}, |dV| {dv:.3g} > {v_bound:.3g}"
    assert dA <= a_bound, f"{name} {op}: area {result.area} vs OCC {a_occ}, |dA| {dA:.3g} > {a_bound:.3g}"
    # the bounds must be tight enough to tell the operations apart
    others = [props(OCC_OPS[o](a.occ(), b.occ()).Shape())[0] for o in OCC_OPS if o != op]
    assert all(abs(v - v_occ) > 2 * v_bound for v in others)


def test_union_all_of_overlapping_spheres_matches_occ():
    # four unit spheres on a regular tetrahedron of edge 1.2 (shifted off the origin), plus one far away
    tet = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float) * 1.2 / np.sqrt(8)
    centers = [tuple(c) for c in tet + [0.31, -0.17, 0.05]] + [(4.0, 0.5, 0.0)]
    spheres = [Sphere(1.0, c, level=4, seed=10 + i) for i, c in enumerate(centers)]
    result = union_all([s.mesh() for s in spheres])
    assert_closed_solid(result)
    assert len(result.topology.edges) and result.euler_characteristic == 4  # two sphere-like shells

    shape = spheres[0].occ()
    for s in spheres[1:]:
        shape = BRepAlgoAPI_Fuse(shape, s.occ()).Shape()
    v_occ, a_occ = props(shape)
    deltas = [s.deviation() for s in spheres]
    v_bound = sum(s.area * d for s, d in zip(spheres, deltas)) + OCC_FLOOR * v_occ
    a_bound = sum(2 * s.kappa * d * s.area for s, d in zip(spheres, deltas)) + OCC_FLOOR * a_occ
    for i in range(4):  # every pair of the four crosses; the parts inside a third sphere only shorten L
        for j in range(i + 1, 4):
            L, sin_alpha = sphere_sphere_crossing(1.0, centers[i], 1.0, centers[j])
            a_bound += 2 * L * (deltas[i] + deltas[j]) / sin_alpha
    assert abs(result.volume - v_occ) <= v_bound, (result.volume, v_occ, v_bound)
    assert abs(result.area - a_occ) <= a_bound, (result.area, a_occ, a_bound)
    # the n-ary union is the chained binary union
    chained = spheres[0].mesh()
    for s in spheres[1:]:
        chained = union(chained, s.mesh())
    assert chained.volume == pytest.approx(result.volume, rel=ALGEBRA_RTOL)
    assert chained.area == pytest.approx(result.area, rel=ALGEBRA_RTOL)


# -- algebraic properties ---------------------------------------------------------------------
coord = st.floats(-1.2, 1.2, allow_nan=False)


@settings(max_examples=25, deadline=None)
@given(c=st.tuples(coord, coord, coord), r=st.floats(0.3, 1.5), seed=st.integers(0, 1000))
def test_inclusion_exclusion(c, r, seed):
    A = Sphere(1.0, (0.0, 0.0, 0.0), level=3, seed=seed).mesh()
    B = Sphere(r, c, level=3, seed=seed + 1).mesh()
    u, i, d = union(A, B), intersection(A, B), difference(A, B)
    vi = i.volume if i.n_faces else 0.0
    ai = i.area if i.n_faces else 0.0
    scale = A.volume + B.volume
    # V(A u B) + V(A n B) = V(A) + V(B) and V(A \ B) + V(A n B) = V(A); the same for areas
    # (the boundary pieces of union and intersection partition those of A and B)
    assert abs(u.volume + vi - A.volume - B.volume) <= ALGEBRA_RTOL * scale
    dv = d.volume if d.n_faces else 0.0
    assert abs(dv + vi - A.volume) <= ALGEBRA_RTOL * scale
    assert abs(u.area + ai - A.area - B.area) <= ALGEBRA_RTOL * (A.area + B.area)
    u2 = union(B, A)
    assert abs(u2.volume - u.volume) <= ALGEBRA_RTOL * scale
    for m in (u, i, d):
        if m.n_faces:
            assert_closed_solid(m)


def test_inverted_body_is_reoriented():
    a = S_UNIT.mesh()
    b = Sphere(0.8, (1.1, 0.13, 0.07), level=4).mesh()
    inverted = PolyMesh(a.vertices, a.faces[:, ::-1])
    assert inverted.volume < 0
    ref = union(a, b)
    for r in (union(inverted, b), union(b, inverted)):
        assert_closed_solid(r)
        assert r.volume == pytest.approx(ref.volume, rel=ALGEBRA_RTOL)
    assert difference(inverted, b).volume == pytest.approx(difference(a, b).volume, rel=ALGEBRA_RTOL)


def test_cavity_is_kept():
    # a hollow ball: outer shell outward, inner shell inward; its volume is the difference of the balls
    outer, inner = icosphere(3, radius=2.0), icosphere(3, radius=1.0)
    n = outer.n_vertices
    hollow = PolyMesh(np.vstack([outer.vertices, inner.vertices]), np.vstack([outer.faces, inner.faces[:, ::-1] + n]))
    r = union(hollow, icosphere(2, radius=0.3, center=(5, 0, 0)))
    assert r.volume == pytest.approx(outer.volume - inner.volume + icosphere(2, radius=0.3).volume, rel=1e-9)


# -- empty results and operands ------------------------------------------------------------------
def test_disjoint_intersection_is_empty_mesh():
    a = icosphere(2)
    b = icosphere(2, center=(3.0, 0.0, 0.0))
    r = intersection(a, b)
    assert isinstance(r, PolyMesh)
    assert r.n_faces == 0 and r.n_vertices == 0 and r.vertices.shape == (0, 3)
    assert not r.is_closed  # no faces (documented)
    # the empty body is a valid operand: the identity of union, absorbing for intersection
    assert union(r, a).volume == pytest.approx(a.volume, rel=ALGEBRA_RTOL)
    assert intersection(a, r).n_faces == 0
    assert difference(a, a).n_faces == 0
    assert union_all([]).n_faces == 0


def test_union_all_single_and_disjoint():
    a = icosphere(2)
    assert union_all([a]).volume == pytest.approx(a.volume, rel=ALGEBRA_RTOL)
    far = [icosphere(1, center=(3.0 * k, 0, 0)) for k in range(5)]
    r = union_all(iter(far))  # any iterable
    assert r.volume == pytest.approx(5 * far[0].volume, rel=ALGEBRA_RTOL)
    assert r.euler_characteristic == 10


# -- other operand types ------------------------------------------------------------------------
def test_manifold_operands_and_conversion():
    a = S_UNIT.mesh()
    m = to_manifold(a)
    assert isinstance(m, manifold3d.Manifold)
    assert m.volume() == pytest.approx(a.volume, rel=1e-12)
    back = from_manifold(m)
    assert back.n_faces == a.n_faces and back.volume == pytest.approx(a.volume, rel=1e-12)
    # float64 all the way: coordinates survive the round trip bit for bit (up to vertex order)
    assert np.array_equal(np.sort(back.vertices, axis=0), np.sort(a.vertices, axis=0))
    b = Sphere(0.8, (1.1, 0.13, 0.07), level=4)
    inverted = manifold3d.Manifold(manifold3d.Mesh64(
        vert_properties=np.array(a.vertices), tri_verts=np.ascontiguousarray(a.faces[:, ::-1]).astype(np.uint64)))
    assert inverted.volume() < 0  # manifold3d keeps the winding it is given
    assert union(inverted, b.mesh()).volume == pytest.approx(union(a, b.mesh()).volume, rel=ALGEBRA_RTOL)
    assert union(m, b.mesh()).volume == pytest.approx(union(a, b.mesh()).volume, rel=ALGEBRA_RTOL)
    assert union(b.mesh(), m).volume == pytest.approx(union(a, b.mesh()).volume, rel=ALGEBRA_RTOL)


def test_manifold_in_error_state_raises_backend_error():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [np.nan, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], np.uint64)
    bad = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=V, tri_verts=F))
    with pytest.raises(BackendError, match="NonFiniteVertex"):
        union(bad, icosphere(1))
    with pytest.raises(BackendError, match="NonFiniteVertex"):
        from_manifold(bad)
    with pytest.raises(ParameterError, match="Manifold"):
        from_manifold(icosphere(1))


def test_tessellate_is_called_with_tolerance(monkeypatch):
    calls = []

    def tessellate(obj, tolerance):
        calls.append((obj, tolerance))
        return icosphere(2, center=(0.5, 0, 0))

    monkeypatch.setattr(booleans, "tessellate", tessellate)  # the name booleans calls
    token = object()
    r = union(icosphere(2), token, tolerance=0.01)
    assert calls == [(token, 0.01)]
    assert r.volume == pytest.approx(union(icosphere(2), icosphere(2, center=(0.5, 0, 0))).volume, rel=1e-12)
    monkeypatch.setattr(booleans, "tessellate", lambda obj, tolerance: "not a mesh")
    with pytest.raises(BackendError, match="str"):
        union(icosphere(1), token)


def test_import_does_not_load_manifold3d_and_missing_backend_is_named(monkeypatch):
    code = "import sys, splinekit.interop.booleans; print('manifold3d' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
    monkeypatch.setitem(sys.modules, "manifold3d", None)
    with pytest.raises(MissingDependencyError, match="pip install manifold3d"):
        union(icosphere(1), icosphere(1))


# -- bad input ---------------------------------------------------------------------------------
def unchecked(V, F) -> PolyMesh:
    """A PolyMesh that skips the constructor's topology checks (which would already reject it)."""
    F = np.asarray(F, dtype=np.int64)
    return PolyMesh.from_topology(np.asarray(V, float), Topology(len(V), F.ravel(), np.arange(len(F) + 1) * F.shape[1], check=False))


def named_edge(message: str) -> tuple:
    m = re.search(r"edge \((\d+), (\d+)\)", message)
    assert m, message
    return tuple(sorted(map(int, m.groups())))


def face_edges(face) -> set:
    return {tuple(sorted((int(face[k]), int(face[(k + 1) % len(face)])))) for k in range(len(face))}


BOX_V = ((np.arange(8)[:, None] >> np.array([2, 1, 0])) & 1).astype(float)
BOX_Q = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])
BOX_T = np.vstack([BOX_Q[:, [0, 1, 2]], BOX_Q[:, [0, 2, 3]]])


@pytest.mark.parametrize("removed", range(6))
def test_open_mesh_names_boundary_edge(removed):
    open_box = PolyMesh(BOX_V, np.delete(BOX_Q, removed, axis=0))  # the constructor allows open meshes
    for call in (lambda: union(open_box, icosphere(1)), lambda: difference(icosphere(1), open_box)):
        with pytest.raises(NotManifoldError, match="boundary edge") as err:
            call()
        assert named_edge(str(err.value)) in face_edges(BOX_Q[removed])
    with pytest.raises(NotManifoldError, match=r"bodies\[1\]"):
        union_all([icosphere(1), open_box])


def test_edge_shared_by_four_faces():
    # two tetrahedra sharing the edge (0, 1) only: manifold3d itself would accept this
    Vt = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    Ft = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    V = np.vstack([Vt, -Vt[2:]])
    F = np.vstack([Ft, np.where(Ft >= 2, Ft + 2, Ft)])
    with pytest.raises(MeshTopologyError):
        PolyMesh(V, F)  # the checked constructor refuses it too
    with pytest.raises(NotManifoldError, match="shared by 4 faces") as err:
        union(unchecked(V, F), icosphere(1))
    assert named_edge(str(err.value)) == (0, 1)


def test_fin_on_closed_mesh():
    # a closed box with an extra triangle hanging on edge (0, 1): three faces on that edge
    F = np.vstack([BOX_T, [[0, 1, 8]]])
    V = np.vstack([BOX_V, [[0.5, -1.0, 0.0]]])
    with pytest.raises(NotManifoldError) as err:
        union(unchecked(V, F), icosphere(1))
    msg = str(err.value)
    assert ("shared by 3 faces" in msg and named_edge(msg) == (0, 1)) or (
        "boundary edge" in msg and named_edge(msg) in {(0, 8), (1, 8)}
    )


@pytest.mark.parametrize("flipped", [0, 5, 11])
def test_inconsistent_orientation(flipped):
    F = BOX_T.copy()
    F[flipped] = F[flipped][::-1]
    with pytest.raises(NotManifoldError, match="inconsistently oriented") as err:
        intersection(icosphere(1), unchecked(BOX_V, F))
    assert named_edge(str(err.value)) in face_edges(BOX_T[flipped])


def test_non_finite_vertices():
    V = BOX_V.copy()
    V[3, 1] = np.nan
    with pytest.raises(SplineKitError, match="vertex 3"):
        PolyMesh(V, BOX_T)
    for bad in (np.nan, np.inf, -np.inf):
        V[3, 1] = bad
        with pytest.raises(SplineKitError, match="vertex 3"):
            union(unchecked(V, BOX_T), icosphere(1))


def test_malformed_faces():
    # the message names the operand, the face and the vertex
    with pytest.raises(MeshTopologyError, match=r"first operand: face 11 refers to vertex 9, outside 0\.\.7"):
        union(unchecked(BOX_V, np.vstack([BOX_T[:-1], [[0, 1, 9]]])), icosphere(1))
    with pytest.raises(MeshTopologyError, match="second operand: face 12 uses vertex 0 more than once"):
        union(icosphere(1), unchecked(BOX_V, np.vstack([BOX_T, [[0, 0, 1]]])))
    quads = [list(q) for q in BOX_Q]
    quads[0] = [0, 1, 3, 1]
    bad = PolyMesh.from_topology(BOX_V, Topology(8, np.ravel(quads), np.arange(7) * 4, check=False))
    with pytest.raises(MeshTopologyError, match="first operand: face 0 uses vertex 1 more than once"):
        union(bad, icosphere(1))
    small = PolyMesh.from_topology(BOX_V, Topology(8, np.r_[BOX_T.ravel(), 0, 1], np.r_[np.arange(13) * 3, 38], check=False))
    with pytest.raises(MeshTopologyError, match=r"bodies\[0\]: face 12 has 2 vertices"):
        union_all([small])


def test_bad_arguments():
    s = icosphere(1)
    flat = PolyMesh(np.array([[0, 0], [1, 0], [0, 1]], float), [[0, 1, 2]])
    with pytest.raises(ParameterError, match="3-D"):
        union(flat, s)
    with pytest.raises(SplineKitError):
        union(s, "a sphere")
    with pytest.raises(SplineKitError):
        intersection(None, s)
    for tol in (-1.0, 0.0, np.nan, "fine", [0.1]):
        with pytest.raises(ParameterError, match="tolerance"):
            union(s, s, tolerance=tol)
    for bodies in (s, 3, "spheres"):
        with pytest.raises(ParameterError, match="bodies"):
            union_all(bodies)
