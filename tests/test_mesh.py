"""PolyMesh topology and geometry (splinekit.mesh): closed forms, invariants, bad input.

Curvature convergence on an icosphere of radius R = 2 (vertices exactly on the
sphere; cotangent mean curvature and angle-defect Gaussian curvature over
Meyer et al. mixed areas), measured with this code (numpy 2.4, float64):

    level  vertices  max|H - 1/R|  mean|H - 1/R|  max|K - 1/R²|  mean|K - 1/R²|
      1         42     6.7e-16        3.3e-16        2.0e-02        1.9e-02
      2        162     7.0e-05        2.8e-05        5.1e-03        4.8e-03
      3        642     1.7e-05        5.7e-06        1.4e-03        1.2e-03
      4       2562     4.4e-06        8.5e-07        3.5e-04        3.0e-04
      5      10242     1.1e-06        1.2e-07        8.9e-05        7.4e-05
      6      40962     2.7e-07        1.5e-08        2.2e-05        1.9e-05

Both errors fall by about 4 per level (second order in the edge length). H is
exact at levels 0 and 1 because there every vertex lies on a symmetry axis of
the icosahedron: for a vertex whose neighbours all lie on the sphere and whose
triangles are not obtuse, the radial part of (L x) / (2 A_voronoi) is exactly
1/R (x_i . (x_i - x_j) = |x_i - x_j|² / 2 and sum_j w_ij |x_i - x_j|² = 4 A_voronoi),
so the only error is the tangential part, which symmetry cancels. K is not
exact: the inscribed polyhedron has less area than the sphere, while its angle
defects always sum to exactly 4 pi.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from splinekit.errors import MeshTopologyError, ParameterError, SplineKitError
from splinekit.mesh import PolyMesh, Topology
from splinekit.mesh import geometry as G
from splinekit.mesh.primitives import box, grid, icosphere, torus

TWO_PI = 2.0 * np.pi

# (level, max |H - 1/R|, mean |H - 1/R|, max |K - 1/R²|, mean |K - 1/R²|) upper bounds:
# the measured values of the module docstring, rounded up by ~10 %
SPHERE_BOUNDS = [
    (1, 1e-14, 1e-14, 2.2e-2, 2.1e-2),
    (2, 7.7e-5, 3.1e-5, 5.6e-3, 5.3e-3),
    (3, 1.9e-5, 6.3e-6, 1.5e-3, 1.3e-3),
    (4, 4.8e-6, 9.4e-7, 3.9e-4, 3.3e-4),
    (5, 1.2e-6, 1.3e-7, 9.8e-5, 8.2e-5),
    (6, 3.0e-7, 1.7e-8, 2.5e-5, 2.1e-5),
]


def reversed_faces(mesh):
    """The same mesh with every face's orientation reversed."""
    t = mesh.topology
    flat = t.face_indices.copy()
    sizes = t.face_sizes
    # reverse inside each face: position p in face f goes to size - 1 - p
    pos = t.corner_index
    flat[t.face_offsets[t.corner_face] + sizes[t.corner_face] - 1 - pos] = t.face_indices
    return PolyMesh(mesh.vertices, np.split(flat, t.face_offsets[1:-1]))


def triangulated(mesh):
    tris, _ = G.triangulate(mesh.topology)
    return PolyMesh(mesh.vertices, tris)


def jittered_grid(nx, ny, seed, amount=0.3):
    """A flat triangulated grid with interior vertices moved randomly in the plane."""
    g = grid(nx, ny)
    V = g.vertices.copy()
    rng = np.random.default_rng(seed)
    inner = ~g.boundary_vertices
    V[inner, :2] += rng.uniform(-amount, amount, (int(inner.sum()), 2)) / max(nx, ny)
    return triangulated(PolyMesh(V, g.faces))


def hemisphere(level, radius=1.0):
    """An open cap: the faces of an icosphere whose centroid has z > 0, unused vertices dropped."""
    s = icosphere(level, radius)
    F = s.faces[s.vertices[s.faces].mean(axis=1)[:, 2] > 0]
    used, inverse = np.unique(F, return_inverse=True)
    return PolyMesh(s.vertices[used], inverse.reshape(F.shape))


