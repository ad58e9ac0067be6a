"""Compiled sparse product ``C = A @ B`` of two CSR matrices, for composing subdivision stencils
(numba, ``cache=True``; imported through :mod:`splinekit.subdiv._kernels` only).

Gustavson's row-by-row product in two passes over the same loops: :func:`product_counts` counts
each row of ``C`` (a marker array per thread finds the distinct columns), then
:func:`product_fill` writes it, accumulating in a dense row of the thread and summing the terms
in the order scipy's ``csr_matmat`` sums them (``A``'s row order, then ``B``'s), so the values
are those scipy computes. Unlike scipy, the columns of each row come out sorted, and rows are
split between threads. Work and memory are linear in the terms ``sum over A's entries of the
length of the row of B they select`` and in the output size.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(cache=True, parallel=True)
def product_counts(a_ptr, a_idx, b_ptr, b_idx, n_cols, n_chunks, counts):
    """``counts[r]`` = distinct columns of row ``r`` of ``A @ B`` (rows split in ``n_chunks``)."""
    n_rows = a_ptr.size - 1
    step = (n_rows + n_chunks - 1) // n_chunks
    for ch in prange(n_chunks):
        mark = np.full(n_cols, -1, np.int64)
        for r in range(ch * step, min(n_rows, (ch + 1) * step)):
            c = 0
            for i in range(a_ptr[r], a_ptr[r + 1]):
                j = a_idx[i]
                for q in range(b_ptr[j], b_ptr[j + 1]):
                    col = b_idx[q]
                    if mark[col] != r:
                        mark[col] = r
                        c += 1
            counts[r] = c


@njit(cache=True, parallel=True)
def product_fill(a_ptr, a_idx, a_val, b_ptr, b_idx, b_val, n_cols, n_chunks, c_ptr, c_idx, c_val):
    """Rows of ``A @ B`` into ``c_idx`` / ``c_val`` from ``c_ptr`` (the prefix sums of the counts),
    columns sorted."""
    n_rows = a_ptr.size - 1
    step = (n_rows + n_chunks - 1) // n_chunks
    for ch in prange(n_chunks):
        mark = np.full(n_cols, -1, np.int64)
        acc = np.zeros(n_cols)
        for r in range(ch * step, min(n_rows, (ch + 1) * step)):
            s = c_ptr[r]
            m = s
            for i in range(a_ptr[r], a_ptr[r + 1]):
                j = a_idx[i]
                x = a_val[i]
                for q in range(b_ptr[j], b_ptr[j + 1]):
                    col = b_idx[q]
                    if mark[col] != r:
                        mark[col] = r
                        c_idx[m] = col
                        m += 1
                        acc[col] = x * b_val[q]
                    else:
                        acc[col] += x * b_val[q]
            if m - s > 48:
                c_idx[s:m] = np.sort(c_idx[s:m])
            else:
                for u in range(s + 1, m):  # insertion sort: rows are short
                    key = c_idx[u]
                    v = u - 1
                    while v >= s and c_idx[v] > key:
                        c_idx[v + 1] = c_idx[v]
                        v -= 1
                    c_idx[v + 1] = key
            for u in range(s, m):
                c_val[u] = acc[c_idx[u]]
