"""Mesh geometry: areas, normals, cotangent Laplacian, mixed areas, curvature.

Every function takes a :class:`~splinekit.mesh.polymesh.PolyMesh` (anything
with ``.vertices (n, dim)`` and ``.topology``) and works on whole arrays: there
is no Python loop per face, vertex or edge.

Conventions shared by every function here
-----------------------------------------
* **Polygons** are split by a *fan triangulation from each face's first
  corner*: a face ``(v0, v1, ..., v_{k-1})`` becomes the ``k - 2`` triangles
  ``(v0, v_j, v_{j+1})``, ``j = 1 .. k-2`` (see :func:`triangulate`). Areas,
  the cotangent Laplacian, mixed areas and both curvatures are computed on
  that triangulation; for a planar convex polygon the result does not depend
  on the choice of fan, for a non-planar one it does.
* **Units.** Lengths are in the units of ``mesh.vertices``; areas are length²,
  mean curvature 1/length, Gaussian curvature 1/length², volume length³;
  angles are radians.
* **Orientation.** Faces are counter-clockwise seen from the side their normal
  points to (outside of a closed mesh, by the right-hand rule).
* **Degenerate input never gives NaN.** A zero-area face has a zero normal and
  contributes nothing to the Laplacian; a vertex whose normal or mixed area is
  zero (isolated vertices, vertices of degenerate faces only) gets a zero
  normal and zero curvature.
* **Robust scaling.** Coordinates are scaled by a power of two (exact) and
  centred before use, so huge or tiny coordinates neither overflow nor lose
  the small differences between nearby vertices far from the origin; results
  are scaled back at the end (so they may still overflow to ``inf`` or
  underflow to 0 when the true value is out of range).
* Extrinsic quantities (normals, signed mean curvature, volume) need 3-D
  vertices; intrinsic ones (areas, Laplacian, mixed areas, mean-curvature
  normal, angle defects, Gaussian curvature) work in any dimension >= 2.
  Anything else raises :class:`~splinekit.errors.ParameterError`.

References: Meyer, Desbrun, Schröder, Barr 2003, *Discrete Differential-Geometry
Operators for Triangulated 2-Manifolds* (cotangent formula, mixed areas, angle
defect); Thürmer & Wüthrich 1998, *Computing vertex normals from polygonal
facets* (angle-weighted normals).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .._validate import as_float_array
from ..errors import MeshTopologyError, ParameterError
from . import _rows

__all__ = [
    "triangulate",
    "check_dimension",
    "face_vector_areas",
    "face_areas",
    "face_normals",
    "vertex_normals",
    "cotangent_laplacian",
    "mixed_areas",
    "mean_curvature_normal",
    "mean_curvature",
    "angle_defects",
    "gaussian_curvature",
    "total_area",
    "volume",
]


# -- helpers ----------------------------------------------------------------------------------
def _fan_corners(topology):
    """Corner (half-edge) indices ``(T, 3)`` of the fan triangles and their faces ``(T,)``."""
    sizes = topology.face_sizes
    n_tri = np.maximum(sizes - 2, 0)
    tri_face = np.repeat(np.arange(topology.n_faces, dtype=np.int64), n_tri)
    first_tri = np.concatenate([[0], np.cumsum(n_tri)]).astype(np.int64)
    j = np.arange(tri_face.size, dtype=np.int64) - first_tri[tri_face] + 1  # 1 .. k-2
    base = topology.face_offsets[:-1][tri_face]
    corners = np.stack([base, base + j, base + j + 1], axis=1) if tri_face.size else np.zeros((0, 3), np.int64)
    return corners, tri_face


def triangulate(topology):
    """Fan triangulation of a polygon mesh.

    Each face ``(v0, v1, ..., v_{k-1})`` becomes the ``k - 2`` triangles
    ``(v0, v_j, v_{j+1})`` for ``j = 1 .. k-2`` (a fan from the face's first
    corner), which keeps the face's orientation. Triangles appear face after
    face, so a triangle mesh is returned unchanged.

    Parameters
    ----------
    topology : :class:`~splinekit.mesh.topology.Topology` or PolyMesh

    Returns
    -------
    triangles : (T, 3) int64 array
        Vertex indices, ``T = sum(face_sizes - 2)``.
    triangle_face : (T,) int64 array
        The original face of each triangle.
    """
    topology = getattr(topology, "topology", topology)
    if topology.is_uniform and topology.face_indices.size == 3 * topology.n_faces:  # triangles
        return topology.face_indices.reshape(-1, 3).copy(), np.arange(topology.n_faces, dtype=np.int64)
    corners, tri_face = _fan_corners(topology)
    return topology.face_indices[corners], tri_face


def check_dimension(mesh, what: str, need_3d: bool = False) -> None:
    """Raise :class:`~splinekit.errors.ParameterError` unless ``mesh.vertices`` fit ``what``.

    ``need_3d``: exactly 3 coordinates; otherwise at least 2.
    """
    shape = np.shape(mesh.vertices)
    dim = shape[1] if len(shape) == 2 else -1
    if need_3d and dim != 3:
        raise ParameterError(f"{what} needs 3-D vertices, got vertices of shape {shape}")
    if dim < 2:
        raise ParameterError(f"{what} needs vertices of dimension >= 2, got vertices of shape {shape}")


def _scaled_vertices(mesh, what: str, need_3d: bool = False):
    """``(U, e)``: vertices scaled by ``2**-e`` (exact) and centred; checks the dimension."""
    check_dimension(mesh, what, need_3d)
    V = np.asarray(mesh.vertices, dtype=np.float64)
    if V.size == 0:
        return V.copy(), 0
    m = float(np.max(np.abs(V)))
    e = int(np.frexp(m)[1]) if m > 0 else 0  # m = f * 2**e, 0.5 <= f < 1
    U = np.ldexp(V, -e)  # centred below by columns (min/max along axis 0 of (n, 3) is 20x slower)
    U = U - np.array([U[:, c].min() + U[:, c].max() for c in range(U.shape[1])]) * 0.5
    return U, e


def _given(value, shape, name):
    """A caller's precomputed array, checked: float64 of ``shape``, finite."""
    arr = as_float_array(value, name)
    if arr.shape != shape:
        raise ParameterError(f"{name} must have shape {shape} for this mesh, got {arr.shape}")
    if not np.isfinite(arr).all():
        raise ParameterError(f"{name} holds non-finite values")
    return arr


