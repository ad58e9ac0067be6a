"""Pictures of polygon meshes, coloured by their discrete curvature, normal or patch."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..mesh import PolyMesh
from ..mesh.components import face_components
from ..mesh.geometry import triangulate
from . import colors, picture


def render_mesh(mesh, path, *, color: str = "curvature", scale: str = "percentile", size=picture.DEFAULT_SIZE,
                view=(28.0, -58.0), title=None) -> str:
    """Write a shaded PNG of a 3-D :class:`~splinekit.PolyMesh` to ``path`` (atomically); returns the path.

    Faces are flat-shaded by their own normals, with a z-buffer deciding what is
    in front per pixel. The curvature modes use the mesh's discrete curvatures
    (``gaussian_curvature``, ``mean_curvature``, per vertex, interpolated across
    each face; 0 on the boundary). On CAD meshes with sharp edges the discrete
    curvature concentrates at the edge and corner vertices (that is what it
    measures), so ``normal`` or ``patch`` reads better there; ``patch`` uses the
    mesh's ``face_patch`` when it has one (a tessellation), else its connected
    components. Options as in :func:`render_patches`.
    """
    size, view = picture.check_render_options(color, scale, size, view)
    if not isinstance(mesh, PolyMesh):
        raise ParameterError(f"render_mesh needs a PolyMesh, got {type(mesh).__name__}")
    if mesh.vertices.shape[1] != 3 or mesh.n_faces == 0:
        raise ParameterError(f"render_mesh needs a 3-D mesh with faces; got {mesh.vertices.shape[1]}-D with {mesh.n_faces} faces")
    corners, source = triangulate(mesh)  # fan triangles and the face each came from
    tris = np.asarray(mesh.vertices, dtype=np.float64)[corners]
    corner_values = None
    if color not in ("normal", "patch"):
        corner_values = colors.curvature_field(color, np.asarray(mesh.gaussian_curvature), np.asarray(mesh.mean_curvature))[corners]
    flat = np.repeat(picture.triangle_normals(tris)[:, None, :], 3, axis=1)
    patch_id = None
    if color == "patch":
        face_patch = getattr(mesh, "face_patch", None)
        patch_id = (np.asarray(face_patch) if face_patch is not None else face_components(mesh)[1])[source]
    outward = 0
    if mesh.is_closed:  # closed PolyMeshes are consistently oriented; the volume's sign says which way
        outward = int(np.sign(float(mesh.volume)))
    return picture.draw(tris, flat, color, scale, size, view, title, path, corner_values=corner_values,
                        patch_id=patch_id, outward=outward)
