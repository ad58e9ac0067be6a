"""The compiled (numba) kernel that fills binary STL records, loaded through
:func:`splinekit._kernels.load` by :func:`exporters._meshio.stl_fill_kernel`. The numpy path it must
agree with byte for byte is :func:`exporters.stl._write_records` (the tests compare them)."""

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def fill(V, tris, N, out):  # pragma: no cover - compiled
    """Write the records of the triangles ``tris`` ``(T, 3)`` int64 of ``V`` ``(n, 3)`` float64 with
    the normals ``N`` ``(T, 3)`` float64 into ``out`` ``(T, 12)`` float32: the normal, then the three
    corners, each value rounded to float32, as the numpy path does."""
    for t in range(tris.shape[0]):
        r = out[t]
        r[0], r[1], r[2] = np.float32(N[t, 0]), np.float32(N[t, 1]), np.float32(N[t, 2])
        for k in range(3):
            v = tris[t, k]
            r[3 + 3 * k] = np.float32(V[v, 0])
            r[4 + 3 * k] = np.float32(V[v, 1])
            r[5 + 3 * k] = np.float32(V[v, 2])