def _given_laplacian(value, n):
    if value is None:
        return None
    if sp.issparse(value):
        if value.shape != (n, n):
            raise ParameterError(f"laplacian must have shape {(n, n)} for this mesh, got {value.shape}")
        return value
    return _given(value, (n, n), "laplacian")


def _unscale(x, e: int, power: int, what: str, item: str):
    """``x * 2**(power * e)``: a quantity of dimension length**power back in mesh units.

    A result beyond the float range raises, naming the ``item`` index.
    """
    with np.errstate(over="ignore"):
        y = np.ldexp(x, power * e)
    if not np.isfinite(y).all():
        where = np.argwhere(~np.isfinite(np.atleast_1d(y)))[0]
        at = f" at {item} {int(where[0])}" if item else ""
        why = "the coordinates are too large" if e > 0 else "the mesh is too small"
        raise MeshTopologyError(f"{what}{at} overflows the float range ({why})")
    return y


def _triangle_geometry(U, tris):
    """Per-triangle quantities in the (scaled) coordinates ``U``.

    Returns ``(double_area (T,), dot (T, 3), cot (T, 3), angle (T, 3), l2 (T, 3))``:
    for corner ``k`` with ``u = x[k+1] - x[k]`` and ``v = x[k+2] - x[k]``, ``dot = u.v``,
    ``angle`` is the interior angle at ``k``, ``cot`` its cotangent (0 for a
    zero-area triangle), and ``l2[:, k] = |u|²`` (the squared length of edge
    ``k -> k+1``).
    """
    X = [U[tris[:, k]].T for k in range(3)]  # corner k, by component: (d, T)
    E = [X[(k + 1) % 3] - X[k] for k in range(3)]  # edge k runs from corner k to k + 1
    l2 = np.stack([_rows.dot(E[k], E[k]) for k in range(3)], axis=1)
    dot = np.stack([-_rows.dot(E[k], E[(k + 2) % 3]) for k in range(3)], axis=1)
    # twice the area, from the two edges beside the longest one (the largest angle):
    # there |u||v| is smallest, and so is the rounding error of u x v
    longest = np.argmax(l2, axis=1) if len(tris) else np.zeros(0, dtype=np.int64)
    a = np.where(longest == 0, E[1], np.where(longest == 1, E[2], E[0]))
    b = np.where(longest == 0, E[2], np.where(longest == 1, E[0], E[1]))
    double_area = _rows.cross_norm(a, b)
    da = double_area[:, None]
    cot = np.divide(dot, da, out=np.zeros_like(dot), where=da > 0)
    angle = np.arctan2(np.broadcast_to(da, dot.shape), dot)
    return double_area, dot, cot, angle, l2


