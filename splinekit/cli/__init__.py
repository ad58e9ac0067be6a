"""The ``splinekit`` command line.

Subcommands::

    splinekit list                                   the models and their parameters
    splinekit build [MODEL] [--set k=v ...] [-o DIR] [--format step,stl,...] [--tolerance T]
    splinekit info FILE                              what a STEP, IGES, BREP or mesh file holds
    splinekit render MODEL|FILE [-o picture.png|.jpg] [--color ...] [--size WxH]
    splinekit check MODEL                            cross-check a model against OpenCascade
    splinekit analyze MODEL|FILE --zebra|--isophotes|--curvature K|--draft X,Y,Z|--deviation SCAN|--continuity
    splinekit demo [-o picture.png]                  a NURBS surface, timed and drawn
    splinekit sweep MODEL --grid k=a:b:n|k=v1,v2 ... [-o DIR] [--format ...] [--measure ...]
                    [--scheduler tcp://host:8786] [--force]
                                                     a parameter sweep on Dask: every variant
                                                     built, measured, exported; results table
    splinekit compare [MODEL] [-o DIR]               one shape in every representation, measured
    splinekit neural fit MODEL -o m.nsdf [--steps N] a neural SDF trained on a model (extra: JAX)
    splinekit neural mesh m.nsdf -o out.stl          the zero set of a trained model as a mesh

Files go to the folder ``out`` unless ``-o`` names another place. ``--quiet`` silences
everything but errors, ``--verbose`` adds detail and tracebacks. Errors are one line on stderr
(``splinekit: error: ...``) with exit status 1 (2 for a malformed command line). SIGINT and
SIGTERM end a command with one line and status 130 / 143, leaving no temporary file (see
:mod:`splinekit._signals`); a closed stdout (``splinekit list | head -1``) ends it silently
with status 141, as SIGPIPE ends other Unix tools.

The models come from the ``models`` package; the environment variable ``SPLINEKIT_MODELS``
names another module with the same registry interface (``MODELS``, ``DEFAULT_MODEL``,
``get_model``, ``build_model``).

One module per command (:mod:`.listing`, :mod:`.build`, :mod:`.info`, :mod:`.render`,
:mod:`.check`, :mod:`.demo`, :mod:`.sweep`, :mod:`.analyze`, :mod:`.compare`, :mod:`.neural`), each a thin mapping
from arguments to library calls;
:mod:`.app` holds the parser and :func:`main`, :mod:`.console` the output formatting,
:mod:`.registry` the model registry.
"""

from __future__ import annotations

import warnings

from exporters import step as _step

from ..brep import TrimmedFace as _TrimmedFace
from ..interop import gprop as _gprop
from ..mesh import components as _components
from .app import COMMANDS, build_parser, main
from .build import DEFAULT_FORMATS, FORMATS, MESH_FORMATS
from .demo import demo_surface
from .info import EXACT_SUFFIXES, MESH_SUFFIXES, STEP_SUFFIXES, read_exact_shape
from .registry import model_mesh

__all__ = ["main", "COMMANDS", "build_parser", "demo_surface", "model_mesh", "read_exact_shape",
           "FORMATS", "MESH_FORMATS", "DEFAULT_FORMATS", "MESH_SUFFIXES", "STEP_SUFFIXES", "EXACT_SUFFIXES"]


def _former_mesh_genus(mesh):
    """``(components, genus or None)``, as the former ``splinekit.cli.mesh_genus`` returned."""
    return _components.face_components(mesh)[0], _components.genus(mesh)


def _former_area(surface, per_span: int = 6) -> float:
    """Area of a surface, as the former ``splinekit.cli._area`` (``per_span`` is ignored: the
    adaptive quadrature of :mod:`splinekit.brep` chooses its own nodes)."""
    return _TrimmedFace(surface).area()


# Library functions that lived here before the command line became a package: name -> (new
# home, function). They still resolve, with a DeprecationWarning naming the new home.
_MOVED = {
    "occ_area": ("splinekit.interop.gprop.occ_area", _gprop.occ_area),
    "occ_volume": ("splinekit.interop.gprop.occ_volume", _gprop.occ_volume),
    "occ_bbox": ("splinekit.interop.gprop.occ_bbox", _gprop.occ_bbox),
    "point_deviation": ("splinekit.interop.gprop.point_deviation", _gprop.point_deviation),
    "read_step_shape": ("exporters.step.read_step_shape", _step.read_step_shape),
    "mesh_genus": ("splinekit.mesh.components.face_components and .genus", _former_mesh_genus),
    "_area": ("splinekit.brep.TrimmedFace(surface).area()", _former_area),
}


def __getattr__(name):
    if name not in _MOVED:
        raise AttributeError(f"module 'splinekit.cli' has no attribute {name!r}")
    new_home, function = _MOVED[name]
    warnings.warn(f"splinekit.cli.{name} moved to {new_home}", DeprecationWarning, stacklevel=2)
    return function
