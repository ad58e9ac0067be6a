"""Tensor-product rule of :mod:`.integrate` for untrimmed faces (natural domain, or one loop around
an axis-parallel rectangle): a Gauss-Kronrod pair in both directions on cells of the faces'
Bézier patches.

Every face of the same degrees is held in one rule, so a pass of the adaptive loop evaluates the
new cells of all of them at once (the Newell teapot's 32 patches: one evaluation per pass
instead of 32; the per-call overhead of numpy, not the arithmetic, was the cost). A cell is
``[patch, a0, a1, b0, b1]``: a box in the local ``[0, 1]^2`` parameters of one Bézier patch of a
face, evaluated with Bernstein polynomials and the patch's own net, which makes patches of
different faces (and different knot vectors) interchangeable.

A cell's error is ``|K x K - G x K| + |K x K - K x G|`` (the u and v parts); cells whose error is
too large are bisected across the direction with the larger part.
"""

from __future__ import annotations

import math

import numpy as np

from .. import limits
from ..basis.algebra import bezier_segments

__all__ = ["TensorRule", "bezier_nets", "group_key"]

CHUNK_POINTS = 4000
"""Cells are evaluated in chunks of at most this many nodes (at least one cell): every temporary
``(points, 3)`` or homogeneous ``(points, 4)`` array then stays under glibc's 128 KiB mmap
threshold and is recycled from the heap, where larger ones were mapped afresh each time and
first-touch page faults cost more than the arithmetic (the teapot's 192 cells at 10-21: 3300
faults and 15.5 ms CPU per evaluation in one block, none and 9.4 ms in chunks of 4096 nodes)."""


def group_key(surface) -> tuple:
    """Faces whose surfaces share this key go into one :class:`TensorRule`: the degrees, whether
    the surface is rational, and the width of its (homogeneous) coefficients."""
    return surface._pu, surface._pv, surface._rational, surface._coefs.shape[-1]


def bezier_nets(surface) -> np.ndarray:
    """``(su, p + 1, sv, q + 1, k)``: the (homogeneous) Bézier nets of the surface's spans, patch
    ``[i, :, j]`` on ``[bu[i], bu[i + 1]] x [bv[j], bv[j + 1]]`` of ``surface.bezier_breakpoints()``.
    Cached on the (immutable) surface."""
    cache = surface._cache
    if "integration bezier nets" not in cache:
        _, su = bezier_segments(surface._pu, surface._ku, surface._coefs)  # (su, p + 1, nv, k)
        _, sv = bezier_segments(surface._pv, surface._kv, su.transpose(2, 0, 1, 3))  # (sv, q + 1, su, p + 1, k)
        nets = np.ascontiguousarray(sv.transpose(2, 3, 0, 1, 4))
        nets.setflags(write=False)
        cache["integration bezier nets"] = nets
    return cache["integration bezier nets"]


def bernstein_ders(p: int, t: np.ndarray) -> np.ndarray:
    """``(2, p + 1) + t.shape``: the degree-``p`` Bernstein polynomials and their derivatives at
    ``t``, from the power form ``C(p, i) t^i (1 - t)^(p - i)`` (positive terms on [0, 1]: a few
    ulps; the polynomial extension just outside it), derivatives
    ``p (B^(p-1)_(i-1) - B^(p-1)_i)``."""
    s = 1.0 - t
    tp, sp = np.empty((p + 1,) + t.shape), np.empty((p + 1,) + t.shape)
    tp[0] = sp[0] = 1.0
    for i in range(1, p + 1):  # powers t^i, (1 - t)^i: p small products
        np.multiply(tp[i - 1], t, out=tp[i])
        np.multiply(sp[i - 1], s, out=sp[i])
    expand = (slice(None),) + (None,) * t.ndim
    out = np.empty((2, p + 1) + t.shape)
    out[0] = np.array([math.comb(p, i) for i in range(p + 1)], float)[expand] * tp * sp[::-1]
    low = np.array([math.comb(p - 1, i) for i in range(p)], float)[expand] * tp[:-1] * sp[-2::-1]  # degree p - 1
    out[1, 0] = -p * low[0]
    out[1, 1:-1] = p * (low[:-1] - low[1:])
    out[1, -1] = p * low[-1]
    return out


