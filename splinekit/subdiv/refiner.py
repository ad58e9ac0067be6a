"""Uniform refinement: topology refined once per level, geometry by sparse stencils.

As in OpenSubdiv's Far layer, :class:`Refinement` refines only the
connectivity (and the crease sharpness) and records, for every level, a sparse
matrix ``S_k`` with ``data_k = S_k @ data_(k-1)``. Positions, colours, uv or any
other per-vertex array are then refined by sparse products; the composed matrix
``S_L ... S_1`` maps the control vertices straight to the finest level.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .. import limits
from .._validate import as_float_array, as_int
from ..errors import MeshTopologyError, ParameterError
from ..mesh.polymesh import PolyMesh
from ..mesh.topology import Topology
from ..basis.jit import subdiv_kernels
from . import _compiled, catmull_clark, doo_sabin, loop
from .creases import CREASE_METHODS, chaikin_half_sharpness, child_sharpness, edge_sharpness, vertex_sharpness

__all__ = ["SCHEMES", "Refinement", "subdivide", "subdivision_matrix"]

SCHEMES = {"catmull-clark": catmull_clark, "loop": loop, "doo-sabin": doo_sabin}
MAX_LEVELS = 12
BYTES_PER_CORNER = 200
"""Peak memory per face corner of the finest level (topology, sharpness, vertices,
stencils when kept), measured at 0.4-1.3 million faces: 100-140 bytes for
Catmull-Clark, about 80 for Loop, 190 for Doo-Sabin; what the memory budget
(:mod:`splinekit.limits`) is given before anything is refined."""


def estimated_faces(topology: Topology, scheme: str, levels: int) -> int:
    """Faces after ``levels`` refinements (exact for Catmull-Clark and Loop)."""
    if levels == 0:
        return topology.n_faces
    if scheme == "catmull-clark":
        return topology.n_halfedges * 4 ** (levels - 1)
    if scheme == "loop":
        return topology.n_faces * 4**levels
    first = topology.n_faces + topology.n_edges + topology.n_vertices
    return first * 4 ** (levels - 1)


def _scheme(name):
    key = str(name).lower().replace("_", "-") if isinstance(name, str) else name
    aliases = {"catmark": "catmull-clark", "cc": "catmull-clark", "catmull clark": "catmull-clark"}
    key = aliases.get(key, key)
    if key not in SCHEMES:
        raise ParameterError(f"scheme must be one of {sorted(SCHEMES)}, got {name!r}")
    return key


class Refinement:
    """A mesh's topology refined ``levels`` times by one scheme.

    Parameters
    ----------
    mesh : PolyMesh or Topology
    scheme : ``"catmull-clark"``, ``"loop"`` or ``"doo-sabin"``
    levels : int, 0..12
    creases : edge sharpness, see :func:`splinekit.subdiv.creases.edge_sharpness`
    corners : vertex sharpness, ``{vertex: sharpness}`` or ``(V,)``
    boundary : ``"edge-and-corner"`` (default; boundary corners with one face
        are interpolated) or ``"edge-only"`` (Catmull-Clark and Loop; Doo-Sabin
        always keeps a corner between two boundary edges in place)
    crease_method : ``"uniform"`` (default: sharpness decreases by one per level)
        or ``"chaikin"`` (semi-sharp sharpness is averaged along the crease first,
        OpenSubdiv's ``CREASE_CHAIKIN``; Catmull-Clark and Loop)
    keep_levels : bool
        Keep every level's topology, stencil and sharpness (default). With
        ``False`` only the input and the finest level are kept, no stencil
        is stored (:meth:`apply` and :attr:`matrix` are unavailable) and,
        when ``mesh`` is a PolyMesh, its vertices are refined level by level
        into :attr:`vertices`; this is what :func:`subdivide` uses, and it
        needs far less memory.

    Attributes
    ----------
    topologies : list of Topology, ``levels + 1`` entries (the input first);
        ``[input, finest]`` with ``keep_levels=False``
    stencils : list of CSR matrices; ``stencils[k]`` maps level k to level k + 1
        (empty with ``keep_levels=False``)
    edge_sharpness : list of per-edge sharpness arrays, one per level (input and
        finest with ``keep_levels=False``; likewise ``vertex_sharpness``)
    vertices : refined vertices of a PolyMesh input with ``keep_levels=False``, else None

    Large Catmull-Clark and Loop levels are built by compiled kernels
    (:mod:`splinekit.subdiv._compiled`): the same topologies and sharpness,
    stencils equal to rounding (1e-15); ``SPLINEKIT_NUMBA=0`` forces the numpy
    path.
    """

    def __init__(self, mesh, scheme: str, levels: int = 1, creases=None, corners=None, boundary: str = "edge-and-corner",
                 keep_levels: bool = True, crease_method: str = "uniform"):
        self.scheme = _scheme(scheme)
        if crease_method not in CREASE_METHODS:
            raise ParameterError(f"crease_method must be one of {CREASE_METHODS}, got {crease_method!r}")
        if crease_method == "chaikin" and self.scheme == "doo-sabin":
            raise ParameterError("crease_method='chaikin' applies to catmull-clark and loop (edges split in halves)")
        self.crease_method = crease_method
        levels = as_int(levels, "levels", minimum=0)
        if levels > MAX_LEVELS:
            raise ParameterError(f"levels = {levels} is more than {MAX_LEVELS} (faces grow 4x per level)")
        topo = mesh.topology if isinstance(mesh, PolyMesh) else mesh
        if not isinstance(topo, Topology):
            raise ParameterError(f"expected a PolyMesh or Topology, got {type(mesh).__name__}")
        if topo.n_faces == 0:
            raise MeshTopologyError("the mesh has no faces to subdivide")
        expected = estimated_faces(topo, self.scheme, levels)
        sides = 3 if self.scheme == "loop" else 4  # of every face after the first level
        limits.check(expected * sides * BYTES_PER_CORNER,
                     f"{levels} levels of {self.scheme} subdivision ({expected:,} faces)")
        if self.scheme == "loop" and not (topo.face_sizes == 3).all():
            f = int(np.flatnonzero(topo.face_sizes != 3)[0])
            raise MeshTopologyError(f"Loop subdivision needs triangles; face {f} has {int(topo.face_sizes[f])} vertices")
        module = SCHEMES[self.scheme]
        edge_s = edge_sharpness(topo, creases)
        vertex_s = vertex_sharpness(topo, corners, boundary)
        self.boundary = boundary
        self.keep_levels = keep = bool(keep_levels)
        self.topologies = [topo]
        self.stencils = []
        self.edge_sharpness = [edge_s]
        self.vertex_sharpness = [vertex_s]
        self._levels = levels
        self.vertices = None
        X = None
        if not keep and isinstance(mesh, PolyMesh):
            X = mesh.vertices.reshape(topo.n_vertices, -1)
        for level in range(levels):
            halves = None
            if crease_method == "chaikin":
                semi = (edge_s > 0) & np.isfinite(edge_s)
                if semi.any():
                    halves = chaikin_half_sharpness(topo, edge_s)
            K = None
            if self.scheme in ("catmull-clark", "loop"):
                K = subdiv_kernels(_compiled.child_face_count(self.scheme, topo))
            if K is not None:
                # compiled: S only when kept, S @ X without S, the finest level's edges on first use
                step = _compiled.Level(K, self.scheme, topo, edge_s, vertex_s)
                topo = None  # unless kept, the parent goes as soon as the step has what it needs
                S = step.stencil() if keep else None
                if X is not None:
                    X = step.apply(X)
                step.release_rows()
                topo = step.child(lazy=level == levels - 1)
                n_inner = step.n_inner_edges
                del step
                # rebinding lets the parent's sharpness go (unless kept) before the next array
                edge_s = child_edge_s = _compiled.child_edge_sharpness(edge_s, n_inner)
                vertex_s = child_vertex_s = _compiled.child_vertex_sharpness(vertex_s, topo.n_vertices)
            else:
                refine = getattr(module, "refine_numpy", module.refine)
                child, S, pairs, parent_s, child_vertex_s = refine(topo, edge_s, vertex_s)
                child_edge_s = np.zeros(child.n_edges)
                if len(pairs):
                    child_edge_s[child.find_edges(pairs)] = child_sharpness(parent_s)
                child_edge_s[child.boundary_edges] = np.inf
                if X is not None:
                    X = S @ X
                topo = child
            if halves is not None:
                # both paths number the child halves of parent edge e as 2e, 2e + 1
                child_edge_s = child_edge_s.copy()
                child_edge_s[: halves.size] = halves
            edge_s, vertex_s = child_edge_s, child_vertex_s
            if keep:
                self.topologies.append(topo)
                self.stencils.append(S)
                self.edge_sharpness.append(edge_s)
                self.vertex_sharpness.append(vertex_s)
            S = None
        if not keep:
            if levels:
                self.topologies.append(topo)
                self.edge_sharpness.append(edge_s)
                self.vertex_sharpness.append(vertex_s)
            if X is not None:
                self.vertices = X.reshape((X.shape[0],) + mesh.vertices.shape[1:])

    @property
    def levels(self) -> int:
        return self._levels

    def _require_stencils(self):
        if not self.keep_levels and self._levels:
            raise ParameterError("this Refinement was made with keep_levels=False: its stencils were not kept")

    @property
    def topology(self) -> Topology:
        """The finest level's connectivity."""
        return self.topologies[-1]

    @cached_property
    def matrix(self) -> sp.csr_matrix:
        """Composed ``(V_L, V_0)`` stencil ``S_L @ ... @ S_1``."""
        self._require_stencils()
        M = sp.identity(self.topologies[0].n_vertices, format="csr")
        for S in self.stencils:
            M = S @ M
        return sp.csr_matrix(M)

    def apply(self, data, composed: bool = False) -> np.ndarray:
        """Refine per-vertex ``data`` ``(V_0, ...)`` to the finest level.

        Level by level (cheapest for one array), or with the composed matrix
        when ``composed`` (cheapest when the same refinement serves many
        frames once :attr:`matrix` is built).
        """
        self._require_stencils()
        X = as_float_array(data, "data")
        n0 = self.topologies[0].n_vertices
        if X.ndim == 0 or X.shape[0] != n0:
            raise ParameterError(f"data must have {n0} rows (one per control vertex), got shape {X.shape}")
        flat = X.reshape(n0, -1)
        if composed:
            out = self.matrix @ flat
        else:
            out = flat
            for S in self.stencils:
                out = S @ out
        return np.asarray(out).reshape((out.shape[0],) + X.shape[1:])

    def mesh(self, vertices) -> PolyMesh:
        """The refined PolyMesh for control ``vertices``."""
        return PolyMesh.from_topology(self.apply(vertices), self.topology)


def subdivide(mesh: PolyMesh, scheme: str, levels: int = 1, creases=None, corners=None, boundary: str = "edge-and-corner",
              crease_method: str = "uniform") -> PolyMesh:
    """Subdivide ``mesh`` ``levels`` times; see :class:`Refinement` for the arguments."""
    if not isinstance(mesh, PolyMesh):
        raise ParameterError(f"subdivide expects a PolyMesh, got {type(mesh).__name__}")
    if levels == 0:
        return Refinement(mesh, scheme, levels, creases, corners, boundary, crease_method=crease_method).mesh(mesh.vertices)
    # refine the vertices level by level and keep only the finest level: far less memory
    r = Refinement(mesh, scheme, levels, creases, corners, boundary, keep_levels=False, crease_method=crease_method)
    return PolyMesh._adopt(r.vertices, r.topology)


def subdivision_matrix(mesh, scheme: str, levels: int = 1, creases=None, corners=None, boundary: str = "edge-and-corner",
                       crease_method: str = "uniform"):
    """``(topology, S)``: the finest connectivity and the composed sparse stencil."""
    r = Refinement(mesh, scheme, levels, creases, corners, boundary, crease_method=crease_method)
    return r.topology, r.matrix