# -- topology ---------------------------------------------------------------------------------
class TestTopology:
    def test_cube_counts(self):
        m = box()
        assert (m.n_vertices, m.topology.n_edges, m.n_faces) == (8, 12, 6)
        assert m.euler_characteristic == 2 and m.is_closed and m.is_quad_mesh
        assert not m.boundary_edges.any() and not m.boundary_vertices.any()
        np.testing.assert_array_equal(m.valence, 3)
        offsets, faces = m.topology.vertex_faces
        np.testing.assert_array_equal(np.diff(offsets), 3)
        # vertex 0 = (low, low, low) lies on the -x, -y and -z faces
        np.testing.assert_array_equal(faces[offsets[0]:offsets[1]], [0, 2, 4])

    @pytest.mark.parametrize("level", [0, 1, 2, 3])
    def test_icosphere_counts(self, level):
        m = icosphere(level)
        n = 4**level
        assert (m.n_vertices, m.topology.n_edges, m.n_faces) == (10 * n + 2, 30 * n, 20 * n)
        assert m.euler_characteristic == 2 and m.is_closed and m.is_triangle_mesh
        counts = np.bincount(m.valence, minlength=7)
        assert counts[5] == 12 and counts[6] == m.n_vertices - 12

    def test_torus_counts(self):
        m = torus(12, 7)
        assert (m.n_vertices, m.topology.n_edges, m.n_faces) == (84, 168, 84)
        assert m.euler_characteristic == 0 and m.is_closed
        np.testing.assert_array_equal(m.valence, 4)

    def test_grid_boundary(self):
        nx, ny = 5, 3
        m = grid(nx, ny)
        t = m.topology
        assert m.euler_characteristic == 1 and not m.is_closed
        assert t.n_edges == nx * (ny + 1) + ny * (nx + 1)
        assert m.boundary_edges.sum() == 2 * (nx + ny)
        assert m.boundary_vertices.sum() == 2 * (nx + ny)
        ij = np.argwhere(np.ones((nx + 1, ny + 1), bool))  # vertex i * (ny + 1) + j
        on_rim = (ij[:, 0] % nx == 0) | (ij[:, 1] % ny == 0)
        np.testing.assert_array_equal(m.boundary_vertices, on_rim)
        # boundary edges have one face, interior edges two
        ef = t.edge_faces
        np.testing.assert_array_equal(ef[:, 1] < 0, m.boundary_edges)
        assert (ef[:, 0] >= 0).all()
        # twins pair interior half-edges in opposite directions
        tw = t.twin
        inner = tw >= 0
        np.testing.assert_array_equal(t.halfedge_src[tw[inner]], t.halfedge_dst[inner])
        assert (tw < 0).sum() == 2 * (nx + ny)

    def test_vertex_faces_and_edges_of_a_small_mesh(self):
        # a quad 0-1-2-3 and a triangle 1-4-2 sharing edge (1, 2)
        m = PolyMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0.5, 0]], [[0, 1, 2, 3], [1, 4, 2]])
        t = m.topology
        assert isinstance(m.faces, list) and len(m.faces) == 2
        np.testing.assert_array_equal(m.face_offsets, [0, 4, 7])
        np.testing.assert_array_equal(m.edges, [[0, 1], [0, 3], [1, 2], [1, 4], [2, 3], [2, 4]])
        offsets, faces = t.vertex_faces
        per_vertex = [faces[offsets[v]:offsets[v + 1]].tolist() for v in range(5)]
        assert per_vertex == [[0], [0, 1], [0, 1], [0], [1]]
        np.testing.assert_array_equal(t.edge_faces[2], [0, 1])
        assert m.euler_characteristic == 5 - 6 + 2 == 1

    def test_isolated_vertices_are_kept(self):
        V = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [7, 7, 7]]
        m = PolyMesh(V, [[0, 1, 2]])
        assert m.n_vertices == 4
        np.testing.assert_array_equal(m.topology.isolated_vertices, [False, False, False, True])
        assert m.valence[3] == 0 and m.euler_characteristic == 4 - 3 + 1
        assert not m.boundary_vertices[3]
        np.testing.assert_array_equal(m.vertex_normals[3], 0.0)
        assert m.mean_curvature[3] == 0 and m.gaussian_curvature[3] == 0 and m.mixed_areas[3] == 0
        # an isolated vertex is a point component: its defect 2 pi keeps Gauss-Bonnet
        assert np.isclose(G.angle_defects(m).sum(), TWO_PI * m.euler_characteristic)
        L = m.cotangent_laplacian
        assert L[3].nnz <= 1 and L[3, 3] == 0

    # every MeshTopologyError case; each message names the culprit
    @pytest.mark.parametrize(
        "vertices, faces, pattern",
        [
            (np.eye(3), [[0, 1, 5]], r"face 0 refers to vertex 5, outside 0\.\.2"),
            (np.eye(3), [[0, 1, 2], [0, -1, 2]], r"face 1 refers to vertex -1"),
            (np.eye(3), [[0, 1, 2], [1, 2]], r"face 1 has 2 vertices; a face needs at least 3"),
            (np.eye(4), [[0, 1, 2], [0, 3, 3]], r"face 1 uses vertex 3 more than once"),
            (np.eye(5), [[0, 1, 2], [1, 0, 3], [0, 1, 4]], r"edge \(0, 1\) is shared by 3 faces \[0, 1, 2\]"),
            (np.eye(4), [[0, 1, 2], [0, 1, 3]], r"faces 0 and 1 are oriented inconsistently.*edge \(0, 1\)"),
            ([[0, 0, 0], [1, np.nan, 0], [0, 1, 0]], [[0, 1, 2]], r"vertex 1 has non-finite coordinates"),
            ([[0, 0, 0], [1, 0, 0], [0, 1, np.inf]], [[0, 1, 2]], r"vertex 2 has non-finite coordinates"),
            (np.eye(3), [[0.0, 1.5, 2.0]], r"integer vertex indices"),
            (np.eye(3), [[0, 1, 2], [[0, 1], [1, 2]]], r"face 1"),
        ],
    )
    def test_mesh_topology_errors_name_the_culprit(self, vertices, faces, pattern):
        with pytest.raises(MeshTopologyError, match=pattern):
            PolyMesh(vertices, faces)

    def test_bad_vertex_arrays(self):
        with pytest.raises(MeshTopologyError, match=r"shape \(n, dim\)"):
            PolyMesh(np.zeros(3), [[0, 1, 2]])
        with pytest.raises(SplineKitError):
            PolyMesh([["a", "b", "c"]] * 3, [[0, 1, 2]])
        m = icosphere(0)
        with pytest.raises(MeshTopologyError, match="vertex 4 has non-finite"):
            m.with_vertices(np.where(np.arange(12)[:, None] == 4, np.nan, m.vertices))

    def test_errors_are_value_errors(self):
        assert issubclass(MeshTopologyError, ValueError)
        with pytest.raises(ValueError):
            Topology(3, [0, 1, 1], [0, 3])


