"""Connected pieces of a polygon mesh: joining meshes into one, labelling the pieces, and the
genus of a closed mesh from its Euler characteristic."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..errors import ParameterError
from .polymesh import PolyMesh
from .topology import Topology

__all__ = ["concatenate", "face_components", "genus"]


def concatenate(meshes) -> PolyMesh:
    """One :class:`PolyMesh` holding every face of ``meshes`` (a non-empty sequence of
    PolyMesh), vertices stacked in order and each mesh's vertex indices offset by the vertices
    before it. Nothing is welded: each input stays a separate piece (a single mesh is returned
    as it is)."""
    meshes = list(meshes)
    if not meshes:
        raise ParameterError("concatenate needs at least one mesh, got none")
    for i, m in enumerate(meshes):
        if not isinstance(m, PolyMesh):
            raise ParameterError(f"meshes[{i}] must be a PolyMesh, got {type(m).__name__}")
    if len(meshes) == 1:
        return meshes[0]
    dims = {np.asarray(m.vertices).shape[1] for m in meshes}
    if len(dims) > 1:
        raise ParameterError(f"the meshes' vertices have different dimensions {sorted(dims)}")
    vertex_start = np.cumsum([0] + [m.n_vertices for m in meshes])
    index_start = np.cumsum([0] + [m.face_indices.size for m in meshes])
    vertices = np.concatenate([np.asarray(m.vertices) for m in meshes])
    indices = np.concatenate([np.asarray(m.face_indices) + o for m, o in zip(meshes, vertex_start[:-1])])
    offsets = np.concatenate([[0]] + [np.asarray(m.face_offsets)[1:] + o for m, o in zip(meshes, index_start[:-1])])
    return PolyMesh.from_topology(vertices, Topology(int(vertex_start[-1]), indices, offsets, check=False))


def face_components(mesh) -> tuple[int, np.ndarray]:
    """``(count, labels (F,))``: the connected pieces of ``mesh``'s faces, faces sharing a
    vertex in one piece, labelled ``0 .. count-1``. Isolated vertices belong to no piece."""
    _require_mesh(mesh, "face_components")
    idx = np.asarray(mesh.face_indices)
    n_vertices, n_faces = mesh.n_vertices, mesh.n_faces
    face_of_corner = np.repeat(np.arange(n_faces), np.diff(np.asarray(mesh.face_offsets)))
    n = n_vertices + n_faces
    # vertex-face incidence graph: two faces are connected when a path of shared vertices joins them
    graph = coo_matrix((np.ones(idx.size), (idx, n_vertices + face_of_corner)), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    _, compact = np.unique(labels[n_vertices:], return_inverse=True)
    return int(compact.max(initial=-1)) + 1, compact.reshape(-1)


def genus(mesh) -> float | None:
    """Genus of a closed mesh (handles summed over its pieces), None when the mesh is open.

    From ``chi = sum over pieces of (2 - 2 g) = 2 C - 2 G`` with ``chi = V - E + F`` counting
    only vertices used by a face: ``G = (2 C - chi) / 2``. A closed orientable 2-manifold
    gives a whole number; a half-integer flags a non-orientable or non-manifold mesh.
    """
    _require_mesh(mesh, "genus")
    if not mesh.is_closed:
        return None
    pieces, _ = face_components(mesh)
    chi = mesh.euler_characteristic - int(mesh.topology.isolated_vertices.sum())
    return (2 * pieces - chi) / 2


def _require_mesh(mesh, what: str) -> None:
    if not isinstance(mesh, PolyMesh):
        raise ParameterError(f"{what} needs a PolyMesh, got {type(mesh).__name__}")
