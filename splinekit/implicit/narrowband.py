"""A sampled signed distance that stores only the samples near its surface: :class:`NarrowBandSDF`."""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, as_int
from ..errors import ParameterError
from ._checks import positive
from .sampled import SampledSDF, _check_count

__all__ = ["NarrowBandSDF"]


class NarrowBandSDF(SampledSDF):
    """A sampled signed distance that stores only the samples with ``|d| < band``.

    Samples outside the band read as ``+band`` or ``-band`` (their sign is kept
    in a bit array, 1 bit per sample); interpolation then works as for
    :class:`SampledSDF`. Values within about one voxel of the band's edge are
    blends with the clamped ``+-band`` samples, so the field equals the dense
    grid's interpolant only where ``|F| < band - sqrt(3) h`` (trilinear) or
    ``band - 2 sqrt(3) h`` (cubic, whose stencil reaches a cell further), ``h``
    the voxel size; its sign is right everywhere.

    Parameters
    ----------
    indices : (m,) int
        Flat C-order indices of the stored samples (any order, unique).
    values : (m,)
        Their signed distances, ``|values| < band``.
    inside : (nx, ny, nz) bool array
        True where a sample is inside (negative); read for out-of-band samples.
    shape, origin, spacing, band, interpolation
        As in :class:`SampledSDF`; ``band > 0`` in model units.
    """

    def __init__(self, indices, values, inside, shape, origin, spacing, band, interpolation: str = "linear"):
        shape = tuple(as_int(s, "shape", minimum=2) for s in shape)
        if len(shape) != 3:
            raise ParameterError(f"shape must be 3 ints, got {shape!r}")
        _check_count(shape)
        band = positive(band, "band")
        idx = np.asarray(indices)
        if idx.ndim != 1 or (idx.size and idx.dtype.kind not in "iu"):
            raise ParameterError(f"indices must be a 1-D integer array, got shape {idx.shape} dtype {idx.dtype}")
        idx = idx.astype(np.int64)
        vals = as_float_array(values, "values")
        if vals.shape != idx.shape:
            raise ParameterError(f"values must have the shape of indices {idx.shape}, got {vals.shape}")
        total = int(np.prod(shape))
        if idx.size and (idx.min() < 0 or idx.max() >= total):
            bad = int(idx[(idx < 0) | (idx >= total)][0])
            raise ParameterError(f"index {bad} lies outside the grid of {total} samples")
        bad = ~(np.isfinite(vals) & (np.abs(vals) < band))
        if bad.any():
            i = int(np.argmax(bad))
            raise ParameterError(f"values[{i}] = {vals[i]!r} must be finite with |value| < band = {band!r}")
        ins = np.asarray(inside, dtype=bool)
        if ins.shape != shape:
            raise ParameterError(f"inside must have shape {shape}, got {ins.shape}")
        order = np.argsort(idx, kind="stable")
        idx, vals = idx[order], vals[order]
        if idx.size > 1 and (np.diff(idx) == 0).any():
            raise ParameterError(f"index {int(idx[np.argmax(np.diff(idx) == 0)])} is given twice")
        self._band = band
        # 4-byte indices when they fit: a stored sample then costs 12 bytes, not 16
        self._idx = idx.astype(np.int32) if total < 2**31 else idx
        self._bvals = np.ascontiguousarray(vals)
        self._signbits = np.packbits(ins.ravel())
        for a in (self._idx, self._bvals, self._signbits):
            a.setflags(write=False)
        self._grid_setup(None, shape, origin, spacing, interpolation)

    @property
    def band(self) -> float:
        return self._band

    @property
    def n_stored(self) -> int:
        """Number of samples stored explicitly (inside the band)."""
        return int(self._idx.size)

    @property
    def values(self) -> np.ndarray:
        """The dense ``(nx, ny, nz)`` samples (built on request; +-band outside the band)."""
        return self._grid_dense()

    def _grid_dense(self) -> np.ndarray:
        inside = np.unpackbits(self._signbits, count=int(np.prod(self._shape))).astype(bool)
        out = np.where(inside, -self._band, self._band)
        out[self._idx] = self._bvals
        return out.reshape(self._shape)

    def nbytes(self) -> int:
        """Bytes held by the sparse storage."""
        return int(self._idx.nbytes + self._bvals.nbytes + self._signbits.nbytes)

    def _grid_gather(self, i, j, k):
        ny, nz = self._shape[1], self._shape[2]
        flat = (np.asarray(i, dtype=np.int64) * ny + j) * nz + k
        flat, = np.broadcast_arrays(flat)
        pos = np.searchsorted(self._idx, flat)
        pos_c = np.minimum(pos, max(self._idx.size - 1, 0))
        hit = (self._idx[pos_c] == flat) if self._idx.size else np.zeros(flat.shape, bool)
        bits = self._signbits[flat >> 3] >> (7 - (flat & 7)) & 1
        out = np.where(bits.astype(bool), -self._band, self._band)
        if self._idx.size:
            out = np.where(hit, self._bvals[pos_c], out)
        return out

    def __repr__(self):
        return super().__repr__()[:-1] + f", band={self._band!r}, stored={self.n_stored})"