# -- triangulation ----------------------------------------------------------------------------
class TestTriangulate:
    def test_fan_from_first_corner(self):
        faces = [[0, 1, 2, 3, 4], [5, 6, 7], [3, 2, 8, 9]]
        t = PolyMesh(np.random.default_rng(0).normal(size=(10, 3)), faces).topology
        tris, tri_face = G.triangulate(t)
        np.testing.assert_array_equal(
            tris, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [5, 6, 7], [3, 2, 8], [3, 8, 9]]
        )
        np.testing.assert_array_equal(tri_face, [0, 0, 0, 1, 2, 2])

    def test_triangle_mesh_unchanged_and_mesh_accepted(self):
        m = icosphere(1)
        tris, tri_face = G.triangulate(m)  # a PolyMesh works as well as its topology
        np.testing.assert_array_equal(tris, m.faces)
        np.testing.assert_array_equal(tri_face, np.arange(m.n_faces))

    def test_fan_keeps_orientation_and_topology(self):
        m = torus(10, 6)
        tm = triangulated(m)  # PolyMesh validates: consistent orientation, manifold
        assert tm.n_faces == 2 * m.n_faces and tm.euler_characteristic == 0
        assert np.isclose(tm.volume, m.volume) and np.isclose(tm.area, m.area)

    def test_empty(self):
        tris, tri_face = G.triangulate(PolyMesh(np.zeros((2, 3)), np.zeros((0, 3), int)).topology)
        assert tris.shape == (0, 3) and tri_face.shape == (0,)