class TensorRule:
    """The Gauss-Kronrod pair ``gk`` (:mod:`.kronrod`) in both directions on cells ``(m, 5)`` =
    ``[patch, a0, a1, b0, b1]`` of the Bézier patches of ``faces`` (all of one :func:`group_key`);
    ``rects[i]`` is the face's axis-parallel rectangle ``(u0, u1, v0, v1)`` when its only loop is
    one, else None (natural domain)."""

    def __init__(self, faces, rects, integrand, gk):
        first = faces[0].surface
        self.gk = gk
        self._weights = np.stack([gk.wk, gk.wg])  # (2, n): the Kronrod and Gauss weights
        self.p, self.q, self.rational = first._pu, first._pv, first._rational
        self.integrand = integrand
        parts = [_patches(face, rect) for face, rect in zip(faces, rects)]
        self.nets = np.concatenate([p[0] for p in parts])  # (patches, p + 1, q + 1, k)
        self.hu = np.concatenate([p[1] for p in parts])  # (patches,) the patches' widths in u, v
        self.hv = np.concatenate([p[2] for p in parts])
        self.sign = np.concatenate([p[4] for p in parts])  # (patches,) -1 on reversed faces
        cells = np.concatenate([p[3] for p in parts])
        offsets = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
        cells[:, 0] += np.repeat(offsets, [len(p[3]) for p in parts])  # the face's patch -> the rule's
        self._initial = cells

    def initial(self):
        return self._initial

    def _derivatives(self, patch, Ba, Bb):
        """``S``, ``Su``, ``Sv`` ``(m, n, n, 3)`` on the tensor grids of ``m`` cells of the
        patches ``patch`` ``(m,)``, given the Bernstein values and derivatives at the cells' local
        nodes, ``Ba`` ``(2, m, n, p + 1)`` in u and ``Bb`` ``(2, m, n, q + 1)`` in v, their
        derivatives already divided by the patches' widths (so ``Su``, ``Sv`` are derivatives with
        respect to the faces' own parameters). Two small contractions per cell: the Bernstein
        values in u with the net, then in v."""
        m, n = Ba.shape[1:3]
        net = self.nets[patch]  # (m, p + 1, q + 1, k)
        p1, q1, k = net.shape[1:]
        # batched matrix products on contiguous operands, each output contiguous in (m, i, j, k)
        # so that the integrand gets (m n n, k) rows without a copy (einsum's generic loop, a
        # transposed result or a strided operand cost 5-10x more here)
        net = net.reshape(m, 1, p1, q1 * k)
        A0, A1 = ((Ba[d][:, None] @ net).reshape(m, n, q1, k) for d in (0, 1))  # (m, i, q + 1, k)
        Bb = Bb[:, :, None]  # (d/dv, m, 1, j, q + 1)
        D = {(0, 0): Bb[0] @ A0, (1, 0): Bb[0] @ A1, (0, 1): Bb[1] @ A0}  # (m, i, j, k)
        if not self.rational:
            return D[0, 0], D[1, 0], D[0, 1]
        w, wu, wv = D[0, 0][..., -1:], D[1, 0][..., -1:], D[0, 1][..., -1:]
        S = D[0, 0][..., :-1] / w
        return S, (D[1, 0][..., :-1] - wu * S) / w, (D[0, 1][..., :-1] - wv * S) / w

    def evaluate(self, cells, targets):
        # what is per cell is computed for all of them; the per-node work runs in chunks, whose
        # temporaries are bounded: only the per-cell arrays grow with the number of cells
        n = self.gk.n
        limits.check(len(cells) * n * 2 * (self.p + self.q + 2) * 8, "tensor quadrature Bernstein values")
        patch = cells[:, 0].astype(np.intp)
        da, db = cells[:, 2] - cells[:, 1], cells[:, 4] - cells[:, 3]
        a = cells[:, 1, None] + da[:, None] * self.gk.t  # (m, n) local parameters
        b = cells[:, 3, None] + db[:, None] * self.gk.t
        Ba = np.ascontiguousarray(bernstein_ders(self.p, a).transpose(0, 2, 3, 1))  # (d/du, m, i, p + 1)
        Bb = np.ascontiguousarray(bernstein_ders(self.q, b).transpose(0, 2, 3, 1))  # (d/dv, m, j, q + 1)
        Ba[1] /= self.hu[patch][:, None, None]  # d/da -> d/du: the patch's width
        Bb[1] /= self.hv[patch][:, None, None]
        jac = (0.25 * da * db * self.hu[patch] * self.hv[patch])[:, None]
        step = max(1, CHUNK_POINTS // (n * n))
        q, absval = zip(*(self._sums(patch[i:i + step], Ba[:, i:i + step], Bb[:, i:i + step])
                          for i in range(0, len(cells), step)))
        q, absval = np.concatenate(q), np.concatenate(absval) * jac
        kk, kg, gk = q[:, 0, 0] * jac, q[:, 0, 1] * jac, q[:, 1, 0] * jac
        err_u, err_v = np.abs(kk - gk), np.abs(kk - kg)
        return kk, err_u + err_v, absval, (err_u, err_v), len(cells) * n * n

    def _sums(self, patch, Ba, Bb):
        """The weighted sums of the integrand over one chunk of cells, before their Jacobians:
        ``q (m, 2, 2, k)`` (u rule, v rule: Kronrod 0, Gauss 1) and ``absval (m, k)`` (Kronrod,
        of ``|f|``)."""
        m, n = Ba.shape[1:3]
        S, Su, Sv = (x.reshape(-1, 3) for x in self._derivatives(patch, Ba, Bb))
        f = self.integrand(S, Su, Sv, np.repeat(self.sign[patch], n * n))  # (m * n * n, k)
        k = f.shape[-1]
        f = f.reshape(m, n, n, k)  # (m, i, j, k): u node i, v node j
        # contract j then i with matmuls on contiguous arrays (transposed operands were slower)
        q = (self._weights @ (self._weights @ f).reshape(m, n, 2 * k)).reshape(m, 2, 2, k)
        return q, self.gk.wk @ (self.gk.wk @ np.abs(f))

    def split(self, cells, info, targets):
        err_u, err_v = info
        in_u = (err_u / targets).max(axis=1) >= (err_v / targets).max(axis=1)
        mid_a = 0.5 * (cells[:, 1] + cells[:, 2])
        mid_b = 0.5 * (cells[:, 3] + cells[:, 4])
        lo, hi = cells.copy(), cells.copy()
        lo[in_u, 2] = hi[in_u, 1] = mid_a[in_u]
        lo[~in_u, 4] = hi[~in_u, 3] = mid_b[~in_u]
        return np.concatenate([lo, hi])


def _patches(face, rect):
    """``(nets (P, p + 1, q + 1, k), hu (P,), hv (P,), cells (P, 5), sign (P,))``: the face's
    Bézier patches that meet its rectangle ``rect`` (all when None), their widths in u and v, one
    initial cell on each (patch indices from 0), the face's orientation. Cached on the face."""
    key = ("tensor patches", rect)
    if key in face._cache:
        return face._cache[key]
    surface = face.surface
    bu, bv = surface.bezier_breakpoints()
    net = bezier_nets(surface)
    iu, au = _spans(bu, None if rect is None else rect[:2])
    iv, av = _spans(bv, None if rect is None else rect[2:])
    nets = net[iu][:, :, iv].transpose(0, 2, 1, 3, 4).reshape((-1,) + net.shape[1:2] + net.shape[3:])
    A0, B0 = np.meshgrid(au[:, 0], av[:, 0], indexing="ij")
    A1, B1 = np.meshgrid(au[:, 1], av[:, 1], indexing="ij")
    index = np.arange(len(iu) * len(iv), dtype=float)
    out = (nets, np.repeat(np.diff(bu)[iu], len(iv)), np.tile(np.diff(bv)[iv], len(iu)),
           np.stack([index, A0.ravel(), A1.ravel(), B0.ravel(), B1.ravel()], axis=1),
           np.full(index.size, -1.0 if face.reversed else 1.0))
    face._cache[key] = out
    return out


def _spans(breaks, interval):
    """The spans of ``breaks`` that meet ``interval`` ``(lo, hi)`` (all of them when None):
    ``(indices (s,), local ranges (s, 2))`` in each span's ``[0, 1]`` parameter. A rectangle a
    little past the domain (within the trims' slack) gives local ranges past [0, 1]: the
    polynomial extension of the end spans, as for Green's trims."""
    n = len(breaks) - 1
    if interval is None:
        return np.arange(n), np.tile([0.0, 1.0], (n, 1))
    lo, hi = interval
    inside = (breaks[1:] > lo) & (breaks[:-1] < hi)
    inside[0] |= hi <= breaks[0]  # a rectangle wholly past an end: the end span's extension
    inside[-1] |= lo >= breaks[-1]
    idx = np.flatnonzero(inside)
    h = breaks[idx + 1] - breaks[idx]
    local = np.tile([0.0, 1.0], (len(idx), 1))
    local[0, 0] = (lo - breaks[idx[0]]) / h[0]  # breaks[idx[0]] <= lo unless idx[0] == 0
    local[-1, 1] = (hi - breaks[idx[-1]]) / h[-1]
    return idx, local
