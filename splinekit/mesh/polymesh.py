"""PolyMesh: vertex coordinates plus a :class:`~splinekit.mesh.topology.Topology`.

Topology (integers) and geometry (coordinates) are kept apart, as in
OpenSubdiv: subdivision refines the topology once and moves any per-vertex
data with a sparse stencil matrix. Derived quantities are cached; both arrays
are read-only, so a cache never goes stale.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from .. import limits
from .._validate import as_float_array
from ..errors import MeshTopologyError
from . import geometry
from .topology import Topology

__all__ = ["BYTES_PER_CORNER", "PolyMesh", "as_face_arrays", "check_mesh_size"]

BYTES_PER_CORNER = 160
"""Peak memory per face corner of building a PolyMesh (faces, the checked topology
with its half-edges and edges, vertices): measured 130 bytes for an icosphere
and for a quad torus of about a million faces, with a margin."""


def check_mesh_size(n_faces, corners_per_face, what: str) -> None:
    """Refuse (:func:`splinekit.limits.check`) a mesh of ``n_faces`` faces of
    ``corners_per_face`` corners before its arrays exist. Counts may be floats
    (an estimate, possibly ``inf``)."""
    limits.check(float(n_faces) * corners_per_face * BYTES_PER_CORNER, f"{what} ({float(n_faces):,.0f} faces)")


def as_face_arrays(faces) -> tuple[np.ndarray, np.ndarray]:
    """Faces as ``(flat indices, offsets)``.

    Accepts an ``(F, k)`` integer array (or nested lists of equal length) or a
    sequence of per-face index sequences of any lengths.
    """
    try:
        arr = np.asarray(faces)
    except ValueError:  # ragged nested lists
        arr = None
    if arr is not None and arr.dtype != object and arr.ndim == 2:
        # before any copy: the flat indices, and the topology built from them, scale with arr.size
        limits.check(arr.size * BYTES_PER_CORNER, f"a mesh of {arr.shape[0]:,} faces")
        if arr.dtype.kind == "u" and arr.size and arr.max() > np.iinfo(np.int64).max:
            raise MeshTopologyError(f"face index {int(arr.max())} is too large for a vertex index")
        if arr.size and arr.dtype.kind not in "iu":
            if arr.dtype.kind == "f" and np.array_equal(arr, np.round(arr)) and np.isfinite(arr).all():
                arr = arr.astype(np.int64)
            else:
                raise MeshTopologyError(f"faces must hold integer vertex indices, got dtype {arr.dtype}")
        arr = arr.astype(np.int64, copy=False)
        F, k = arr.shape
        return arr.ravel(), np.arange(F + 1, dtype=np.int64) * k
    if arr is not None and arr.dtype != object and arr.ndim == 1 and arr.size == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(1, dtype=np.int64)
    try:
        items = list(faces)
    except TypeError:
        raise MeshTopologyError(f"faces must be an (F, k) array or a sequence of index sequences, got {type(faces).__name__}") from None
    parts = []
    for f, face in enumerate(items):
        try:
            a = np.asarray(face)
        except ValueError:
            raise MeshTopologyError(f"face {f} is not a flat sequence of vertex indices") from None
        if a.ndim != 1:
            raise MeshTopologyError(f"face {f} must be a 1-D sequence of vertex indices, got shape {a.shape}")
        if a.size and a.dtype.kind not in "iu":
            raise MeshTopologyError(f"face {f} holds non-integer vertex indices (dtype {a.dtype})")
        parts.append(a.astype(np.int64, copy=False))
    sizes = np.array([p.size for p in parts], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    flat = np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)
    return flat, offsets


class PolyMesh:
    """A polygon mesh with faces of any valence.

    Parameters
    ----------
    vertices : array_like, shape (n, dim)
        Vertex coordinates (usually ``dim = 3``), finite.
    faces : (F, k) int array, or a sequence of per-face index sequences
        Counter-clockwise seen from outside (consistently oriented).

    Attributes
    ----------
    vertices : (n, dim) float64, read-only
    faces : (F, k) int array when every face has k sides, else a list of arrays
    face_indices, face_offsets : the flat CSR form of the faces
    topology : :class:`~splinekit.mesh.topology.Topology`
    """

    __slots__ = ("_vertices", "topology", "__dict__")

    def __init__(self, vertices, faces):
        V = as_float_array(vertices, "vertices", MeshTopologyError)
        if V.ndim != 2 or V.shape[1] < 1:
            raise MeshTopologyError(f"vertices must have shape (n, dim), got {V.shape}")
        bad = ~np.isfinite(V).all(axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise MeshTopologyError(f"vertex {i} has non-finite coordinates {V[i].tolist()}")
        flat, offsets = as_face_arrays(faces)
        # the topology costs ~20x the flat indices: refused before it is built
        limits.check(flat.size * BYTES_PER_CORNER, f"a mesh of {offsets.size - 1:,} faces")
        self._init(V, Topology(len(V), flat, offsets, check=True))

    def _init(self, vertices, topology):
        V = np.array(vertices, dtype=np.float64, order="C", copy=True)
        V.setflags(write=False)
        object.__setattr__(self, "_vertices", V)
        object.__setattr__(self, "topology", topology)

    @classmethod
    def from_topology(cls, vertices, topology: Topology):
        """A mesh from already-checked connectivity (no validation)."""
        obj = object.__new__(cls)
        obj._init(vertices, topology)
        return obj

    @classmethod
    def _adopt(cls, vertices: np.ndarray, topology: Topology):
        """Like :meth:`from_topology`, but takes ownership of ``vertices`` (a fresh float64 array
        nobody else holds) instead of copying it; the array becomes read-only."""
        V = np.ascontiguousarray(vertices, dtype=np.float64)
        V.setflags(write=False)
        obj = object.__new__(cls)
        object.__setattr__(obj, "_vertices", V)
        object.__setattr__(obj, "topology", topology)
        return obj

    def with_vertices(self, vertices):
        """The same connectivity with new coordinates ``(n, dim)`` (checked)."""
        V = as_float_array(vertices, "vertices", MeshTopologyError)
        if V.ndim != 2 or V.shape[0] != self.topology.n_vertices or V.shape[1] < 1:
            raise MeshTopologyError(f"expected vertices of shape ({self.topology.n_vertices}, dim), got {V.shape}")
        if not np.isfinite(V).all():
            i = int(np.flatnonzero(~np.isfinite(V).all(axis=1))[0])
            raise MeshTopologyError(f"vertex {i} has non-finite coordinates")
        return PolyMesh.from_topology(V, self.topology)

    def __setattr__(self, name, value):
        raise AttributeError("PolyMesh is immutable; operations return new meshes")

    def __reduce__(self):  # pickling and copy rebuild (and re-check) from the flat arrays
        t = self.topology
        return (_from_flat, (np.array(self._vertices), np.array(t.face_indices), np.array(t.face_offsets)))

    def __repr__(self):
        t = self.topology
        kind = "empty" if not t.n_faces else f"{int(t.face_sizes[0])}-gons" if t.is_uniform else "mixed faces"
        return (
            f"PolyMesh(vertices={t.n_vertices}, faces={t.n_faces} ({kind}), edges={t.n_edges}, "
            f"{'closed' if t.is_closed else 'open'}, euler={t.euler_characteristic})"
        )

    def __eq__(self, other):
        if not isinstance(other, PolyMesh):
            return NotImplemented
        a, b = self.topology, other.topology
        return (
            self._vertices.shape == other._vertices.shape
            and np.array_equal(a.face_offsets, b.face_offsets)
            and np.array_equal(a.face_indices, b.face_indices)
            and bool(np.array_equal(self._vertices, other._vertices))
        )

    __hash__ = None

    # -- data -------------------------------------------------------------------------------
    @property
    def vertices(self) -> np.ndarray:
        """``(n, dim)`` vertex coordinates (read-only)."""
        return self._vertices

    @property
    def face_indices(self) -> np.ndarray:
        return self.topology.face_indices

    @property
    def face_offsets(self) -> np.ndarray:
        return self.topology.face_offsets

    @cached_property
    def faces(self):
        """``(F, k)`` int array when all faces have k sides, else a list of index arrays."""
        t = self.topology
        if t.is_uniform:
            k = int(t.face_offsets[1] - t.face_offsets[0]) if t.n_faces else 3
            out = t.face_indices.reshape(t.n_faces, k)
            out.setflags(write=False)
            return out
        return np.split(t.face_indices, t.face_offsets[1:-1])

    @property
    def n_vertices(self) -> int:
        return self.topology.n_vertices

    @property
    def n_faces(self) -> int:
        return self.topology.n_faces

    @property
    def edges(self) -> np.ndarray:
        """``(E, 2)`` undirected edges."""
        return self.topology.edges

    @property
    def is_closed(self) -> bool:
        return self.topology.is_closed

    @property
    def euler_characteristic(self) -> int:
        return self.topology.euler_characteristic

    @property
    def valence(self) -> np.ndarray:
        return self.topology.valence

    @property
    def boundary_edges(self) -> np.ndarray:
        return self.topology.boundary_edges

    @property
    def boundary_vertices(self) -> np.ndarray:
        return self.topology.boundary_vertices

    @property
    def is_triangle_mesh(self) -> bool:
        t = self.topology
        return t.n_faces > 0 and bool((t.face_sizes == 3).all())

    @property
    def is_quad_mesh(self) -> bool:
        t = self.topology
        return t.n_faces > 0 and bool((t.face_sizes == 4).all())

    def derived(self, key: str, make):
        """``make(self)``, computed on the first call for ``key`` and kept with the mesh.

        For values that modules in lower layers derive from a mesh and would otherwise rebuild
        on every call (the manifold3d object of :mod:`splinekit.interop.booleans`). Safe because
        a mesh is immutable (read-only arrays, no attribute assignment); a value is dropped with
        its mesh, and pickling or copying a mesh does not carry it. ``make`` raising caches nothing.
        """
        cache = self.__dict__.setdefault("_derived", {})
        if key not in cache:
            cache[key] = make(self)
        return cache[key]

    # -- geometry (splinekit.mesh.geometry), cached; arrays are read-only -----------------
    # Polygons are fan-triangulated from each face's first corner; see geometry.py for
    # units, sign conventions and degenerate cases. Normals, mean curvature and volume
    # need 3-D vertices (ParameterError otherwise).
    @staticmethod
    def _readonly(a: np.ndarray) -> np.ndarray:
        a.setflags(write=False)
        return a

    @cached_property
    def face_areas(self) -> np.ndarray:
        """``(F,)`` face areas (sum of fan-triangle areas)."""
        return self._readonly(geometry.face_areas(self))

    @cached_property
    def area(self) -> float:
        """Total surface area."""
        return geometry.total_area(self)

    @cached_property
    def face_normals(self) -> np.ndarray:
        """``(F, 3)`` unit face normals (normalized vector area; zero for zero-area faces)."""
        return self._readonly(geometry.face_normals(self))

    @cached_property
    def vertex_normals(self) -> np.ndarray:
        """``(V, 3)`` angle-weighted unit vertex normals (zero at isolated vertices)."""
        geometry.check_dimension(self, "vertex normals", need_3d=True)
        return self._readonly(geometry.vertex_normals(self, face_normals=self.face_normals))

    @cached_property
    def cotangent_laplacian(self):
        """``(V, V)`` CSR cotangent Laplacian, positive semi-definite convention (read-only arrays)."""
        L = geometry.cotangent_laplacian(self)
        for a in (L.data, L.indices, L.indptr):
            a.setflags(write=False)
        return L

    @cached_property
    def mixed_areas(self) -> np.ndarray:
        """``(V,)`` mixed Voronoi areas (Meyer et al. 2003)."""
        return self._readonly(geometry.mixed_areas(self))

    @cached_property
    def mean_curvature_normal(self) -> np.ndarray:
        """``(V, dim)`` mean-curvature normal ``H n`` (zero on the boundary)."""
        geometry.check_dimension(self, "the mean-curvature normal")
        return self._readonly(geometry.mean_curvature_normal(self, laplacian=self.cotangent_laplacian))

    @cached_property
    def mean_curvature(self) -> np.ndarray:
        """``(V,)`` signed mean curvature, ``-1/R`` on a sphere with outward normals (the
        convention of :func:`splinekit.curvature` and OCC); 0 on the boundary."""
        geometry.check_dimension(self, "mean curvature", need_3d=True)
        return self._readonly(
            geometry.mean_curvature(self, laplacian=self.cotangent_laplacian, normals=self.vertex_normals)
        )

    @cached_property
    def gaussian_curvature(self) -> np.ndarray:
        """``(V,)`` angle-defect Gaussian curvature; 0 on the boundary."""
        return self._readonly(geometry.gaussian_curvature(self))

    @cached_property
    def volume(self) -> float:
        """Signed enclosed volume of a closed mesh (MeshTopologyError if open)."""
        return geometry.volume(self)


def _from_flat(vertices, face_indices, face_offsets) -> PolyMesh:
    return PolyMesh.from_topology(vertices, Topology(len(vertices), face_indices, face_offsets, check=True))