# -- faces, areas, volume ---------------------------------------------------------------------
class TestFacesAndVolume:
    def test_cube_normals_areas_volume(self):
        m = box(size=(1.0, 2.0, 3.0), center=(5.0, -1.0, 2.0))
        expected_normals = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]])
        np.testing.assert_allclose(m.face_normals, expected_normals, atol=1e-15)
        np.testing.assert_allclose(m.face_areas, [6, 6, 3, 3, 2, 2], rtol=1e-14)
        assert np.isclose(m.area, 22.0, rtol=1e-14)
        assert np.isclose(m.volume, 6.0, rtol=1e-14)
        corner = np.sign(m.vertices - [5.0, -1.0, 2.0]) / np.sqrt(3)
        np.testing.assert_allclose(m.vertex_normals, corner, atol=1e-15)
        np.testing.assert_allclose(G.face_vector_areas(m), expected_normals * m.face_areas[:, None], atol=1e-14)

    def test_reversed_orientation_flips_normals_volume_and_mean_curvature(self):
        m = icosphere(2, 1.5)
        r = reversed_faces(m)
        np.testing.assert_allclose(r.face_normals, -m.face_normals, atol=1e-15)
        np.testing.assert_allclose(r.vertex_normals, -m.vertex_normals, atol=1e-15)
        assert np.isclose(r.volume, -m.volume)
        np.testing.assert_allclose(r.mean_curvature, -m.mean_curvature, rtol=1e-12)
        np.testing.assert_allclose(r.gaussian_curvature, m.gaussian_curvature, rtol=1e-12)
        np.testing.assert_allclose(r.face_areas, m.face_areas, rtol=1e-14)

    def test_sphere_area_and_volume_converge(self):
        R = 3.0
        errs = []
        for level in range(1, 6):
            m = icosphere(level, R)
            assert m.volume > 0
            errs.append((abs(m.area - 4 * np.pi * R**2), abs(m.volume - 4 / 3 * np.pi * R**3)))
        errs = np.array(errs)
        assert (errs[:-1] / errs[1:] > 3.5).all()  # second order: about 4 per level
        assert errs[-1, 0] / (4 * np.pi * R**2) < 5e-4

    def test_volume_is_translation_invariant_and_needs_a_closed_mesh(self):
        m = torus(16, 8, 2.0, 0.5)
        shifted = m.with_vertices(m.vertices + [1e3, -2e3, 5e2])
        assert np.isclose(shifted.volume, m.volume, rtol=1e-9)
        with pytest.raises(MeshTopologyError, match=r"volume needs a closed mesh; edge \(\d+, \d+\) is on the boundary"):
            grid(2, 2).volume
        with pytest.raises(MeshTopologyError, match="no faces"):
            G.volume(PolyMesh(np.zeros((3, 3)), np.zeros((0, 3), int)))

    def test_polygon_faces(self):
        # a regular pentagon and a square sharing no vertex, as one mesh of mixed faces
        a = TWO_PI * np.arange(5) / 5
        pent = np.column_stack([np.cos(a), np.sin(a), np.zeros(5)])
        sq = np.array([[0, 0, 1], [1, 0, 1], [1, 0, 2], [0, 0, 2]], float)  # in the plane y = 0
        m = PolyMesh(np.vstack([pent, sq]), [[0, 1, 2, 3, 4], [5, 6, 7, 8]])
        np.testing.assert_allclose(m.face_areas, [2.5 * np.sin(TWO_PI / 5), 1.0], rtol=1e-14)
        np.testing.assert_allclose(m.face_normals, [[0, 0, 1], [0, -1, 0]], atol=1e-15)

    def test_non_planar_quad_normal_is_the_vector_area(self):
        V = np.array([[0, 0, 0], [1, 0, 0.3], [1, 1, 0], [0, 1, 0.3]])
        m = PolyMesh(V, [[0, 1, 2, 3]])
        vec = 0.5 * sum(np.cross(V[i], V[(i + 1) % 4]) for i in range(4))  # polygon vector area
        np.testing.assert_allclose(G.face_vector_areas(m)[0], vec, atol=1e-15)
        np.testing.assert_allclose(m.face_normals[0], vec / np.linalg.norm(vec), atol=1e-15)
        # the area is that of the fan (0, 1, 2) + (0, 2, 3), at least |vector area|
        fan = 0.5 * (np.linalg.norm(np.cross(V[1], V[2])) + np.linalg.norm(np.cross(V[2], V[3])))
        assert np.isclose(m.face_areas[0], fan) and m.face_areas[0] >= np.linalg.norm(vec)

    def test_quad_and_triangulated_quad_mesh_agree(self):
        for m in (box(), torus(12, 8), grid(3, 4)):
            t = triangulated(m)
            for name in ("area", "vertex_normals", "mean_curvature", "gaussian_curvature", "mixed_areas"):
                np.testing.assert_allclose(getattr(m, name), getattr(t, name), atol=1e-13, err_msg=name)
            np.testing.assert_allclose(
                m.cotangent_laplacian.toarray(), t.cotangent_laplacian.toarray(), atol=1e-13
            )

    def test_two_dimensional_meshes(self):
        V2 = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float)
        m = PolyMesh(V2, [[0, 1, 2, 3]])
        np.testing.assert_allclose(m.face_areas, [2.0])
        assert np.isclose(m.area, 2.0) and np.isclose(m.mixed_areas.sum(), 2.0)
        np.testing.assert_array_equal(m.gaussian_curvature, 0.0)
        assert m.cotangent_laplacian.shape == (4, 4)
        for name in ("face_normals", "vertex_normals", "mean_curvature", "volume"):
            with pytest.raises(ParameterError, match="needs 3-D vertices"):
                getattr(m, name)
        with pytest.raises(ParameterError, match="dimension >= 2"):
            G.face_areas(PolyMesh([[0.0], [1.0], [2.0]], [[0, 1, 2]]))

    def test_higher_dimensional_areas(self):
        # a unit right triangle embedded in 5-D, rotated: area 1/2
        Q, _ = np.linalg.qr(np.random.default_rng(1).normal(size=(5, 5)))
        V = np.array([[0, 0, 0, 0, 0], [1, 0, 0, 0, 0], [0, 1, 0, 0, 0]], float) @ Q.T
        assert np.isclose(PolyMesh(V, [[0, 1, 2]]).area, 0.5, rtol=1e-14)


