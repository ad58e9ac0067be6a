"""Topology of shells and solids: which edge uses are one edge, the vertices, free edges, Euler
characteristic, genus and closedness.

Two uses of an edge are paired by their ``key`` when both carry one; a use without a key is paired
geometrically with any use whose 3-D end points match (either way round) within the tolerance and
whose arc-length mid points agree. Vertices are the uses' 3-D end points clustered within the
tolerance. Candidates are found with a k-d tree (end points) or a sort (:mod:`.links`), and the
links joined by whole-array component labelling, so pairing costs ``O(n log n)`` in the number of
uses; only the per-use sampling is a Python loop over uses.

Counting follows the Euler-Poincaré formula of B-reps with inner loops::

    V - E + F - (L - F) = 2 (S - G)        (closed shells)

with ``L`` the loops (a face bounded by its natural domain has one), ``S`` the shells and ``G``
the genus. Degenerate edges (poles, apexes) are not counted: a sphere is ``V = 2`` (the poles),
``E = 1`` (the seam), ``F = 1``. A seam used twice by one face is one edge.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .._validate import as_float_array
from ..errors import ParameterError
from .links import close_pairs, first_use_labels, link_components

__all__ = [
    "EdgeGroup", "ShellTopology", "TopologyQueries", "edge_points", "pair_by_samples", "shell_topology", "surface_points",
]

_SAMPLES = 33
"""Points per edge use for its mid point and direction (the mid point only tells edges apart)."""

_MID_RELATIVE = 1e-3
"""Mid points of two uses of one edge may differ by this fraction of the edge's length: the
arc-length mid point is found on a polyline, and two different edges with the same ends have mid
points much further apart."""


def surface_points(face, uv) -> np.ndarray:
    """The face's surface at ``uv`` ``(n, 2)`` clamped into its domain (a trim of an invalid face
    may leave the domain; :mod:`check` reports that): ``(n, 3)``."""
    (u0, u1), (v0, v1) = face.domain
    uv = np.asarray(uv, dtype=np.float64)
    return face.surface.evaluate(np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1))


def edge_points(face, edge, t) -> np.ndarray:
    """3-D points ``(n, 3)`` of ``edge`` (a use on ``face``) at parameters ``t`` ``(n,)``: its 3-D
    curve where it has one, else the surface at the pcurve's points."""
    t = np.asarray(t, dtype=np.float64)
    if edge.curve is not None:
        return edge.curve.evaluate(t)
    return surface_points(face, edge.pcurve.evaluate(t))


@dataclass(frozen=True)
class EdgeGroup:
    """One edge of a shell: the uses that are the same edge.

    ``uses`` is a tuple of ``(face, loop, edge)`` indices into the shell's faces, their
    ``boundary_loops()`` and the loop's edges; ``vertices`` the indices (into the shell's
    ``vertices``) of the first use's start and end; ``degenerate`` marks a pole or apex.
    """

    uses: tuple[tuple[int, int, int], ...]
    vertices: tuple[int, int]
    degenerate: bool
    key: object = None

    @property
    def is_free(self) -> bool:
        """Used by one face only (a boundary edge of an open shell)."""
        return len(self.uses) == 1 and not self.degenerate


