"""File writers and readers (STEP, STL, 3MF, OBJ, PLY, glTF) built on splinekit.

Nothing is here yet; the exporters issue fills this package.
"""

# mesh formats (STL, OBJ, PLY, 3MF, glTF binary)
from ._meshio import export_mesh, import_mesh
from .gltf import export_glb, import_glb
from .obj import export_obj, import_obj
from .ply import export_ply, import_ply
from .stl import export_stl, import_stl
from .threemf import export_3mf, import_3mf

from .step import export_step, import_step