# -- normals ----------------------------------------------------------------------------------
class TestNormals:
    def test_flat_grid_normals(self):
        for m in (grid(4, 3), jittered_grid(6, 5, seed=3)):
            np.testing.assert_allclose(m.face_normals, np.tile([0, 0, 1.0], (m.n_faces, 1)), atol=1e-15)
            np.testing.assert_allclose(m.vertex_normals, np.tile([0, 0, 1.0], (m.n_vertices, 1)), atol=1e-15)

    def test_sphere_vertex_normals_are_nearly_radial(self):
        # measured max |n - radial| (R = 2): levels 0, 1: 2e-16 (every vertex lies on a
        # symmetry axis); 2: 1.04e-2, 3: 5.2e-3, 4: 2.6e-3, 5: 1.3e-3, 6: 6.5e-4. The max error
        # is first order (angle weights are O(h) on irregular rings), the mean falls faster
        # (4.6e-3, 2.2e-3, 7.5e-4, 2.2e-4, 6.0e-5)
        previous = None
        for level in range(0, 6):
            m = icosphere(level, 2.0, center=(1.0, -2.0, 0.5))
            radial = (m.vertices - [1.0, -2.0, 0.5]) / 2.0
            err = np.linalg.norm(m.vertex_normals - radial, axis=1).max()
            if level <= 1:
                assert err < 1e-14
            elif level == 2:
                assert err < 1.1e-2
            else:
                assert err < previous / 1.9
            previous = err
        assert previous < 1.4e-3
        np.testing.assert_allclose(np.linalg.norm(m.vertex_normals, axis=1), 1.0, rtol=1e-15)

    def test_angle_weights_ignore_how_a_face_is_split(self):
        # vertex 0 of a unit cube corner; splitting the +z face into 2 triangles or 4
        # changes face counts around vertex 0 but not the angle-weighted normal
        m = box()
        t = triangulated(m)
        np.testing.assert_allclose(t.vertex_normals, m.vertex_normals, atol=1e-15)

    def test_degenerate_faces_give_zero_normals_not_nan(self):
        V = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 0, 0], [5, 5, 5]]
        m = PolyMesh(V, [[0, 1, 2], [1, 0, 3]])  # collinear; with two coincident points
        np.testing.assert_array_equal(m.face_normals, 0.0)
        np.testing.assert_array_equal(m.vertex_normals, 0.0)
        for name in ("face_areas", "mixed_areas", "mean_curvature", "gaussian_curvature", "mean_curvature_normal"):
            value = getattr(m, name)
            assert np.isfinite(value).all() and not value.any(), name
        assert np.isfinite(m.cotangent_laplacian.toarray()).all()


