"""Every representation of one shape, measured in one run: :func:`compare`.

One closed shape (default the torus; ``splinekit compare`` uses the mug) is held as exact
patches, a subdivision cage and its limit, a triangle mesh at a tolerance, a point cloud, a
signed-distance grid, its analytic implicit where one exists and a neural SDF (when the optional
``splinekit.neural`` imports). For each, at several resolutions: the bytes of the arrays held,
build time, time per point of four queries, accuracy against the exact surface, volume and
genus; then how memory and query time grow with resolution, and the cost and error of five
operations (render, boolean, bend, curvature, closest point), or why one does not apply.

``splinekit.compare`` is :func:`compare` (this package is named ``comparison`` so that
importing it does not replace that function on the ``splinekit`` module).
"""

from .chart import accuracy_chart
from .run import COLUMNS, REPRESENTATIONS, UNITS, compare
from .shape import REFERENCE_TOLERANCE, Reference, Shape, as_shape, sphere, torus
from .table import Table

__all__ = ["COLUMNS", "REFERENCE_TOLERANCE", "REPRESENTATIONS", "UNITS", "Reference", "Shape", "Table",
           "accuracy_chart", "as_shape", "compare", "sphere", "torus"]
