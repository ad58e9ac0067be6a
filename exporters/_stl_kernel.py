"""The compiled (numba) kernel that fills binary STL records, loaded through
:func:`splinekit._kernels.load` by :func:`exporters._meshio.stl_fill_kernel`. The numpy path it must
agree with byte for byte is :func:`exporters.stl._binary_records` (the tests compare them)."""

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def fill(V, tris, out):  # pragma: no cover - compiled
    """Write the records of the triangles ``tris`` ``(T, 3)`` int64 of ``V`` ``(n, 3)`` float64 into
    ``out`` ``(T, 12)`` float32: the normal, then the three corners, every corner rounded to float32
    before the normal is computed (in float64), as the numpy path does."""
    f0 = np.float32(0.0)
    for t in range(tris.shape[0]):
        a, b, c = tris[t, 0], tris[t, 1], tris[t, 2]
        ax, ay, az = np.float32(V[a, 0]), np.float32(V[a, 1]), np.float32(V[a, 2])
        bx, by, bz = np.float32(V[b, 0]), np.float32(V[b, 1]), np.float32(V[b, 2])
        cx, cy, cz = np.float32(V[c, 0]), np.float32(V[c, 1]), np.float32(V[c, 2])
        # the normal of the float32 triangle, in float64 (float32 coordinates cannot overflow it)
        ux, uy, uz = np.float64(bx) - ax, np.float64(by) - ay, np.float64(bz) - az
        vx, vy, vz = np.float64(cx) - ax, np.float64(cy) - ay, np.float64(cz) - az
        nx = uy * vz - uz * vy
        ny = uz * vx - ux * vz
        nz = ux * vy - uy * vx
        length = np.sqrt(nx * nx + ny * ny + nz * nz)
        r = out[t]
        if length > 0 and np.isfinite(length):
            r[0], r[1], r[2] = nx / length, ny / length, nz / length
        else:
            r[0], r[1], r[2] = f0, f0, f0
        r[3], r[4], r[5] = ax, ay, az
        r[6], r[7], r[8] = bx, by, bz
        r[9], r[10], r[11] = cx, cy, cz