class _Geometry:
    """Scaled coordinates of one mesh and the quantities derived from them, each computed once.

    Everything here is in the scaled units of ``U = (vertices * 2**-e) - centre``.
    """

    def __init__(self, mesh, what: str, need_3d: bool = False):
        self.U, self.e = _scaled_vertices(mesh, what, need_3d)
        self.topology = mesh.topology
        self.tris, self.tri_face = triangulate(self.topology)

    @cached_property
    def tri(self):
        return _triangle_geometry(self.U, self.tris)

    @cached_property
    def face_vector_areas(self):
        """``(F, 3)`` vector areas (3-D only)."""
        tri_vec = np.empty((len(self.tris), 3))
        # by chunks of rows (the gathered corners stay in cache), into contiguous (t, 3) rows
        for s in range(0, len(self.tris), _rows.CHUNK):
            P = self.U[self.tris[s:s + _rows.CHUNK]]  # (t, 3 corners, 3 coordinates)
            _rows.cross_rows(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0], out=tri_vec[s:s + _rows.CHUNK])
        tri_vec *= 0.5
        if len(self.tri_face) == self.topology.n_faces:  # all triangles: no per-face sum
            return tri_vec
        return _rows.per_vertex(self.tri_face, tri_vec.T, self.topology.n_faces)

    @cached_property
    def face_normals(self):
        return _rows.normalize_rows(self.face_vector_areas)

    @cached_property
    def corner_angles(self):
        """Interior angle ``(H,)`` of every polygon corner (in [0, pi]), from its two face edges."""
        t = self.topology
        x = self.U[t.face_indices].T  # (d, H)
        u = x[:, t.next_corner] - x
        v = x[:, t.prev_corner] - x
        return np.arctan2(_rows.cross_norm(u, v), _rows.dot(u, v))

    def vertex_normals(self, face_normals=None):
        t = self.topology
        fn = self.face_normals if face_normals is None else _given(face_normals, (t.n_faces, 3), "face_normals")
        weighted = fn[t.corner_face].T * self.corner_angles
        return _rows.normalize_rows(_rows.per_vertex(t.face_indices, weighted, t.n_vertices))

    @cached_property
    def laplacian(self):
        n = self.topology.n_vertices
        tris = self.tris
        # the edge opposite corner k joins corners k+1 and k+2
        a = tris[:, [1, 2, 0]].ravel()
        b = tris[:, [2, 0, 1]].ravel()
        w = 0.5 * self.tri[2].ravel()
        W = sp.coo_matrix((w, (np.minimum(a, b), np.maximum(a, b))), shape=(n, n)).tocsr()
        W = W + W.T  # upper and lower parts do not overlap: exactly symmetric
        d = np.asarray(W.sum(axis=1)).ravel()
        L = (sp.diags(d, format="csr") - W).tocsr()
        L.sort_indices()
        return L

    @cached_property
    def mixed_areas(self):
        double_area, dot, cot, _, l2 = self.tri
        area = 0.5 * double_area
        # corner k: |x_k x_{k+1}|² cot(angle k+2) + |x_k x_{k+2}|² cot(angle k+1)
        voronoi = (l2 * np.roll(cot, -2, axis=1) + np.roll(l2, -2, axis=1) * np.roll(cot, -1, axis=1)) / 8.0
        obtuse = dot < 0
        part = np.where(
            obtuse.any(axis=1, keepdims=True), np.where(obtuse, 0.5, 0.25) * area[:, None], voronoi
        )
        return _rows.per_vertex(self.tris.ravel(), part.ravel(), self.topology.n_vertices)

    @cached_property
    def angle_sums(self):
        return _rows.per_vertex(self.tris.ravel(), self.tri[3].ravel(), self.topology.n_vertices)

    def mean_curvature_normal(self, laplacian=None):
        L = _given_laplacian(laplacian, self.topology.n_vertices)
        L = self.laplacian if L is None else L
        A = self.mixed_areas
        LU = np.asarray(L @ self.U)
        ok = ((A > 0) & ~self.topology.boundary_vertices)[:, None]
        return np.divide(LU, 2.0 * A[:, None], out=np.zeros_like(LU), where=ok)


