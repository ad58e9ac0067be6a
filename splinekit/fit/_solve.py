"""Banded linear solves for fitting systems.

Interpolation and least-squares matrices of B-splines are banded (a row has at
most ``p + 1`` consecutive non-zeros), so a system with ``n`` unknowns costs
``O(n p^2)`` and any number of right-hand sides share one factorization.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import FittingError

RANK_RTOL = 1e-7
"""A Cholesky pivot below this fraction of the largest one marks a rank-deficient
least-squares system (condition number above about 1e14)."""


def _bands(A: sp.spmatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int]:
    coo = A.tocoo()
    keep = coo.data != 0
    i, j, x = coo.row[keep], coo.col[keep], coo.data[keep]
    lower = int(max(0, (i - j).max(initial=0)))
    upper = int(max(0, (j - i).max(initial=0)))
    return i, j, x, lower, upper


def solve_banded_square(A: sp.spmatrix, rhs: np.ndarray, what: str) -> np.ndarray:
    """Solve the square sparse banded system ``A x = rhs`` (``rhs`` ``(n, k)``) by banded LU."""
    import scipy.linalg as la  # imported on use: it costs about 0.2 s, too much for `import splinekit`

    n = A.shape[0]
    i, j, x, lower, upper = _bands(A)
    ab = np.zeros((lower + upper + 1, n))
    ab[upper + i - j, j] = x
    try:
        out = la.solve_banded((lower, upper), ab, rhs, check_finite=False)
    except la.LinAlgError:
        raise FittingError(f"the {what} system is singular") from None
    if not np.isfinite(out).all():
        raise FittingError(
            f"the {what} system is numerically singular (non-finite solution)"
        )
    return out


def solve_banded_spd(ab: np.ndarray, rhs: np.ndarray, what: str) -> np.ndarray:
    """Solve ``M x = rhs`` for symmetric positive definite banded ``M`` in LAPACK upper storage.

    ``ab[u + i - j, j] = M[i, j]`` for ``i <= j`` (``u = ab.shape[0] - 1``);
    ``rhs`` ``(n, k)``. Banded Cholesky; raises :class:`FittingError` when a
    pivot falls below ``RANK_RTOL`` times the largest (rank deficiency, for
    example a knot span without data).
    """
    import scipy.linalg as la  # imported on use: it costs about 0.2 s, too much for `import splinekit`

    try:
        c = la.cholesky_banded(ab, lower=False, check_finite=False)
    except la.LinAlgError:
        raise FittingError(
            f"the {what} least-squares system is rank deficient (a knot span without data?)"
        ) from None
    pivots = np.abs(c[-1])
    if not pivots.min() > RANK_RTOL * pivots.max():
        k = int(np.argmin(pivots))
        raise FittingError(
            f"the {what} least-squares system is rank deficient: unknown control point {k} is not determined "
            "by the data (a knot span without enough data?)"
        )
    out = la.cho_solve_banded((c, False), rhs, check_finite=False)
    if not np.isfinite(out).all():
        raise FittingError(f"the {what} least-squares system is numerically singular")
    return out