@dataclass(frozen=True, eq=False)
class ShellTopology:
    """The topology of a set of faces, computed once by :func:`shell_topology`.

    Attributes
    ----------
    uses : (m, 3) int array
        ``(face, loop, edge)`` of every edge use, loop after loop, face after face.
    use_group : (m,) int array
        Index into ``edges`` of each use.
    use_vertices : (m, 2) int array
        Start and end vertex of each use.
    direction : (m, 3) float array
        Unit 3-D tangent of each use at its arc-length mid point, flipped on reversed faces: the
        sense in which the face's outward-oriented boundary runs along the edge.
    edges : tuple of EdgeGroup
    vertices : (V, 3) float array
    n_faces, n_loops : int
    tolerance : float
        The largest merging distance (pairs merge within the sum of their own tolerances).
    """

    uses: np.ndarray
    use_group: np.ndarray
    use_vertices: np.ndarray
    direction: np.ndarray
    edges: tuple
    vertices: np.ndarray
    n_faces: int
    n_loops: int
    tolerance: float

    @cached_property
    def free_edges(self) -> tuple:
        """Edges used by one face only."""
        return tuple(g for g in self.edges if g.is_free)

    @cached_property
    def n_edges(self) -> int:
        """Edges counted by Euler-Poincaré (degenerate ones left out)."""
        return sum(not g.degenerate for g in self.edges)

    @cached_property
    def euler_characteristic(self) -> int:
        """``V - E + F - (L - F)``: 2 for a sphere-like closed shell, 0 for a torus-like one."""
        return len(self.vertices) - self.n_edges + self.n_faces - (self.n_loops - self.n_faces)

    @cached_property
    def badly_used(self) -> tuple:
        """Non-degenerate edges not used exactly twice in opposite senses, with the reason:
        ``(group index, "free" | "non-manifold" | "same-direction")``."""
        out = []
        for i, g in enumerate(self.edges):
            if g.degenerate:
                continue
            if len(g.uses) == 1:
                out.append((i, "free"))
            elif len(g.uses) > 2:
                out.append((i, "non-manifold"))
        # pairs walked the same way: vectorized over the two-use groups
        two = np.array([i for i, g in enumerate(self.edges) if len(g.uses) == 2 and not g.degenerate], dtype=np.intp)
        if two.size:
            order = np.argsort(self.use_group, kind="stable")
            starts = np.searchsorted(self.use_group[order], two)
            a, b = order[starts], order[starts + 1]
            same = np.einsum("ij,ij->i", self.direction[a], self.direction[b]) > 0
            out += [(int(i), "same-direction") for i in two[same]]
        return tuple(sorted(out))

    @cached_property
    def is_closed(self) -> bool:
        """Every non-degenerate edge is used exactly twice, in opposite senses."""
        return not self.badly_used

    @cached_property
    def n_components(self) -> int:
        """Connected pieces (faces joined through shared edges)."""
        if self.n_faces == 0:
            return 0
        f = self.uses[:, 0]
        g = self.use_group
        # face -> edge-group incidence; faces sharing a group are connected
        n = self.n_faces + len(self.edges)
        labels = link_components(n, f, self.n_faces + g)
        return len(np.unique(labels[: self.n_faces]))

    @cached_property
    def n_boundaries(self) -> int:
        """Boundary curves: connected chains of free edges."""
        free = [g for g in self.edges if g.is_free]
        if not free:
            return 0
        ends = np.array([g.vertices for g in free])
        labels = link_components(len(self.vertices), ends[:, 0], ends[:, 1])
        return len(np.unique(labels[ends[:, 0]]))

    @cached_property
    def genus(self) -> int:
        """Handles, from ``V - E + F - (L - F) = 2 C - 2 G - B`` (``C`` connected pieces, ``B``
        boundary curves; a closed connected shell is ``2 - 2 G``)."""
        return (2 * self.n_components - self.n_boundaries - self.euler_characteristic) // 2