# -- faces ------------------------------------------------------------------------------------
def face_vector_areas(mesh) -> np.ndarray:
    """Vector area of every face ``(F, 3)`` (length²), 3-D only.

    The sum of the fan triangles' area vectors ``(x_j - x_0) x (x_{j+1} - x_0) / 2``;
    for any polygon this equals ``1/2 sum_i x_i x x_{i+1}``, independent of the
    fan apex. Its length is the area of a planar face; its direction is the
    face normal.
    """
    g = _Geometry(mesh, "face vector areas", need_3d=True)
    return _unscale(g.face_vector_areas, g.e, 2, "the vector area", "face")


def face_areas(mesh) -> np.ndarray:
    """Area of every face ``(F,)`` (length²), any dimension >= 2.

    The sum of the areas of the face's fan triangles (fan from the first
    corner). For a planar convex polygon this is its area; for a non-planar
    one it is the area of that particular triangulation (at least the length
    of :func:`face_vector_areas`). Summed over faces it equals the sum of
    :func:`mixed_areas` over vertices.
    """
    g = _Geometry(mesh, "face areas")
    return _unscale(_rows.per_vertex(g.tri_face, 0.5 * g.tri[0], g.topology.n_faces), g.e, 2, "the area", "face")


def total_area(mesh) -> float:
    """Total surface area (length²): the sum of :func:`face_areas`."""
    g = _Geometry(mesh, "the total area")
    return float(_unscale(0.5 * g.tri[0].sum(), g.e, 2, "the total area", ""))


def face_normals(mesh) -> np.ndarray:
    """Unit normal of every face ``(F, 3)``, 3-D only.

    The normalized vector area (:func:`face_vector_areas`): for a triangle the
    direction of ``(x1 - x0) x (x2 - x0)``, for a polygon the normalized sum
    of its fan triangles' area vectors (a best-fit normal of a non-planar
    face). A face that is counter-clockwise seen by the viewer points toward
    the viewer. A face of zero vector area gets the zero vector, never NaN.
    """
    return _Geometry(mesh, "face normals", need_3d=True).face_normals


# -- vertices ---------------------------------------------------------------------------------
def vertex_normals(mesh, face_normals=None) -> np.ndarray:
    """Angle-weighted unit vertex normals ``(V, 3)`` (Thürmer & Wüthrich 1998), 3-D only.

    ``n_v = normalize(sum_f theta_{f,v} n_f)`` over the faces ``f`` around ``v``,
    where ``n_f`` is the :func:`face_normals` normal (for a polygon, its
    normalized vector area) and ``theta_{f,v}`` the interior angle of polygon
    ``f`` at ``v`` (between its two edges at ``v``, in ``[0, pi]``; a reflex
    corner of a non-convex polygon counts with its convex angle). For planar
    faces the result does not depend on how they are subdivided. Isolated
    vertices, and vertices whose weighted sum vanishes, get zeros.

    ``face_normals`` : optional precomputed ``(F, 3)`` face normals of the same mesh.
    """
    return _Geometry(mesh, "vertex normals", need_3d=True).vertex_normals(face_normals)


