"""Uniform refinement: topology refined once per level, geometry by sparse stencils.

As in OpenSubdiv's Far layer, :class:`Refinement` refines only the
connectivity (and the crease sharpness) and records, for every level, a sparse
matrix ``S_k`` with ``data_k = S_k @ data_(k-1)``. Positions, colours, uv or any
other per-vertex array are then refined by sparse products; the composed matrix
``S_L ... S_1`` maps the control vertices straight to the finest level.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .. import limits
from .._validate import as_float_array, as_int
from ..errors import MeshTopologyError, ParameterError
from ..mesh.polymesh import PolyMesh
from ..mesh.topology import Topology
from . import catmull_clark, doo_sabin, loop
from ._compiled import PreparedLevel
from .compose import compose
from .creases import CREASE_METHODS, chaikin_half_sharpness, edge_sharpness, vertex_sharpness
from .level import Level
from .scheme import Scheme

__all__ = ["SCHEMES", "Refinement", "scheme_named", "subdivide", "subdivision_matrix"]

SCHEMES: dict[str, Scheme] = {s.name: s for s in (catmull_clark.SCHEME, loop.SCHEME, doo_sabin.SCHEME)}
"""The schemes by name; each value is the scheme's :class:`~splinekit.subdiv.scheme.Scheme`."""
MAX_LEVELS = 12
BYTES_PER_CORNER = 200
"""Peak memory per face corner of the finest level (topology, sharpness, vertices,
stencils when kept), measured at 0.4-1.3 million faces: 100-140 bytes for
Catmull-Clark, about 80 for Loop, 190 for Doo-Sabin; what the memory budget
(:mod:`splinekit.limits`) is given before anything is refined."""


def estimated_faces(topology: Topology, scheme: str, levels: int) -> int:
    """Faces after ``levels`` refinements (exact for Catmull-Clark and Loop)."""
    return SCHEMES[scheme].estimated_faces(topology, levels)


def scheme_named(name) -> str:
    """The canonical name of scheme ``name`` (aliases ``catmark``, ``cc``, underscores and case
    accepted); ParameterError for an unknown one."""
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
    hierarchy : tuple of :class:`~splinekit.subdiv.level.Level`, ``levels + 1`` entries (the input
        first; ``hierarchy[k].stencil`` maps level k - 1 to level k); ``(input, finest)`` with
        ``keep_levels=False``, the finest without its stencil
    topologies, stencils, edge_sharpness, vertex_sharpness : lists read from ``hierarchy``
        (``stencils[k]`` maps level k to level k + 1; empty with ``keep_levels=False``)
    vertices : refined vertices of a PolyMesh input with ``keep_levels=False``, else None

    Large Catmull-Clark and Loop levels are built by compiled kernels
    (:mod:`splinekit.subdiv._compiled`): the same topologies and sharpness,
    stencils equal to rounding (1e-15); ``SPLINEKIT_NUMBA=0`` forces the numpy
    path.
    """

    def __init__(self, mesh, scheme: str, levels: int = 1, creases=None, corners=None, boundary: str = "edge-and-corner",
                 keep_levels: bool = True, crease_method: str = "uniform"):
        self.scheme = scheme_named(scheme)
        rules = SCHEMES[self.scheme]
        if crease_method not in CREASE_METHODS:
            raise ParameterError(f"crease_method must be one of {CREASE_METHODS}, got {crease_method!r}")
        if crease_method == "chaikin" and not rules.splits_edges:
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
        expected = rules.estimated_faces(topo, levels)
        limits.check(expected * rules.output_face_size * BYTES_PER_CORNER,
                     f"{levels} levels of {self.scheme} subdivision ({expected:,} faces)")
        size = rules.input_face_size
        if size is not None and not (topo.face_sizes == size).all():
            f = int(np.flatnonzero(topo.face_sizes != size)[0])
            shape = {3: "triangles", 4: "quads"}.get(size, f"faces of {size} vertices")
            raise MeshTopologyError(f"{self.scheme.capitalize()} subdivision needs {shape}; face {f} has "
                                    f"{int(topo.face_sizes[f])} vertices")
        self.boundary = boundary
        self.keep_levels = keep = bool(keep_levels)
        self._levels = levels
        self.vertices = None
        level = Level(topo, edge_sharpness(topo, creases), vertex_sharpness(topo, corners, boundary), self.scheme)
        del topo
        hierarchy = [level]
        X = None
        if not keep and isinstance(mesh, PolyMesh):
            X = mesh.vertices.reshape(mesh.topology.n_vertices, -1)
        # the job's size decides once: on the small first levels of a large job the numpy rules
        # cost about 1.5 ms each in per-call overhead (icosahedron -> Loop level 6: 22,000 Python
        # calls, 16 ms CPU with them, 6.6 ms with the kernels at every level)
        K = rules.kernels(level.topology, work=expected) if levels else None
        for k in range(levels):
            halves = None
            if crease_method == "chaikin":
                semi = (level.edge_sharpness > 0) & np.isfinite(level.edge_sharpness)
                if semi.any():
                    halves = chaikin_half_sharpness(level.topology, level.edge_sharpness)
            if K is not None:
                # compiled: S only when kept, S @ X without S, the finest level's edges on first use
                prepared = PreparedLevel(K, rules, level)
                level = None  # unless kept, the parent goes as soon as the kernels hold what they need
                S = prepared.stencil() if keep else None
                if X is not None:
                    X = prepared.apply(X)
                prepared.release_rows()
                level = prepared.child_level(S, lazy=k == levels - 1)
                del prepared, S
            else:
                level = rules.refine(level).level
                if X is not None:
                    X = level.stencil @ X
                if not keep:
                    level = replace(level, stencil=None)
            if halves is not None:
                # both paths number the child halves of parent edge e as 2e, 2e + 1
                edge_s = level.edge_sharpness.copy()
                edge_s[: halves.size] = halves
                level = replace(level, edge_sharpness=edge_s)
            if keep or k == levels - 1:
                hierarchy.append(level)
        self.hierarchy = tuple(hierarchy)
        if X is not None:
            self.vertices = X.reshape((X.shape[0],) + mesh.vertices.shape[1:])

    @property
    def levels(self) -> int:
        return self._levels

    @property
    def topologies(self) -> list:
        return [lv.topology for lv in self.hierarchy]

    @property
    def stencils(self) -> list:
        return [lv.stencil for lv in self.hierarchy[1:]] if self.keep_levels else []

    @property
    def edge_sharpness(self) -> list:
        return [lv.edge_sharpness for lv in self.hierarchy]

    @property
    def vertex_sharpness(self) -> list:
        return [lv.vertex_sharpness for lv in self.hierarchy]

    @property
    def finest(self) -> Level:
        """The finest :class:`~splinekit.subdiv.level.Level`."""
        return self.hierarchy[-1]

    def _require_stencils(self):
        if not self.keep_levels and self._levels:
            raise ParameterError("this Refinement was made with keep_levels=False: its stencils were not kept")

    @property
    def topology(self) -> Topology:
        """The finest level's connectivity."""
        return self.hierarchy[-1].topology

    @cached_property
    def matrix(self) -> sp.csr_matrix:
        """Composed ``(V_L, V_0)`` stencil ``S_L @ ... @ S_1`` (see
        :func:`splinekit.subdiv.compose.compose`: level by level, in time linear in its size)."""
        self._require_stencils()
        return compose(self.stencils, self.hierarchy[0].n_vertices)

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
