"""Composition of the stencils of a refinement: ``M = S_L @ ... @ S_1`` ``(V_L, V_0)``.

The product runs from the coarse end, ``M_k = S_k @ M_(k-1)``, each a sparse-sparse product: the
rows of ``M_(k-1)`` are the (short) composed stencils of level ``k - 1``, so the work of a level is
the nonzeros of ``S_k`` times the mean row length of ``M_(k-1)`` and every intermediate is sparse;
the whole composition is linear in the size of the result (the levels' sizes grow fourfold, so
the last product dominates). Large products use a compiled two-pass product split between
threads (:mod:`splinekit.subdiv._kernel_compose`) with the values scipy computes; small ones,
or with compiled code switched off, scipy's.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import _kernels, limits
from ..errors import ParameterError, ResourceLimitError
from .scheme import KERNELS

__all__ = ["compose", "product"]

_I32 = np.iinfo(np.int32).max


def product(A: sp.csr_matrix, B: sp.csr_matrix) -> sp.csr_matrix:
    """``A @ B`` as CSR with sorted indices (the compiled product when ``A`` has enough rows)."""
    A, B = sp.csr_matrix(A), sp.csr_matrix(B)
    if A.shape[1] != B.shape[0]:
        raise ParameterError(f"stencil shapes {A.shape} and {B.shape} do not chain")
    K = _kernels.load(KERNELS, work=A.shape[0])
    if K is None:
        C = sp.csr_matrix(A @ B)
        C.sort_indices()
        return C
    n_rows, n_cols = A.shape[0], B.shape[1]
    # a few chunks per thread balance the load; each chunk allocates one (n_cols,) marker row
    n_chunks = max(1, min(-(-n_rows // 2048), 64))
    a_ptr, a_idx = A.indptr.astype(np.int64), A.indices.astype(np.int64)
    b_ptr, b_idx = B.indptr.astype(np.int64), B.indices.astype(np.int64)
    counts = np.empty(n_rows, np.int64)
    K.product_counts(a_ptr, a_idx, b_ptr, b_idx, n_cols, n_chunks, counts)
    c_ptr = np.zeros(n_rows + 1, np.int64)
    np.cumsum(counts, out=c_ptr[1:])
    nnz = int(c_ptr[-1])
    if max(nnz, n_cols, n_rows) >= _I32:
        raise ResourceLimitError(f"a composed subdivision stencil with {nnz:,} entries exceeds the int32 index range")
    limits.check(12.0 * nnz, f"a composed subdivision stencil with {nnz:,} entries")
    c_idx = np.empty(nnz, np.int64)
    c_val = np.empty(nnz)
    K.product_fill(a_ptr, a_idx, np.ascontiguousarray(A.data, dtype=np.float64), b_ptr, b_idx,
                   np.ascontiguousarray(B.data, dtype=np.float64), n_cols, n_chunks, c_ptr, c_idx, c_val)
    C = sp.csr_matrix((c_val, c_idx.astype(np.int32), c_ptr.astype(np.int32)), shape=(n_rows, n_cols), copy=False)
    C.has_sorted_indices = True
    if not c_val.all():  # exact cancellation (scipy's product drops such zeros too)
        C.eliminate_zeros()
    return C


def compose(stencils, n_vertices: int) -> sp.csr_matrix:
    """``S_L @ ... @ S_1`` for ``stencils = [S_1, ..., S_L]`` (``S_k`` maps level ``k - 1`` to ``k``)
    on ``n_vertices`` control vertices: ``(V_L, n_vertices)`` CSR, sorted indices; the identity
    when there is no stencil."""
    if not stencils:
        return sp.identity(n_vertices, format="csr")
    M = sp.csr_matrix(stencils[0], copy=True)
    M.sort_indices()
    for S in stencils[1:]:
        M = product(S, M)
    return M