def cotangent_laplacian(mesh) -> sp.csr_matrix:
    """Cotangent Laplacian ``L`` ``(V, V)`` as scipy CSR, any dimension >= 2.

    Positive semi-definite convention: for ``i != j``,
    ``L[i, j] = -w_ij`` with ``w_ij = (cot alpha_ij + cot beta_ij) / 2`` (the
    angles opposite edge ``ij`` in its one or two triangles; one term on a
    boundary edge), and ``L[i, i] = sum_j w_ij``. So ``L`` is exactly
    symmetric, every row sums to zero (up to rounding), ``x^T L x >= 0`` is the
    Dirichlet energy of the piecewise-linear function ``x``, and
    ``(L @ X)[i] = sum_j w_ij (x_i - x_j)``. Dimensionless (the weights are
    scale invariant).

    It is built on the fan triangulation, so a polygon mesh also gets weights
    across the fan diagonals. Zero-area triangles contribute nothing; isolated
    vertices have an empty row (a stored zero on the diagonal).
    """
    return _Geometry(mesh, "the cotangent Laplacian").laplacian


def mixed_areas(mesh) -> np.ndarray:
    """Mixed Voronoi area of every vertex ``(V,)`` (length²), any dimension >= 2.

    Meyer, Desbrun, Schröder & Barr 2003 (Fig. 4), on the fan triangulation.
    Each triangle gives each of its corners ``k``:

    * if the triangle is not obtuse, the Voronoi area
      ``(|x_k x_{k+1}|² cot(angle_{k+2}) + |x_k x_{k+2}|² cot(angle_{k+1})) / 8``;
    * if it is obtuse, ``area / 2`` to the obtuse corner and ``area / 4`` to
      each of the other two.

    Right triangles count as not obtuse. The areas tile the surface:
    ``sum(mixed_areas) == sum(face_areas)`` (up to rounding). Isolated vertices
    get 0.
    """
    g = _Geometry(mesh, "mixed areas")
    return _unscale(g.mixed_areas, g.e, 2, "the mixed area", "vertex")


# -- curvature --------------------------------------------------------------------------------
def mean_curvature_normal(mesh, *, laplacian=None) -> np.ndarray:
    """Mean-curvature normal ``H n`` per vertex ``(V, dim)`` (1/length), any dimension >= 2.

    ``H n = (L @ X) / (2 A_mixed)`` with the PSD :func:`cotangent_laplacian`
    ``L`` and :func:`mixed_areas` (Meyer et al. 2003, eq. 8, whose
    ``K(x_i) = -2 H n``). For a sphere of radius R with outward-facing faces it
    points outward with length about 1/R. Boundary vertices (where ``L @ X``
    measures the boundary, not the curvature), isolated vertices and vertices
    of zero mixed area get zeros.

    ``laplacian`` : optional precomputed :func:`cotangent_laplacian` of the same
    mesh (it is scale invariant; the areas are always recomputed in scaled
    coordinates, so that they cannot overflow or underflow on the way).
    """
    g = _Geometry(mesh, "the mean-curvature normal")
    return _unscale(g.mean_curvature_normal(laplacian), g.e, -1, "the mean-curvature normal", "vertex")


