"""Composition of the stencils of a refinement: ``M = S_L @ ... @ S_1`` ``(V_L, V_0)``.

The product runs from the coarse end, ``M_k = S_k @ M_(k-1)``, each a sparse-sparse product
(scipy's): the rows of ``M_(k-1)`` are the short composed stencils of level ``k - 1``, so the work
of a level is the nonzeros of ``S_k`` times the mean row length of ``M_(k-1)``, every intermediate
is sparse, and the whole composition is linear in the size of the result (the levels grow
fourfold, so the last product dominates). Its cost is memory latency: each stencil row picks rows
of ``M_(k-1)`` scattered in memory. A compiled two-pass product split between two threads was
tried and was no faster than scipy's on a loaded 2-core machine (and three times slower with
sorted rows), and so were reorderings for locality (parents renumbered in first-touch order,
stencil rows sorted by parent, row blocks), so scipy serves; the benchmark
``benchmarks/bench_subdiv_compose.py`` measures the time against the bare reads of the parent
rows, and its docstring keeps the profile.
"""

from __future__ import annotations

import scipy.sparse as sp

__all__ = ["compose"]


def compose(stencils, n_vertices: int) -> sp.csr_matrix:
    """``S_L @ ... @ S_1`` for ``stencils = [S_1, ..., S_L]`` (``S_k`` maps level ``k - 1`` to ``k``)
    on ``n_vertices`` control vertices: ``(V_L, n_vertices)`` CSR (a row's columns unsorted, as
    scipy's products leave them); the identity when there is no stencil."""
    if not stencils:
        return sp.identity(n_vertices, format="csr")
    M = sp.csr_matrix(stencils[0], copy=True)
    for S in stencils[1:]:
        M = sp.csr_matrix(S @ M)
    return M
