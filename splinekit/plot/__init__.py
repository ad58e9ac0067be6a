"""Pictures of curves, surfaces and meshes as PNG files (matplotlib writes them, Agg backend).

A person would rather look at a surface than read its numbers; these helpers
write a shaded PNG so that anyone, including the test suite, can:

* :func:`render_surface` -- one surface and its control net (``splinekit demo``);
* :func:`render_patches` -- a set of exact patches colored by exact curvature
  (:func:`splinekit.curvature` on each patch's grid), normal or patch;
* :func:`render_mesh` -- a :class:`~splinekit.PolyMesh` colored by its discrete
  curvature, normal or patch / component.

Patches and meshes are drawn by a z-buffer rasterizer in numpy
(:mod:`splinekit.plot.raster`): what is in front is decided per pixel, so
surfaces that pierce or hide each other show right; silhouettes, depth jumps
and creases get a thin outline. Every PNG is written atomically (a temporary
file renamed into place).
"""

from .colors import COLOR_MODES, COLOR_SCALES
from .meshes import render_mesh
from .picture import DEFAULT_SIZE
from .surfaces import MAX_RESOLUTION, render_patches, render_surface

__all__ = ["render_surface", "render_patches", "render_mesh", "COLOR_MODES", "COLOR_SCALES", "DEFAULT_SIZE", "MAX_RESOLUTION"]
