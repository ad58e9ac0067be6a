"""Compiled kernels of subdivision (numba, ``cache=True``): one level of Catmull-Clark and Loop
refinement.

This module gathers the kernels of :mod:`~splinekit.subdiv._kernel_rows` (stencil rows),
:mod:`~splinekit.subdiv._kernel_children` (child connectivity) and :mod:`~splinekit.subdiv._kernel_corners`
(corner arithmetic). It imports numba
and is itself imported only through :func:`splinekit._kernels.load` on the first large refinement,
never when splinekit is imported. The numpy/scipy construction in
:mod:`~splinekit.subdiv.catmull_clark`, :mod:`~splinekit.subdiv.loop` and
:mod:`~splinekit.subdiv.masks` is the reference; these kernels build the same
stencil matrix ``S`` row by row, straight into CSR arrays (sorted column
indices, no explicit zeros):

- rows ``0 .. V-1``: vertex points. Each vertex gets the mask of its parent
  rule (``rule_p``: smooth and dart use the scheme's smooth mask, crease the
  ``3/4, 1/8, 1/8`` mask along its two sharp edges, corner the vertex itself)
  and, where the rule changes at the next level, ``cp * parent + cc * child``
  with the child rule (``rule_c``) and the weights of
  :func:`~splinekit.subdiv.masks.vertex_point_matrix`. Sharp edges are those
  with sharpness ``> 0`` for the parent rule and ``> 1`` for the child rule.
- rows ``V .. V+E-1``: edge points, ``(1 - ws) smooth + ws midpoint`` with
  ``ws = clip(s, 0, 1)``.
- rows ``V+E ..`` (Catmull-Clark): face centroids.

Entries are summed in the order scipy's products and sums use for the
reference matrix wherever that is cheap (so most values agree bit for bit;
the others to one rounding). :func:`rows` serves three modes from the same row
code: row-length bounds, filling the CSR arrays, and ``S @ X`` without storing
``S`` (each row accumulated in CSR order as scipy's ``csr_matvecs`` does, so
the result is exactly ``S @ X`` for the ``S`` the fill mode builds).

Performance notes: the parallel kernels only split the work into chunks and
call a plain function per chunk (numba's parallel passes are slow to compile
on large bodies), and the row code is written out in one function with
scalar-only helpers (numba reference-counts every array argument of an
inlined function on each call, which cost more than the rows themselves).

The child connectivity (faces and the edge tables of
:class:`~splinekit.mesh.topology.Topology`) is numbered exactly as
:func:`splinekit.subdiv.split.child_topology` numbers it; the edge tables are
derived from the child faces plus three per-edge parent arrays (low end and
the two half-edges), so they can also be built later, on first use.

Corners of uniform meshes (``k = 4`` quads, ``k = 3`` triangles) are located by
arithmetic; other meshes pass ``cf`` (face of each corner).
"""

from ._kernel_children import cc_child_edges, cc_child_faces, loop_child_edges, loop_child_faces
from ._kernel_corners import CATMULL_CLARK, CORNER, CREASE, DART, LOOP, SMOOTH, vertex_corners
from ._kernel_rows import APPLY, BOUNDS, FILL, compact, rows

__all__ = ["APPLY", "BOUNDS", "CATMULL_CLARK", "CORNER", "CREASE", "DART", "FILL", "LOOP", "SMOOTH", "cc_child_edges",
           "cc_child_faces", "compact", "loop_child_edges", "loop_child_faces", "rows",
           "vertex_corners"]
