"""Booleans of closed bodies through manifold3d: union, difference, intersection.

Every operand is a closed, consistently oriented triangle or polygon
:class:`~splinekit.mesh.polymesh.PolyMesh` (polygons are fan-triangulated from
their first corner, so they should be convex, or at least star-shaped from that
corner), a ``manifold3d.Manifold``, or anything
:func:`splinekit.tessellation.tessellate` turns into such a mesh (the
``tolerance`` keyword is passed on to it), such as a
:class:`splinekit.brep.Solid`, whose trimmed faces tessellate watertight. The
result is always a triangle ``PolyMesh`` in the operands' length unit. These
are the fast path; :func:`splinekit.brep.fuse` / ``cut`` / ``common`` are the
exact booleans of solids (through OpenCascade).

Checks before manifold3d sees a mesh (vectorized over edges, no loop per face):

- vertices must be 3-D and finite;
- every edge must have exactly two faces (a boundary edge or an edge shared by
  three or more faces raises :class:`~splinekit.errors.NotManifoldError` naming
  the edge's two vertex indices), and the two faces must traverse it in
  opposite directions (consistent orientation).

manifold3d accepts an edge shared by four faces without complaint and would
return a result for it, which is why the edge check is done here.

Orientation: a body whose signed volume is negative (faces clockwise seen from
outside, as some file formats store them) is **reoriented**, not rejected: the
region a closed surface bounds does not depend on its winding, so flipping
every face gives the intended solid. The sign is taken for the whole operand:
inside an outward-facing body, an inward-facing component is a cavity, and it
is kept as one. Vertices shared by two otherwise separate sheets ("pinched"
vertices, two cubes touching at a corner) are accepted, as manifold3d does.

Self-intersecting operands are not detected (neither splinekit nor manifold3d
looks for them); their results are undefined.

An empty result (the intersection of disjoint bodies, ``a - a``) is a
``PolyMesh`` with no vertices and no faces; such a mesh is also accepted as
the empty operand. It has ``is_closed == False`` (no faces) and no volume.

Conversion is cheap in both directions: the arrays go to ``manifold3d.Mesh64``
(float64 vertices, so coordinates keep double precision) with one copy each,
and the result's arrays are adopted without a copy. The result's topology is
not re-validated (manifold3d guarantees a closed manifold); its edge table is
built lazily when first asked for.

Each PolyMesh is converted once: its checked, positively oriented
``Manifold`` is kept with the mesh (:meth:`PolyMesh.derived`; meshes are
immutable), and a boolean's result keeps the ``Manifold`` it came from, so a
mesh used in several booleans, or a chain of booleans, pays no conversion
after the first. The cached object holds a copy of the mesh in manifold3d's
memory for as long as the mesh lives.
"""

from __future__ import annotations

import weakref

import numpy as np

from .._signals import reraise_interrupt
from .._validate import as_positive
from ..errors import (
    BackendError,
    MeshTopologyError,
    MissingDependencyError,
    NotManifoldError,
    ParameterError,
)
from ..mesh.geometry import triangulate
from ..mesh.polymesh import PolyMesh
from ..mesh.topology import Topology
from ..tessellation import tessellate

__all__ = ["union", "difference", "intersection", "union_all", "to_manifold", "from_manifold"]

# Topologies already known to be closed, edge-manifold and consistently oriented (boolean
# results, and operands that passed the checks once). Connectivity is immutable, so a check
# never goes stale; chaining booleans then skips the edge-table sort of the previous result.
_VERIFIED: weakref.WeakSet = weakref.WeakSet()
_MANIFOLD_KEY = "manifold3d.Manifold"  # a PolyMesh's converted operand, in PolyMesh.derived


def _require_manifold3d():
    """The manifold3d module, or MissingDependencyError naming the package."""
    try:
        import manifold3d
    except ImportError as exc:
        reraise_interrupt(exc)  # Ctrl-C during the import is an interrupt, not a missing package
        raise MissingDependencyError(
            f"mesh booleans need manifold3d: install it with pip install manifold3d; the import failed with: {exc}"
        ) from None
    return manifold3d