# -- Laplacian and mixed areas ----------------------------------------------------------------
class TestLaplacian:
    @pytest.mark.parametrize("make", [lambda: icosphere(2), lambda: torus(10, 6), lambda: jittered_grid(5, 4, 7), lambda: grid(3, 2)])
    def test_symmetric_zero_row_sums_psd(self, make):
        m = make()
        L = m.cotangent_laplacian
        assert sp.issparse(L) and L.format == "csr" and L.shape == (m.n_vertices,) * 2
        assert (L != L.T).nnz == 0  # exactly symmetric
        np.testing.assert_allclose(np.asarray(L.sum(axis=1)).ravel(), 0.0, atol=1e-12)
        eig = np.linalg.eigvalsh(L.toarray())
        assert eig[0] > -1e-12 and abs(eig[0]) < 1e-12  # PSD, constants in the kernel
        assert (L.diagonal() >= 0).all()

    def test_equilateral_weights(self):
        # two equilateral triangles: every angle is 60 degrees, cot = 1/sqrt(3)
        V = [[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0], [0.5, -np.sqrt(3) / 2, 0]]
        L = PolyMesh(V, [[0, 1, 2], [1, 0, 3]]).cotangent_laplacian.toarray()
        c = 1 / np.sqrt(3)
        assert np.isclose(L[0, 1], -c) and np.isclose(L[0, 2], -c / 2) and L[2, 3] == 0
        assert np.isclose(L[0, 0], 2 * c)

    @pytest.mark.parametrize("seed", [0, 1, 2])
    def test_linear_precision_on_planar_meshes(self, seed):
        rng = np.random.default_rng(seed)
        for m in (jittered_grid(7, 6, seed), grid(5, 4, size=(2.0, 0.7))):
            a, b = rng.normal(size=3), rng.normal()
            f = m.vertices @ a + b
            Lf = m.cotangent_laplacian @ f
            inner = ~m.boundary_vertices
            assert abs(Lf[inner]).max() < 1e-12
            assert abs(Lf[~inner]).max() > 1e-3  # the boundary rows do not vanish

    def test_laplacian_of_coordinates_is_twice_area_gradient_on_sphere(self):
        m = icosphere(3)
        Hn = m.mean_curvature_normal
        LX = m.cotangent_laplacian @ m.vertices
        np.testing.assert_allclose(Hn, LX / (2 * m.mixed_areas[:, None]), rtol=1e-12)

    def test_mixed_areas_of_single_triangles(self):
        eq = PolyMesh([[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]], [[0, 1, 2]])
        np.testing.assert_allclose(eq.mixed_areas, eq.area / 3, rtol=1e-14)
        right = PolyMesh([[0, 0, 0], [2, 0, 0], [0, 1, 0]], [[0, 1, 2]])  # Voronoi: circumcentre on the hypotenuse
        np.testing.assert_allclose(right.mixed_areas, [0.5, 0.25, 0.25], rtol=1e-14)
        obtuse = PolyMesh([[0, 0, 0], [2, 0, 0], [1, 0.2, 0]], [[0, 1, 2]])  # obtuse at vertex 2
        A = obtuse.area
        np.testing.assert_allclose(obtuse.mixed_areas, [A / 4, A / 4, A / 2], rtol=1e-14)

    @pytest.mark.parametrize("make", [lambda: jittered_grid(6, 6, 11, 0.45), lambda: icosphere(3), lambda: torus(9, 5)])
    def test_mixed_areas_tile_the_surface(self, make):
        m = make()
        assert np.isclose(m.mixed_areas.sum(), m.area, rtol=1e-13)
        assert (m.mixed_areas > 0).all()


