"""File writers and readers built on splinekit.

* exact geometry: STEP AP214 through OpenCascade (:func:`export_step`,
  :func:`import_step`), curves and surfaces as B-spline geometry, B-rep solids,
  shells and trimmed faces exactly, with names and units; IGES
  (:func:`export_iges`, :func:`import_iges`) and OCC's native ``.brep``
  (:func:`export_brep`, :func:`import_brep`) for the same B-rep objects;
* meshes: STL (binary and ASCII), OBJ, PLY (binary and ASCII), 3MF and glTF
  binary (.glb), written with numpy; :func:`export_mesh` / :func:`import_mesh`
  choose the format from the suffix.

Every writer writes a temporary file beside the target and renames it into
place, so a failed or interrupted export leaves no partial file and never
damages an existing one.

Import it beside splinekit, splinekit first::

    import splinekit as sk
    from exporters import export_step, export_stl

``exporters`` is a common name: once splinekit is imported, ``import exporters``
raises :class:`splinekit.errors.ShadowedPackageError` (an ImportError naming
both folders and the fix) when another project's ``exporters`` comes first on
``sys.path``, instead of silently importing that one.
"""

from ._meshio import export_mesh, import_mesh
from .brep import export_brep, import_brep
from .gltf import export_glb, import_glb
from .iges import export_iges, import_iges
from .obj import export_obj, import_obj
from .ply import export_ply, import_ply
from .step import STEP_UNITS, StepItem, export_step, import_step
from .stl import export_stl, import_stl
from .threemf import export_3mf, import_3mf

__all__ = [
    "export_step",
    "import_step",
    "StepItem",
    "STEP_UNITS",
    "export_iges",
    "import_iges",
    "export_brep",
    "import_brep",
    "export_mesh",
    "import_mesh",
    "export_stl",
    "import_stl",
    "export_obj",
    "import_obj",
    "export_ply",
    "import_ply",
    "export_3mf",
    "import_3mf",
    "export_glb",
    "import_glb",
]