# -- checks ---------------------------------------------------------------------------------
def _edge_text(topology, e: int) -> str:
    a, b = topology.edges[e]
    return f"edge ({int(a)}, {int(b)})"


def _check_faces(topology, name: str) -> None:
    """Index range, face sizes and repeated vertices in a face (MeshTopologyError naming ``name``).

    The checks are the Topology constructor's own (an operand may come from an unchecked
    ``Topology(..., check=False)``); only the edge checks below are specific to booleans.
    """
    try:
        topology._check_faces()
    except MeshTopologyError as exc:
        raise MeshTopologyError(f"{name}: {exc}") from None


def _check_edges(topology, name: str) -> None:
    """Every edge has exactly two faces traversing it in opposite directions (NotManifoldError)."""
    E, H = topology.n_edges, topology.n_halfedges
    pairs = topology.edge_halfedges  # (E, 2); second -1 on a boundary edge
    # each edge has at least two half-edges and there are 2E of them: exactly two each
    if H != 2 * E or (pairs[:, 1] < 0).any():
        counts = np.bincount(topology.halfedge_edge, minlength=E)
        e = int(np.flatnonzero(counts != 2)[0])
        faces = topology.corner_face[topology.halfedge_edge == e].tolist()
        n_boundary = int((counts == 1).sum())
        n_over = int((counts > 2).sum())
        if counts[e] == 1:
            raise NotManifoldError(
                f"{name} is not closed: {_edge_text(topology, e)} is a boundary edge, used only by face "
                f"{faces[0]}; a closed surface has exactly 2 faces on every edge "
                f"({n_boundary} boundary edges, {n_over} edges with more than 2 faces)"
            )
        raise NotManifoldError(
            f"{name} is not a 2-manifold: {_edge_text(topology, e)} is shared by {int(counts[e])} faces "
            f"{faces}; a 2-manifold has exactly 2 faces on every edge "
            f"({n_over} edges with more than 2 faces, {n_boundary} boundary edges)"
        )
    src = topology.halfedge_src
    same = src[pairs[:, 0]] == src[pairs[:, 1]]
    if same.any():
        e = int(np.flatnonzero(same)[0])
        f0, f1 = (int(topology.corner_face[h]) for h in pairs[e])
        raise NotManifoldError(
            f"{name} is inconsistently oriented: faces {f0} and {f1} both traverse {_edge_text(topology, e)} "
            f"in the same direction; neighbouring faces must run along their shared edge in opposite "
            f"directions ({int(same.sum())} such edges)"
        )