def shell_topology(faces, tolerance: float | None = None) -> ShellTopology:
    """Pair the edge uses of ``faces`` and cluster their vertices.

    ``tolerance`` (model units): points closer than this are merged. By default each pair of
    points is merged within the sum of their own tolerances (the larger of the edge's and the
    face's): each lies within its own tolerance of the true vertex or edge, so one sloppy edge
    does not widen the merging of every other.
    """
    faces = tuple(faces)
    uses, keys, degenerate, tols = [], [], [], []
    starts, ends, mids, dirs, lengths = [], [], [], [], []
    n_loops = 0
    s = np.linspace(0.0, 1.0, _SAMPLES)
    for fi, face in enumerate(faces):
        loops = face.boundary_loops()
        n_loops += len(loops)
        for li, loop in enumerate(loops):
            for ei, e in enumerate(loop):
                a, b = e.domain
                p = edge_points(face, e, a + (b - a) * s)
                seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
                cum = np.concatenate([[0.0], np.cumsum(seg)])
                total = cum[-1]
                # arc-length mid point and the chord direction there
                k = min(int(np.searchsorted(cum, 0.5 * total, side="right")) - 1, _SAMPLES - 2)
                k = max(k, 0)
                w = (0.5 * total - cum[k]) / seg[k] if seg[k] > 0 else 0.0
                mid = p[k] + w * (p[k + 1] - p[k])
                d = p[k + 1] - p[k]
                d = d / np.linalg.norm(d) if seg[k] > 0 else np.zeros(3)
                uses.append((fi, li, ei))
                keys.append(e.key)
                degenerate.append(e.degenerate)
                tols.append(max(e.tolerance, face.tolerance))
                starts.append(p[0])
                ends.append(p[-1])
                mids.append(mid)
                dirs.append(-d if face.reversed else d)
                lengths.append(total)
    m = len(uses)
    tols = np.array(tols, dtype=np.float64)
    if tolerance is None:
        pair_tol = tols  # per point; a pair merges within the sum of its two
        tolerance = 2.0 * float(tols.max()) if m else 0.0
    else:
        pair_tol = np.full(m, 0.5 * float(tolerance))
    uses = np.array(uses, dtype=np.intp).reshape(m, 3)
    degenerate = np.array(degenerate, dtype=bool)
    starts, ends, mids = (np.array(x, dtype=np.float64).reshape(m, 3) for x in (starts, ends, mids))
    dirs = np.array(dirs, dtype=np.float64).reshape(m, 3)
    lengths = np.array(lengths)

    # vertices: every use's start and end clustered within the tolerance
    ends_all = np.concatenate([starts, ends])
    labels = _clusters(ends_all, np.concatenate([pair_tol, pair_tol]))
    n_vert = int(labels.max()) + 1 if m else 0
    vertices = np.zeros((n_vert, 3))
    np.add.at(vertices, labels, ends_all)
    vertices /= np.maximum(np.bincount(labels, minlength=n_vert), 1)[:, None]
    use_vertices = np.stack([labels[:m], labels[m:]], axis=1)

    # edges: union of uses sharing a key, then keyless uses matched geometrically
    parent = np.arange(m)
    by_key = {}
    for i in range(m):
        if keys[i] is not None and not degenerate[i]:
            by_key.setdefault(keys[i], []).append(i)
    rows, cols = [], []
    for members in by_key.values():
        rows += members[1:]
        cols += [members[0]] * (len(members) - 1)
    keyless = np.flatnonzero(np.array([k is None for k in keys], dtype=bool) & ~degenerate)
    solid = np.flatnonzero(~degenerate)
    if keyless.size and solid.size:
        from scipy.spatial import cKDTree  # on use: scipy.spatial takes ~0.15 s to import, ten times all of brep
        target = cKDTree(np.concatenate([starts[solid], ends[solid]], axis=1))
        for query in (np.concatenate([starts[keyless], ends[keyless]], axis=1),
                      np.concatenate([ends[keyless], starts[keyless]], axis=1)):
            pairs = cKDTree(query).sparse_distance_matrix(target, 2.0 * tolerance, output_type="coo_matrix")
            i, j = keyless[pairs.row], solid[pairs.col]
            limit = pair_tol[i] + pair_tol[j]
            ends_ok = pairs.data <= np.sqrt(2.0) * limit  # both ends, as one 6-D distance
            near = np.linalg.norm(mids[i] - mids[j], axis=1) <= np.maximum(limit, _MID_RELATIVE * np.maximum(lengths[i], lengths[j]))
            keep = ends_ok & near & (i != j)
            rows += i[keep].tolist()
            cols += j[keep].tolist()
    if m:
        parent = link_components(m, rows, cols)
    # degenerate uses stay single edges (each its own group)
    groups = {}
    for i in range(m):
        groups.setdefault(("degenerate", i) if degenerate[i] else int(parent[i]), []).append(i)
    edges, use_group = [], np.empty(m, dtype=np.intp)
    for gi, members in enumerate(groups.values()):
        use_group[members] = gi
        first = members[0]
        edges.append(EdgeGroup(tuple(tuple(int(x) for x in uses[i]) for i in members),
                               (int(use_vertices[first, 0]), int(use_vertices[first, 1])),
                               bool(degenerate[first]), keys[first]))
    return ShellTopology(uses, use_group, use_vertices, dirs, tuple(edges), vertices, len(faces), n_loops,
                         float(tolerance))