def mean_curvature(mesh, *, laplacian=None, normals=None) -> np.ndarray:
    """Signed mean curvature ``H = (k1 + k2) / 2`` per vertex ``(V,)`` (1/length), 3-D only.

    ``|H| = |L @ X| / (2 A_mixed)`` (the cotangent formula on the fan
    triangulation, see :func:`mean_curvature_normal`), signed against
    ``n``, the :func:`vertex_normals` normal. **Sign convention** (the one of
    :func:`splinekit.curvature` and OpenCascade, for every representation):
    positive where the surface bends toward its normal, so ``H = -1/R`` on a
    sphere of radius R with outward normals (faces counter-clockwise seen
    from outside); reversing the face orientation flips the sign. Boundary
    vertices, isolated vertices and vertices of zero mixed area get 0.

    ``laplacian`` / ``normals`` : optional precomputed :func:`cotangent_laplacian`
    and :func:`vertex_normals` of the same mesh.
    """
    g = _Geometry(mesh, "mean curvature", need_3d=True)
    Hn = g.mean_curvature_normal(laplacian)
    n = g.vertex_normals() if normals is None else _given(normals, (g.topology.n_vertices, 3), "normals")
    # L @ X points away from the centre of curvature (outward on a sphere)
    sign = np.where(np.einsum("vd,vd->v", Hn, n) > 0, -1.0, 1.0)
    return _unscale(sign * np.sqrt(np.einsum("vd,vd->v", Hn, Hn)), g.e, -1, "the mean curvature", "vertex")


def angle_defects(mesh) -> np.ndarray:
    """Discrete angle defect per vertex ``(V,)`` (radians), any dimension >= 2.

    ``2 pi - sum(angles)`` at interior (and isolated) vertices and
    ``pi - sum(angles)`` at boundary vertices (the boundary's turning angle),
    with the angles of the fan triangles at the vertex. Discrete Gauss-Bonnet:
    ``angle_defects(mesh).sum() == 2 pi * euler_characteristic`` up to
    rounding, for any mesh whose boundary vertices each have two boundary
    edges (triangles with coincident vertices can break it).
    """
    g = _Geometry(mesh, "angle defects")
    full = np.where(g.topology.boundary_vertices, np.pi, 2.0 * np.pi)
    return full - g.angle_sums


def gaussian_curvature(mesh) -> np.ndarray:
    """Gaussian curvature ``K = k1 k2`` per vertex ``(V,)`` (1/length²), any dimension >= 2.

    ``K = (2 pi - sum(angles)) / A_mixed`` at interior vertices (Meyer et al.
    2003: the angle defect over :func:`mixed_areas`, with fan-triangle angles).
    **Boundary vertices get 0**: there the angle sum measures the boundary's
    geodesic turning, not the Gaussian curvature (that part is kept in
    :func:`angle_defects`). Isolated vertices and vertices of zero mixed area
    also get 0; the result is never NaN. For a closed mesh, discrete
    Gauss-Bonnet: ``sum(K * mixed_areas) == 2 pi * euler_characteristic``.
    """
    g = _Geometry(mesh, "Gaussian curvature")
    A = g.mixed_areas
    defect = 2.0 * np.pi - g.angle_sums
    ok = (A > 0) & ~g.topology.boundary_vertices
    K = np.divide(defect, A, out=np.zeros_like(defect), where=ok)
    return _unscale(K, g.e, -2, "the Gaussian curvature", "vertex")


# -- solids -----------------------------------------------------------------------------------
def volume(mesh) -> float:
    """Signed enclosed volume (length³) of a closed 3-D mesh (divergence theorem).

    ``sum over fan triangles of det(x0, x1, x2) / 6``, computed about the
    bounding-box centre. Positive when the faces are counter-clockwise seen
    from outside (normals outward), negative for the reverse orientation.
    Raises :class:`~splinekit.errors.MeshTopologyError` naming a boundary edge
    if the mesh is open (or has no faces), and
    :class:`~splinekit.errors.ParameterError` for non-3-D vertices.
    """
    g = _Geometry(mesh, "volume", need_3d=True)
    topo = g.topology
    if topo.n_faces == 0:
        raise MeshTopologyError("volume needs a closed mesh; this mesh has no faces")
    if topo.boundary_edges.any():
        edge = topo.edges[np.flatnonzero(topo.boundary_edges)[0]]
        raise MeshTopologyError(
            f"volume needs a closed mesh; edge {tuple(int(v) for v in edge)} is on the boundary "
            f"({int(topo.boundary_edges.sum())} boundary edges)"
        )
    X = [g.U[g.tris[:, k]].T for k in range(3)]
    det = _rows.dot(X[0], _rows.cross(X[1], X[2]))
    return float(_unscale(det.sum() / 6.0, g.e, 3, "the volume", ""))