def _checked_triangles(mesh, name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(V (n, 3) float64, T (m, 3) uint64)`` fresh writable arrays of a checked closed mesh."""
    V = mesh.vertices
    if V.ndim != 2 or V.shape[1] != 3:
        raise ParameterError(f"{name} must have 3-D vertices for a boolean, got vertices of shape {V.shape}")
    if not np.isfinite(V).all():
        i = int(np.flatnonzero(~np.isfinite(V).all(axis=1))[0])
        raise MeshTopologyError(f"{name}: vertex {i} has non-finite coordinates {V[i].tolist()}")
    topology = mesh.topology
    if topology.n_faces and topology not in _VERIFIED:
        _check_faces(topology, name)
        _check_edges(topology, name)
        _VERIFIED.add(topology)
    # manifold3d's bindings refuse read-only arrays: one copy each (the uint64 view is free)
    Vw = np.array(V, dtype=np.float64, order="C")
    if topology.n_faces == 0:
        return Vw, np.zeros((0, 3), dtype=np.uint64)
    if topology.is_uniform and int(topology.face_sizes[0]) == 3:
        T = np.array(topology.face_indices.reshape(-1, 3))
    else:
        T = np.ascontiguousarray(triangulate(topology)[0])
    return Vw, T.view(np.uint64)


def _status_error(status, what: str) -> BackendError:
    return BackendError(f"manifold3d reported {getattr(status, 'name', status)} for {what}")


def _checked_manifold(m, what: str):
    """``m`` itself if its status is NoError, else BackendError naming the status."""
    m3 = _require_manifold3d()
    status = m.status()
    if status != m3.Error.NoError:
        raise _status_error(status, what)
    return m


def _build(V: np.ndarray, T: np.ndarray, name: str):
    """A manifold3d.Manifold from checked arrays, reoriented if its volume is negative."""
    m3 = _require_manifold3d()
    m = _checked_manifold(m3.Manifold(m3.Mesh64(vert_properties=V, tri_verts=T)), name)
    if m.volume() < 0.0:
        # wound clockwise seen from outside: the same solid with every face flipped
        m = _checked_manifold(
            m3.Manifold(m3.Mesh64(vert_properties=V, tri_verts=np.ascontiguousarray(T[:, ::-1]))), name
        )
    return m


def _check_tolerance(tolerance):
    if tolerance is None:
        return None
    return as_positive(tolerance, "tolerance")


def _as_mesh(obj, tolerance, name: str):
    """A PolyMesh for ``obj``: itself, or its tessellation."""
    if isinstance(obj, PolyMesh):
        return obj
    mesh = tessellate(obj, tolerance)
    if not isinstance(mesh, PolyMesh):
        raise BackendError(f"splinekit.tessellate returned a {type(mesh).__name__} for {name}, not a PolyMesh")
    return mesh


def _is_manifold(obj) -> bool:
    mod = type(obj).__module__ or ""
    if not mod.startswith("manifold3d"):  # do not import manifold3d just to test a type
        return False
    return isinstance(obj, _require_manifold3d().Manifold)


def _operand(obj, tolerance, name: str):
    """A manifold3d.Manifold for one operand (checked, positively oriented)."""
    if _is_manifold(obj):
        m = _checked_manifold(obj, name)
        if m.volume() < 0.0:
            mesh = m.to_mesh64()
            V = np.array(mesh.vert_properties[:, :3], dtype=np.float64, order="C")
            return _build(V, np.array(mesh.tri_verts, dtype=np.uint64), name)
        return m
    if isinstance(obj, PolyMesh):
        # converted once per mesh (meshes are immutable): a mesh used in several booleans, or
        # the result of one fed to the next, costs no second conversion (about half the time
        # of a boolean of two large meshes went to building the operands)
        return obj.derived(_MANIFOLD_KEY, lambda mesh: _build(*_checked_triangles(mesh, name), name))
    mesh = _as_mesh(obj, tolerance, name)
    V, T = _checked_triangles(mesh, name)
    return _build(V, T, name)


# -- conversion -------------------------------------------------------------------------------
def to_manifold(obj, *, tolerance=None):
    """A ``manifold3d.Manifold`` for a closed body.

    Parameters
    ----------
    obj : PolyMesh, manifold3d.Manifold, or anything ``splinekit.tessellate`` accepts
        A closed, consistently oriented 2-manifold (checked; see the module notes).
    tolerance : float, optional
        Chordal tolerance (length units) for operands that must be tessellated.

    Raises
    ------
    NotManifoldError
        Naming the first boundary, over-shared or inconsistently oriented edge.
    MeshTopologyError, ParameterError
        Malformed faces, non-finite or non-3-D vertices, an unsupported type.
    BackendError
        manifold3d rejected the mesh (the message names its status).
    """
    _require_manifold3d()
    return _operand(obj, _check_tolerance(tolerance), "the body")


def from_manifold(manifold):
    """The triangle PolyMesh of a ``manifold3d.Manifold``: vertices ``(n, 3)`` float64,
    faces ``(m, 3)``; no vertices and no faces for an empty manifold.

    Raises BackendError naming the status if the manifold is in an error state.
    """
    if not _is_manifold(manifold):
        raise ParameterError(f"expected a manifold3d.Manifold, got {type(manifold).__name__}")
    _checked_manifold(manifold, "the manifold")
    mesh = manifold.to_mesh64()
    V = np.asarray(mesh.vert_properties, dtype=np.float64)
    if V.size == 0:
        V = np.zeros((0, 3))
    elif V.shape[1] != 3:  # a Manifold carrying extra vertex properties: keep the positions
        V = np.ascontiguousarray(V[:, :3])
    T = np.asarray(mesh.tri_verts, dtype=np.uint64).reshape(-1, 3)
    # indices are < n_vertices: reinterpreting uint64 as int64 is exact and copies nothing
    flat = T.view(np.int64).reshape(-1)
    topology = Topology(len(V), flat, np.arange(len(T) + 1, dtype=np.int64) * 3, check=False)
    if len(T):
        _VERIFIED.add(topology)
    return PolyMesh._adopt(V, topology)


# -- booleans -----------------------------------------------------------------------------------
def _result(out, what: str) -> PolyMesh:
    """The PolyMesh of a boolean's manifold ``out`` (checked), which it keeps as its manifold3d
    object: a result used as the next operand is not converted back."""
    m3 = _require_manifold3d()
    status = out.status()
    if status != m3.Error.NoError:
        raise _status_error(status, what)
    mesh = from_manifold(out)
    if mesh.n_faces and out.num_prop() == 0:  # the very solid of the mesh (no extra vertex properties)
        mesh.derived(_MANIFOLD_KEY, lambda _: out)
    return mesh


def _binary(a, b, op: str, tolerance):
    _require_manifold3d()  # MissingDependencyError before any conversion
    tol = _check_tolerance(tolerance)
    ma = _operand(a, tol, "the first operand")
    mb = _operand(b, tol, "the second operand")
    if op == "union":
        out = ma + mb
    elif op == "difference":
        out = ma - mb
    else:
        out = ma ^ mb
    return _result(out, f"the {op}")


def union(a, b, *, tolerance=None):
    """The union ``a ∪ b`` of two closed bodies as a triangle PolyMesh.

    ``a`` and ``b`` are PolyMeshes (closed, consistently oriented; polygons are
    fan-triangulated), ``manifold3d.Manifold`` objects, or anything
    ``splinekit.tessellate`` accepts, tessellated with ``tolerance`` (length
    units; ignored for meshes). Returns vertices ``(n, 3)`` float64 and faces
    ``(m, 3)``, closed and outward oriented, or an empty mesh. Errors: see
    :func:`to_manifold`; BackendError if manifold3d reports a failure.
    """
    return _binary(a, b, "union", tolerance)


def difference(a, b, *, tolerance=None):
    """The difference ``a \\ b`` (``a`` minus ``b``) as a triangle PolyMesh; see :func:`union`."""
    return _binary(a, b, "difference", tolerance)


def intersection(a, b, *, tolerance=None):
    """The intersection ``a ∩ b`` as a triangle PolyMesh (empty when they are disjoint); see :func:`union`."""
    return _binary(a, b, "intersection", tolerance)


def union_all(bodies, *, tolerance=None):
    """The union of any number of closed bodies in one manifold3d batch operation.

    ``bodies`` is an iterable of operands as for :func:`union`; the union of none
    is the empty mesh. Errors name the offending body as ``bodies[i]``.
    """
    m3 = _require_manifold3d()
    tol = _check_tolerance(tolerance)
    if isinstance(bodies, (str, bytes)) or _is_manifold(bodies) or not hasattr(bodies, "__iter__"):
        raise ParameterError(f"bodies must be an iterable of bodies, got {type(bodies).__name__}")
    if isinstance(bodies, PolyMesh):
        raise ParameterError("bodies must be an iterable of bodies, got a single PolyMesh")
    parts = [_operand(body, tol, f"bodies[{i}]") for i, body in enumerate(bodies)]
    if not parts:
        return from_manifold(m3.Manifold())
    out = m3.Manifold.batch_boolean(parts, m3.OpType.Add)
    return _result(out, f"the union of {len(parts)} bodies")