def pair_by_samples(points, tol) -> np.ndarray:
    """Group edge uses that are one edge by their sampled 3-D points: labels ``(n,)``.

    ``points`` ``(n, k, 3)``: each use's 3-D points at the same ``k`` parameter fractions of its
    own domain, ``k`` odd (e.g. 0, 1/4, 1/2, 3/4, 1); ``tol`` ``(n,)`` or a float (model units).
    Two uses are one edge when every sample agrees within the larger of their two tolerances, in
    the same order or reversed (the uses run the edge in opposite directions); the labels are the
    connected components of those pairs, numbered in order of their first use. The candidates
    are the pairs whose middle samples lie within that distance (:func:`.links.close_pairs`: a
    sort, or a k-d tree where the sort would compare too many), so this costs ``O(n log n)``.
    For keyless uses: uses that carry a ``key`` are paired by it.
    """
    P = as_float_array(points, "points")
    if P.size == 0:
        return np.zeros(0, dtype=np.intp)
    if P.ndim != 3 or P.shape[2] != 3 or P.shape[1] % 2 != 1:
        raise ParameterError(f"points must be (n, k, 3) with k odd (samples per edge use), got shape {P.shape}")
    if not np.isfinite(P).all():
        raise ParameterError("points must be finite")
    n = len(P)
    tol = as_float_array(tol, "tol")
    if not (tol.ndim == 0 or tol.shape == (n,)) or not (np.isfinite(tol) & (tol >= 0)).all():
        raise ParameterError(f"tol must be one finite tolerance >= 0 or one per use ({n}), got {tol!r}")
    tol = np.broadcast_to(tol, (n,))
    pairs = close_pairs(P[:, P.shape[1] // 2], float(tol.max()))
    if len(pairs):
        A, B = P[pairs[:, 0]], P[pairs[:, 1]]
        limit2 = np.square(np.maximum(tol[pairs[:, 0]], tol[pairs[:, 1]]))[:, None]
        d = A - B
        same = (np.einsum("ijk,ijk->ij", d, d) <= limit2).all(axis=1)
        d = A - B[:, ::-1]
        flip = (np.einsum("ijk,ijk->ij", d, d) <= limit2).all(axis=1)
        pairs = pairs[same | flip]
    return first_use_labels(link_components(n, pairs[:, 0], pairs[:, 1]))


def _clusters(points: np.ndarray, tol: np.ndarray) -> np.ndarray:
    """Labels ``(n,)``: points ``a``, ``b`` closer than ``tol[a] + tol[b]`` (transitively) share one."""
    n = len(points)
    if n == 0:
        return np.zeros(0, dtype=np.intp)
    pairs = close_pairs(points, 2.0 * float(tol.max()))
    if len(pairs):
        d = np.linalg.norm(points[pairs[:, 0]] - points[pairs[:, 1]], axis=1)
        pairs = pairs[d <= tol[pairs[:, 0]] + tol[pairs[:, 1]]]
    return first_use_labels(link_components(n, pairs[:, 0], pairs[:, 1]))


class TopologyQueries:
    """Topology properties for :class:`Shell`, :class:`Solid` and :class:`TrimmedFace` (a face is
    treated as a one-face shell, so a sphere's single face is closed). Subclasses provide
    ``_topologies()``: one :class:`ShellTopology` per shell, cached on the immutable object."""

    __slots__ = ()

    def _topologies(self) -> tuple:
        raise NotImplementedError

    @property
    def topology(self) -> ShellTopology:
        """The topology of the (first / only) shell."""
        return self._topologies()[0]

    @property
    def vertices(self) -> np.ndarray:
        """``(V, 3)`` vertex positions (end points of edges clustered within the tolerance)."""
        return np.concatenate([t.vertices for t in self._topologies()])

    @property
    def free_edges(self) -> tuple:
        """Edges used by one face only, as :class:`EdgeGroup` (indices per shell)."""
        return tuple(g for t in self._topologies() for g in t.free_edges)

    @property
    def euler_characteristic(self) -> int:
        """``V - E + F - (L - F)`` summed over the shells (degenerate edges not counted)."""
        return sum(t.euler_characteristic for t in self._topologies())

    @property
    def genus(self) -> int:
        """Number of handles (through holes), summed over the shells: 0 for a box, 1 for a torus
        or a box with one through hole."""
        return sum(t.genus for t in self._topologies())

    @property
    def is_closed(self) -> bool:
        """Every non-degenerate edge is used exactly twice, in opposite senses."""
        return all(t.is_closed for t in self._topologies())