# -- curvature --------------------------------------------------------------------------------
class TestCurvature:
    def test_sphere_convergence(self):
        R = 2.0
        rows = []
        for level, h_max, h_mean, k_max, k_mean in SPHERE_BOUNDS:
            m = icosphere(level, R)
            eh = np.abs(m.mean_curvature + 1 / R)
            ek = np.abs(m.gaussian_curvature - 1 / R**2)
            rows.append((level, m.n_vertices, eh.max(), eh.mean(), ek.max(), ek.mean()))
            assert eh.max() < h_max and eh.mean() < h_mean, rows[-1]
            assert ek.max() < k_max and ek.mean() < k_mean, rows[-1]
            assert (m.mean_curvature < 0).all()  # outward normals: negative (OCC's sign)
        e = np.array(rows)
        # second-order convergence from level 2 on (level 1 is exact by symmetry for H)
        assert (e[1:-1, 2] / e[2:, 2] > 3.5).all() and (e[:-1, 4] / e[1:, 4] > 3.5).all()

    def test_sphere_curvature_scales_with_radius(self):
        a, b = icosphere(3, 1.0), icosphere(3, 1e-3)
        np.testing.assert_allclose(b.mean_curvature, 1e3 * a.mean_curvature, rtol=1e-12)
        np.testing.assert_allclose(b.gaussian_curvature, 1e6 * a.gaussian_curvature, rtol=1e-12)

    @pytest.mark.parametrize(
        "make",
        [
            lambda: icosphere(0),
            lambda: icosphere(3, 0.7),
            lambda: box((1, 3, 0.2)),
            lambda: triangulated(box()),
            lambda: torus(20, 9, 1.0, 0.45),
            lambda: PolyMesh(icosphere(2).vertices * [1.0, 2.0, 0.5], icosphere(2).faces),  # ellipsoid
        ],
    )
    def test_gauss_bonnet_closed(self, make):
        m = make()
        K, A = m.gaussian_curvature, m.mixed_areas
        assert np.isclose((K * A).sum(), TWO_PI * m.euler_characteristic, rtol=0, atol=1e-10)
        assert np.isclose(G.angle_defects(m).sum(), TWO_PI * m.euler_characteristic, rtol=0, atol=1e-10)

    def test_gauss_bonnet_on_a_noisy_sphere(self):
        rng = np.random.default_rng(5)
        s = icosphere(3)
        m = s.with_vertices(s.vertices * rng.uniform(0.8, 1.2, (s.n_vertices, 1)))
        assert np.isclose((m.gaussian_curvature * m.mixed_areas).sum(), 2 * TWO_PI, atol=1e-10)

    def test_torus_defect_sums_to_zero_and_curvature_matches(self):
        nu, nv, R, r = 96, 48, 1.0, 0.4
        m = torus(nu, nv, R, r)
        assert abs(G.angle_defects(m).sum()) < 1e-10
        assert abs((m.gaussian_curvature * m.mixed_areas).sum()) < 1e-10
        t = TWO_PI * np.tile(np.arange(nv), nu) / nv  # tube angle of each vertex
        K = np.cos(t) / (r * (R + r * np.cos(t)))
        H = (R + 2 * r * np.cos(t)) / (2 * r * (R + r * np.cos(t)))
        # measured on this quad mesh: max errors 7.6e-3 (K) and 1.5e-3 (H)
        assert np.abs(m.gaussian_curvature - K).max() < 1e-2
        assert np.abs(m.mean_curvature + H).max() < 2e-3  # outward normals: -H
        # K < 0 on the inside of the ring, > 0 outside
        assert (np.sign(m.gaussian_curvature[np.abs(np.cos(t)) > 0.1]) == np.sign(np.cos(t)[np.abs(np.cos(t)) > 0.1])).all()

    def test_flat_grid_has_zero_curvature(self):
        for m in (grid(6, 4), jittered_grid(8, 8, 2), triangulated(grid(3, 5, size=(10.0, 1.0)))):
            assert np.abs(m.mean_curvature).max() < 1e-12
            assert np.abs(m.gaussian_curvature).max() < 1e-12
            np.testing.assert_allclose(m.mean_curvature_normal, 0.0, atol=1e-12)
            inner = ~m.boundary_vertices
            np.testing.assert_allclose(G.angle_defects(m)[inner], 0.0, atol=1e-13)

    def test_open_mesh_boundary(self):
        R = 1.5
        m = hemisphere(4, R)
        b = m.boundary_vertices
        assert not m.is_closed and b.any() and m.euler_characteristic == 1
        # boundary vertices get 0 for both curvatures (documented convention) ...
        np.testing.assert_array_equal(m.mean_curvature[b], 0.0)
        np.testing.assert_array_equal(m.gaussian_curvature[b], 0.0)
        np.testing.assert_array_equal(m.mean_curvature_normal[b], 0.0)
        # ... interior vertices are unaffected by the cut
        s = icosphere(4, R)
        assert np.abs(m.mean_curvature[~b] + 1 / R).max() < 1e-5
        assert np.abs(m.gaussian_curvature[~b] - 1 / R**2).max() < 1e-3
        # discrete Gauss-Bonnet with the boundary turning angles (pi - angle sum)
        assert np.isclose(G.angle_defects(m).sum(), TWO_PI * m.euler_characteristic, atol=1e-10)
        assert np.isfinite(m.vertex_normals).all()
        radial = m.vertices / R
        assert np.linalg.norm(m.vertex_normals - radial, axis=1).max() < 0.1
        assert s.mean_curvature.shape == (s.n_vertices,)

    def test_grid_boundary_defects(self):
        # flat rectangle: corners turn by pi/2, edge vertices by 0; sum 2 pi (a disk)
        m = grid(4, 3)
        d = G.angle_defects(m)
        corners = [0, 3, 16, 19]
        np.testing.assert_allclose(d[corners], np.pi / 2, atol=1e-14)
        np.testing.assert_allclose(np.delete(d, corners), 0.0, atol=1e-14)

    def test_saddle_sign(self):
        # z = x^2 - y^2 near the origin: K = -4, H = 0 (for normal +z)
        n = 41
        x = np.linspace(-0.05, 0.05, n)
        X, Y = np.meshgrid(x, x, indexing="ij")
        g = grid(n - 1, n - 1)
        V = np.column_stack([X.ravel(), Y.ravel(), (X**2 - Y**2).ravel()])
        m = triangulated(PolyMesh(V, g.faces))
        centre = (n // 2) * n + n // 2
        assert np.isclose(m.gaussian_curvature[centre], -4.0, rtol=2e-2)
        assert abs(m.mean_curvature[centre]) < 1e-2
        # a bowl z = x^2 + y^2 with normal +z (toward the centre of curvature): H = +2 at the bottom
        Vb = V.copy()
        Vb[:, 2] = (X**2 + Y**2).ravel()
        bowl = triangulated(PolyMesh(Vb, g.faces))
        assert np.isclose(bowl.mean_curvature[centre], 2.0, rtol=2e-2)
        assert np.isclose(bowl.gaussian_curvature[centre], 4.0, rtol=2e-2)


# -- scaling, caching, primitives -------------------------------------------------------------
class TestRobustness:
    def test_extreme_coordinates(self):
        s = icosphere(2)
        huge = s.with_vertices(s.vertices * 1e300)
        np.testing.assert_allclose(huge.mean_curvature * 1e300, s.mean_curvature, rtol=1e-12)
        np.testing.assert_allclose(huge.face_normals, s.face_normals, atol=1e-15)
        np.testing.assert_allclose(huge.vertex_normals, s.vertex_normals, atol=1e-15)
        with pytest.raises(MeshTopologyError, match="area at face 0 overflows.*too large"):
            huge.face_areas
        with pytest.raises(MeshTopologyError, match="volume overflows"):
            huge.volume
        tiny = s.with_vertices(s.vertices * 1e-300)
        np.testing.assert_allclose(tiny.mean_curvature * 1e-300, s.mean_curvature, rtol=1e-12)
        small = s.with_vertices(s.vertices * 1e-150)
        np.testing.assert_allclose(small.mixed_areas / 1e-150 / 1e-150, s.mixed_areas, rtol=1e-12)
        with pytest.raises(MeshTopologyError, match="Gaussian curvature at vertex 0 overflows.*too small"):
            tiny.gaussian_curvature

    def test_far_from_origin(self):
        s = icosphere(3)
        far = s.with_vertices(s.vertices + 1e4)
        np.testing.assert_allclose(far.mean_curvature, s.mean_curvature, rtol=1e-9)
        np.testing.assert_allclose(far.gaussian_curvature, s.gaussian_curvature, rtol=1e-8)
        assert np.isclose(far.volume, s.volume, rtol=1e-10)

    def test_cached_and_read_only(self):
        m = icosphere(1)
        for name in ("face_normals", "face_areas", "vertex_normals", "mean_curvature", "gaussian_curvature", "mixed_areas"):
            value = getattr(m, name)
            assert getattr(m, name) is value
            with pytest.raises(ValueError):
                value[0] = 1.0
        L = m.cotangent_laplacian
        assert m.cotangent_laplacian is L
        with pytest.raises(ValueError):
            L.data[0] = 1.0
        assert isinstance(m.area, float) and isinstance(m.volume, float)
        with pytest.raises(AttributeError):
            m.face_normals = None

    def test_functions_match_properties(self):
        m = torus(8, 5)
        np.testing.assert_array_equal(G.face_normals(m), m.face_normals)
        np.testing.assert_array_equal(G.vertex_normals(m), m.vertex_normals)
        np.testing.assert_array_equal(G.mean_curvature(m), m.mean_curvature)
        np.testing.assert_array_equal(G.gaussian_curvature(m), m.gaussian_curvature)
        np.testing.assert_array_equal(G.mixed_areas(m), m.mixed_areas)
        assert G.total_area(m) == m.area and G.volume(m) == m.volume

    def test_precomputed_arguments_are_checked(self):
        m = icosphere(1)
        with pytest.raises(ParameterError, match=r"face_normals must have shape \(80, 3\)"):
            G.vertex_normals(m, face_normals=np.zeros((3, 3)))
        with pytest.raises(ParameterError, match="normals holds non-finite"):
            G.mean_curvature(m, normals=np.full((42, 3), np.nan))
        with pytest.raises(ParameterError, match=r"laplacian must have shape \(42, 42\)"):
            G.mean_curvature(m, laplacian=sp.eye(3))
        np.testing.assert_allclose(
            G.mean_curvature(m, laplacian=m.cotangent_laplacian.toarray(), normals=m.vertex_normals), m.mean_curvature
        )

    def test_primitive_parameters(self):
        with pytest.raises(ParameterError, match="radius"):
            icosphere(1, radius=-1.0)
        with pytest.raises(ParameterError, match="subdivisions"):
            icosphere(1.5)
        with pytest.raises(ParameterError, match="exceeds"):
            icosphere(17)
        with pytest.raises(ParameterError, match="smaller than R"):
            torus(8, 8, 1.0, 1.0)
        with pytest.raises(ParameterError, match="nv"):
            torus(8, 2)
        with pytest.raises(ParameterError, match="size"):
            box(size=(1, 0, 1))
        with pytest.raises(ParameterError, match="nx"):
            grid(0, 3)
        assert np.isclose(box(size=2.0).volume, 8.0)
        np.testing.assert_allclose(np.linalg.norm(icosphere(3, 2.5).vertices, axis=1), 2.5, rtol=1e-15)


def test_polymesh_pickles_and_copies():
    import copy
    import pickle

    from splinekit.mesh import primitives

    m = primitives.torus(5, 4)
    assert pickle.loads(pickle.dumps(m)) == m
    assert copy.deepcopy(m) == m
