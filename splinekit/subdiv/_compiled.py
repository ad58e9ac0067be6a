"""One level of Catmull-Clark or Loop refinement with the compiled kernels.

:class:`PreparedLevel` prepares a parent :class:`~splinekit.subdiv.level.Level` for
:mod:`splinekit.subdiv._kernels` (the module the caller loaded through
:func:`splinekit._kernels.load`, so numba is imported only for large meshes) and offers the
three products of a step separately, so that a caller can keep only what it needs and drop the
rest early: the stencil matrix ``S`` (:meth:`PreparedLevel.stencil`), ``S @ X`` without ``S``
(:meth:`PreparedLevel.apply`) and the child level (:meth:`PreparedLevel.child_level`, whose edge
tables can be deferred to first use).

The scheme's rules reach the kernels as its :class:`~splinekit.subdiv.scheme.Scheme` fields
(``kernel``: the rule set's id, ``valence_weights``: Loop's beta per valence); the per-vertex
rule codes and blend weights come from the same functions of :mod:`splinekit.subdiv.creases`
that :func:`~splinekit.subdiv.masks.vertex_point_matrix` uses; the numbering of child vertices,
faces and edges is that of the numpy path (:func:`splinekit.subdiv.split.child_topology`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import limits
from ..errors import ResourceLimitError
from ..mesh.topology import Topology
from .creases import child_sharpness, transition_weights, vertex_rules
from .level import Level, RefinementStep

CATMULL_CLARK, LOOP = 0, 1
"""Rule-set ids of the kernels (a scheme's ``Scheme.kernel``)."""
_I32 = np.iinfo(np.int32).max
_NONE = np.empty(0, np.int64)
_NONE.setflags(write=False)  # every kernel call sees the same array types (one compiled version each)
_EMPTY_I64 = np.empty(0, np.int64)
_EMPTY_I32 = np.empty(0, np.int32)
_EMPTY_F64 = np.empty(0)
_EMPTY_X = np.empty((0, 1))


def _uniform_size(t: Topology) -> int:
    """3 or 4 when every face is a triangle or every face a quad, else 0 (remembered on ``t``)."""
    k = t.__dict__.get("_uniform_size")
    if k is None:
        sizes = t.__dict__.get("face_sizes")
        if sizes is None:
            sizes = np.diff(t.face_offsets)
        k = int(sizes[0]) if sizes.size and bool((sizes == sizes[0]).all()) else 0
        k = k if k in (3, 4) else 0
        t.__dict__["_uniform_size"] = k
    return k


class EdgeTables:
    """Builds a refined level's edge tables from its faces and three per-edge arrays of the
    parent (low end, first and second half-edge); called once, by :class:`Topology`, when the
    edges are first needed."""

    def __init__(self, K, scheme_id, V, E, k, offsets, lo, h0, h1, compact=False):
        self.K, self.scheme_id, self.V, self.E, self.k = K, scheme_id, V, E, k
        if compact and max(V + E, 4 * h0.size) < _I32:
            # kept until first use: half the memory (converted back when called)
            lo, h0, h1 = lo.astype(np.int32), h0.astype(np.int32), h1.astype(np.int32)
        self.offsets, self.lo, self.h0, self.h1 = offsets, lo, h0, h1

    def __call__(self, topology: Topology):
        K = self.K
        lo, h0, h1 = (np.ascontiguousarray(a, dtype=np.int64) for a in (self.lo, self.h0, self.h1))
        offsets = self.offsets
        self.offsets = self.lo = self.h0 = self.h1 = None
        if self.scheme_id == CATMULL_CLARK:
            edges, che, h0, h1 = K.cc_child_edges(self.V, self.E, topology.face_indices, offsets, self.k, lo, h0, h1)
        else:
            edges, che, h0, h1 = K.loop_child_edges(self.V, self.E, topology.face_indices, lo, h0, h1)
        return edges, che, (h0, h1)


class PreparedLevel:
    """A parent level prepared for the kernels ``K`` and the rules of ``scheme`` (see the module
    docstring)."""

    def __init__(self, K, scheme, level: Level):
        self.K = K
        self.scheme = scheme.name
        self.sid = scheme.kernel
        t, edge_s, vertex_s = level.topology, level.edge_sharpness, level.vertex_sharpness
        self.parent_s = (edge_s, vertex_s)  # for the child's sharpness
        self.V, self.E, self.F, self.H = t.n_vertices, t.n_edges, t.n_faces, t.n_halfedges
        self.fi = t.face_indices
        self.off = t.face_offsets
        self.k = _uniform_size(t)
        self.cf = _NONE if self.k else np.repeat(np.arange(self.F, dtype=np.int64), np.diff(self.off))
        self.cf.setflags(write=False)
        self.he = np.ascontiguousarray(t.halfedge_edge, dtype=np.int64)
        self.edges = np.ascontiguousarray(t.edges, dtype=np.int64)
        h0, h1 = t._edge_halfedge_pairs
        self.h0 = np.ascontiguousarray(h0, dtype=np.int64)
        self.h1 = np.ascontiguousarray(h1, dtype=np.int64)
        self.n_rows = self.V + self.E + (self.F if self.sid == CATMULL_CLARK else 0)
        edge_s = np.ascontiguousarray(edge_s, dtype=np.float64)
        self._prepare_rows(t, edge_s, np.ascontiguousarray(vertex_s, dtype=np.float64), scheme.valence_weights)

    # -- stencil rows -------------------------------------------------------------------------
    def _prepare_rows(self, t, edge_s, vertex_s, valence_weights):
        self.edge_s = edge_s
        self.vc_off, self.vc, self.valence = self.K.vertex_corners(self.fi, self.V, self.edges)
        if not edge_s.any() and not vertex_s.any():
            # every vertex smooth at both levels: coef_parent = 1, coef_child = 0
            self.rule_p = self.rule_c = np.zeros(self.V, np.int8)
            self.cp = self.cc = np.empty(0)
        else:
            parent = vertex_rules(t, edge_s, vertex_s)
            child = vertex_rules(t, child_sharpness(edge_s), child_sharpness(vertex_s))
            w = transition_weights(t, edge_s, vertex_s)
            same = parent == child
            self.cp = np.where(same, 1.0, w)
            self.cc = np.where(same, 0.0, 1.0 - w)
            self.rule_p = parent.astype(np.int8)
            self.rule_c = child.astype(np.int8)
        if valence_weights is not None:
            vmax = int(self.valence.max()) if self.V else 0
            self.beta = np.ascontiguousarray(valence_weights(np.arange(vmax + 1)), dtype=np.float64)
        else:
            self.beta = np.empty(0)

    def _rows(self, mode, max_bound=0, bound=None, indices=None, data=None, counts=None, X=None, Y=None):
        """Run the row kernel in ``mode`` (the unused arrays are empty placeholders of fixed types)."""
        return self.K.rows(
            mode, self.sid, self.V, self.E, self.n_rows, self.fi, self.off, self.k, self.cf, self.he, self.edges,
            self.h0, self.h1, self.vc_off, self.vc, self.valence, self.edge_s, self.rule_p, self.rule_c, self.cp,
            self.cc, self.beta, max_bound,
            _EMPTY_I64 if bound is None else bound,
            _EMPTY_I32 if indices is None else indices,
            _EMPTY_F64 if data is None else data,
            _EMPTY_I64 if counts is None else counts,
            _EMPTY_X if X is None else X,
            _EMPTY_X if Y is None else Y,
        )

    def stencil(self) -> sp.csr_matrix:
        """``S`` ``(n_rows, V)`` CSR, sorted indices, no explicit zeros."""
        BOUNDS, FILL = 0, 1
        bound = np.empty(self.n_rows + 1, np.int64)
        bound[0] = 0
        max_bound = int(self._rows(BOUNDS, bound=bound))
        np.cumsum(bound, out=bound)
        nnz = int(bound[-1])
        if max(nnz, self.V, self.n_rows) >= _I32:
            # the stencil's indices are int32 (scipy's CSR for sizes below 2**31), whatever the budget
            raise ResourceLimitError(f"a subdivision stencil with {nnz:,} entries exceeds the int32 index range")
        limits.check(12.0 * nnz, f"a subdivision stencil with {nnz:,} entries")
        indices = np.empty(nnz, np.int32)
        data = np.empty(nnz)
        counts = np.empty(self.n_rows, np.int64)
        self._rows(FILL, max_bound, bound, indices, data, counts)
        if int(counts.sum()) != nnz:
            indptr = np.zeros(self.n_rows + 1, np.int64)
            np.cumsum(counts, out=indptr[1:])
            new_indices = np.empty(int(indptr[-1]), np.int32)
            new_data = np.empty(int(indptr[-1]))
            self.K.compact(bound, indices, data, counts, indptr, new_indices, new_data)
            indices, data = new_indices, new_data
        else:
            indptr = bound
        S = sp.csr_matrix((data, indices, indptr.astype(np.int32)), shape=(self.n_rows, self.V), copy=False)
        S.has_sorted_indices = True
        S.has_canonical_format = True
        return S

    def apply(self, X: np.ndarray) -> np.ndarray:
        """``S @ X`` for ``X`` ``(V, d)``, bit for bit, without building ``S``."""
        APPLY = 2
        X = np.ascontiguousarray(X, dtype=np.float64)
        if not X.flags.writeable:
            X = X.copy()  # the kernels are compiled for writable arrays only
        bound = np.zeros(self.n_rows + 1, np.int64)
        max_bound = int(self._rows(0, bound=bound))
        del bound
        Y = np.empty((self.n_rows, X.shape[1]))
        self._rows(APPLY, max_bound, X=X, Y=Y)
        return Y

    def release_rows(self):
        """Drop what only the stencil rows need."""
        self.vc_off = self.vc = self.valence = self.rule_p = self.rule_c = self.cp = self.cc = None
        self.edge_s = self.beta = None

    # -- child connectivity ---------------------------------------------------------------------
    @property
    def n_inner_edges(self) -> int:
        """Child edges that split no parent edge (numbered after the ``2E`` halves)."""
        return self.H if self.sid == CATMULL_CLARK else 3 * self.F

    def child(self, lazy: bool = False) -> Topology:
        """The child topology; with ``lazy`` its edge tables are built on first use. Call it last:
        it lets go of the parent arrays as soon as they have served (lower peak memory)."""
        K = self.K
        lo = np.ascontiguousarray(self.edges[:, 0])
        self.edges = None
        if self.sid == CATMULL_CLARK:
            faces = K.cc_child_faces(self.V, self.E, self.fi, self.off, self.k, self.cf, self.he)
            n_child, size = self.V + self.E + self.F, 4
        else:
            faces = K.loop_child_faces(self.V, self.fi, self.he)
            n_child, size = self.V + self.E, 3
        self.fi = self.he = self.cf = None
        offsets = np.arange(0, faces.size + 1, size, dtype=np.int64)
        tables = EdgeTables(K, self.sid, self.V, self.E, self.k, self.off if self.k == 0 else _NONE, lo, self.h0, self.h1,
                            compact=lazy)
        self.h0 = self.h1 = self.off = None
        if lazy:
            child = Topology(n_child, faces, offsets, check=False, edge_table=tables)
        else:
            child = Topology(n_child, faces, offsets, check=False)
            child._set_edge_table(*tables(child))
        child.__dict__["_uniform_size"] = size
        return child

    def child_level(self, stencil=None, lazy: bool = False) -> Level:
        """The child :class:`Level` (with ``stencil`` when given); see :meth:`child`. Its sharpness
        is computed from the parent's without locating edges (:func:`child_edge_sharpness`)."""
        edge_s, vertex_s = self.parent_s
        self.parent_s = None
        topology = self.child(lazy=lazy)
        return Level(topology, child_edge_sharpness(edge_s, self.n_inner_edges),
                     child_vertex_sharpness(vertex_s, topology.n_vertices), self.scheme, stencil)


def child_edge_sharpness(edge_s: np.ndarray, n_inner: int) -> np.ndarray:
    """Child edge sharpness: both halves of edge ``e`` get ``max(s - 1, 0)``, the inner edges 0.

    Equal to locating the crease halves with ``find_edges`` (boundary halves stay ``inf``). Only
    the nonzero entries are written (the zeros of a smooth mesh stay untouched pages)."""
    E = edge_s.size
    out = np.zeros(2 * E + n_inner)
    sharp = np.flatnonzero(edge_s > 1.0)
    s = child_sharpness(edge_s[sharp])
    out[2 * sharp] = s
    out[2 * sharp + 1] = s
    return out


def child_vertex_sharpness(vertex_s: np.ndarray, n_child: int) -> np.ndarray:
    """``max(s - 1, 0)`` for the parent vertices, 0 for the new ones (nonzero entries written only)."""
    out = np.zeros(n_child)
    sharp = np.flatnonzero(vertex_s > 1.0)
    out[sharp] = child_sharpness(vertex_s[sharp])
    return out


def refine(K, scheme, level: Level) -> RefinementStep:
    """The compiled counterpart of the numpy rules ``scheme.refine`` (the same step)."""
    t, edge_s = level.topology, level.edge_sharpness
    prepared = PreparedLevel(K, scheme, level)
    S = prepared.stencil()
    prepared.release_rows()
    child = prepared.child_level(S)
    V = t.n_vertices
    sharp = np.flatnonzero(edge_s > 0)
    pairs = np.concatenate(
        [np.column_stack([t.edges[sharp, 0], V + sharp]), np.column_stack([V + sharp, t.edges[sharp, 1]])]
    )
    return RefinementStep(child, pairs, np.tile(edge_s[sharp], 2))
