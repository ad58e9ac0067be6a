"""Adaptive, watertight tessellation of patch sets (:func:`tessellate_patches`).

Design (whole-array work; Python loops run over degree pairs, sample-count
classes, multi-span patches and refinement rounds, never over points or
triangles):

1. Every patch is cut into Bézier cells (:mod:`.cells`). A cell is sampled on a
   uniform ``n x m`` grid of its local parameters; the a-priori counts come from
   bounds on the second derivatives (linear interpolation over a step ``h``
   errs by at most ``h^2 / 8 max |S''|``) and from the angle tolerance
   (:mod:`.counts`).
2. Shared edges must carry the same samples on both sides. Each cell has a
   "u node" (the samples along its two u-running edges) and a "v node". Cell
   edges that coincide (same points at t = 0, 1/4, 1/2, 3/4, 1, in either
   orientation), and neighbouring cells of one patch, link their nodes; every
   connected set of nodes takes the largest count of its members
   (:mod:`.counts`). Uniform samples of a whole edge are symmetric under
   reversal, so orientation does not matter.
3. Evaluation (:mod:`.grids`): the cells of single-cell patches (Bézier patch sets)
   and of patches of at most ``TENSOR_CELLS`` cells in batches of equal degrees and
   counts as ``Bu @ net @ Bv^T`` (two products for the whole batch); a larger
   multi-span patch as one tensor grid on the concatenation of its spans' samples
   (banded collocation matrices). Each grid is evaluated at the
   vertices (with first partials, for the normals), at the half-step points
   (edge midpoints, quad centres) and at the triangle centres, and one fused
   pass measures the deviations and normal angles per cell.
4. A pilot round at no more than ``PILOT`` steps per cell predicts the counts
   (the error is quadratic in the step); cells still over the tolerance are
   refined by ``sqrt(deviation / tolerance)``, the counts re-propagated and
   only the changed cells (patches) evaluated again.
5. Grids are triangulated by index arithmetic (:mod:`.assembly`). Only vertices
   on a grid's boundary can merge: collapsed cell edges (poles) become one
   vertex, the rest are welded where they lie within the weld distance (a sweep
   along one direction, :func:`.welding.close_pairs`), and only triangles
   touching a grid boundary are remapped, and dropped when they collapse.
   Normals at collapsed points are limit normals (:mod:`.poles`).
6. A closed body facing inward is turned outward; the common cases (an open
   mesh: nothing welded; an outward body: clearly positive volume) are told
   apart cheaply, without building the mesh's edge table.

Small models spend most of their time in fixed per-call work rather than in
evaluation, so the bookkeeping avoids sorts, sparse matrices and per-patch
Python work where a cached table or one whole-array operation does; what does
not depend on the tolerance (steps 1 and 2, and the bounds of step 1) is
computed once per patch set and kept on its first patch. Once the
compiled kernels (:mod:`._kernels`) are loaded (:mod:`splinekit._kernels`: a
large tessellation, or enough work done, loads them), the fused pass, the weld,
the triangle remap, the vertex gathering, the pole normals and the rational
a-priori bounds run compiled, with the numpy path's results bit for bit (the
fused pass's normals to rounding).
"""

from __future__ import annotations

import math

import numpy as np

from .. import _kernels, limits
from ..tolerances import WELD
from .assembly import assemble, outward
from .cells import cells_of_patches, second_derivative_bounds
from .counts import MAX_COUNT, count_rates, counts_from_rates, node_groups, propagate
from .grids import Grid
from .poles import CellIndex
from .result import Tessellation

__all__ = ["tessellate_patches"]

MAX_ROUNDS = 8
"""Largest number of measure-and-refine rounds."""
ANGLE_MAX_COUNT = 64
"""The angle criterion refines a cell direction only while it has fewer steps than this."""
BYTES_PER_TRIANGLE = 420
"""Peak memory per triangle of a tessellation (the sample grids of every round, the
welding tables and the result), measured on the teapot at 1.6 and 5.5 million
triangles (405-410 bytes); what :func:`splinekit.limits.check` is given."""
TENSOR_CELLS = 16
"""A patch of more Bézier cells than this is evaluated as one tensor grid on the concatenation of
its spans' samples (banded collocation matrices, no welds along its knot lines); a smaller one
goes cell by cell like a Bézier patch set, its cells' shared edges welded. The tensor grid's
set-up (ten sparse collocation matrices) costs ~2.5 ms, five times a whole 8-cell sphere by cells;
at 81 cells (a 12 x 12 bicubic net) the cells' welds cost more (24 against 17 ms at 1e-3)."""
PILOT = 8
"""Largest per-direction count of the first (pilot) evaluation of a cell."""
PILOT_TARGET = 0.8
"""Counts predicted from the pilot aim at this fraction of the tolerance."""
# WELD (from splinekit.tolerances): weld and edge-matching distance, relative to the model's
# bounding-box diagonal.


class _Prepared:
    """What a patch set's tessellation needs at any tolerance, computed once per patch set and
    kept in the first patch's ``_cache`` (surfaces are immutable): the Bézier cells and their
    per-cell tables, the second-derivative bounds and the linked cell nodes (which depend on the
    weld distance, i.e. on the model size only)."""

    def __init__(self, patches, weld_tol):
        self.patches, self.weld_tol = tuple(patches), weld_tol
        self.cellsets = cellsets = cells_of_patches(patches)
        sizes = [len(cs) for cs in cellsets]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.C = C = int(self.offsets[-1])
        self.set_of = np.repeat(np.arange(len(cellsets)), sizes)
        self.patch_of = np.concatenate([cs.patch for cs in cellsets])
        self.span_of = np.concatenate([cs.span for cs in cellsets])
        self.box_of = np.concatenate([cs.box for cs in cellsets])
        # cells of one patch are contiguous, in (iu, iv) order with iu major
        self.n_cells = np.bincount(self.patch_of, minlength=len(patches))
        self.first = np.full(len(patches), C, dtype=np.int64)
        np.minimum.at(self.first, self.patch_of, np.arange(C))
        self.nsv = np.zeros(len(patches), dtype=np.int64)
        np.maximum.at(self.nsv, self.patch_of, self.span_of[:, 1] + 1)
        self.labels, self.collapsed = node_groups(cellsets, self.patch_of, self.span_of, self.nsv, weld_tol)
        self.rates = count_rates(cellsets, [second_derivative_bounds(cs) for cs in cellsets])
        self.cell_index = CellIndex(cellsets, self.offsets, self.first, self.n_cells, self.nsv, self.box_of)

    @classmethod
    def of(cls, patches, weld_tol):
        """The cached preparation of ``patches`` (the same surface objects in the same order and
        the same weld distance), else a new one, cached."""
        cache = getattr(patches[0], "_cache", None)
        prep = cache.get("tessellate_patches") if cache is not None else None
        if not (prep is not None and prep.weld_tol == weld_tol and len(prep.patches) == len(patches)
                and all(a is b for a, b in zip(prep.patches, patches))):  # fmt: skip
            prep = cls(patches, weld_tol)
            if cache is not None:
                cache["tessellate_patches"] = prep
        return prep


def tessellate_patches(patches, tol: float, angle_tol, weld_scale: float, *, orient: bool = True) -> Tessellation:
    """Tessellate validated 3-D spline patches (see :func:`splinekit.tessellation.tessellate`).

    ``tol`` is the absolute chordal tolerance, ``angle_tol`` radians or None,
    ``weld_scale`` the model size (bounding-box diagonal) used for welding. The
    tolerance-independent preparation is cached on the first patch (:class:`_Prepared`).
    ``orient``: turn a closed body that faces inward outward (:func:`.assembly.outward`);
    False keeps every patch's ``Su x Sv`` (B-rep faces, whose orientation is given).
    """
    weld_tol = WELD * weld_scale
    prep = _Prepared.of(patches, weld_tol)
    cellsets, offsets, C, set_of = prep.cellsets, prep.offsets, prep.C, prep.set_of
    patch_of, span_of, box_of, n_cells, first, nsv = prep.patch_of, prep.span_of, prep.box_of, prep.n_cells, prep.first, prep.nsv
    labels, collapsed = prep.labels, prep.collapsed
    any_collapsed = collapsed.any(axis=1)
    multi = n_cells[patch_of] > TENSOR_CELLS
    any_multi = bool(multi.any())
    nu, nv = counts_from_rates(prep.rates, tol, angle_tol)
    done_u = np.zeros(C, dtype=np.int64)  # counts each cell was last evaluated with
    done_v = np.zeros(C, dtype=np.int64)
    record = np.full(C, -1, dtype=np.int64)  # which grid holds each cell's latest evaluation
    grids: list[Grid] = []
    # The a-priori counts are upper estimates (a bound over the whole cell); a pilot
    # evaluation at no more than PILOT steps measures the actual error, from which the
    # counts are predicted (error ~ h^2), up or down. Later rounds only refine.
    apriori_u, apriori_v = propagate(nu, nv, labels)
    nu, nv = np.minimum(apriori_u, PILOT), np.minimum(apriori_v, PILOT)
    for round_ in range(MAX_ROUNDS):
        nu, nv = propagate(nu, nv, labels)
        todo = np.flatnonzero((nu != done_u) | (nv != done_v))
        if todo.size == 0:
            break
        # every cell's current counts: the mesh this round would hold, checked before its grids exist
        total = 2 * float((nu.astype(np.float64) * nv).sum())
        limits.check(total * BYTES_PER_TRIANGLE, f"tessellation at tolerance {tol:.3g} ({total:,.0f} triangles)")
        # the compiled kernels serve every step of a tessellation once loaded, and win at every
        # size (serial kernels: no thread start-up); a round counts its size toward loading them
        # (a quad costs the numpy path about four point-equivalents)
        work = 4 * float((nu[todo].astype(np.float64) * nv[todo]).sum())
        _kernels.load("splinekit.tessellation._kernels", work=work, min_work=0)
        new = []
        # cells evaluated as cells (single-cell and small patches): group by (cell set, nu, nv),
        # evaluate each group at once
        single = todo[~multi[todo]]
        if single.size:
            # one int64 key per cell, ordered like the rows (set, nu, nv): counts are <= MAX_COUNT
            base = MAX_COUNT + 1
            key = (set_of[single] * base + nu[single]) * base + nv[single]
            if (key == key[0]).all():  # one group (a pilot round of one cell set): no sort
                uniq, groups = key[:1], [single]
            else:
                uniq, inverse = np.unique(key, return_inverse=True)
                order = np.argsort(inverse, kind="stable")
                bounds = np.searchsorted(inverse[order], np.arange(len(uniq) + 1))
                groups = [single[order[bounds[g] : bounds[g + 1]]] for g in range(len(uniq))]
            for members, s, n, m in zip(groups, uniq // base**2, uniq // base % base, uniq % base):
                flags = any_collapsed[offsets[s] : offsets[s + 1]]
                grid = Grid.cells(cellsets[s], members - offsets[s], int(n), int(m), tol, angle_tol, weld_tol, flags)
                grid.cells = members
                new.append(grid)
        # larger multi-span patches: one tensor grid each, on the concatenated span samples
        for P in np.unique(patch_of[todo[multi[todo]]]) if any_multi else ():
            cells = np.arange(first[P], first[P] + n_cells[P])
            shape = (n_cells[P] // nsv[P], nsv[P])
            counts_u = nu[cells].reshape(shape).max(axis=1)
            counts_v = nv[cells].reshape(shape).max(axis=0)
            box = box_of[cells]
            bu = np.append(box[:: shape[1], 0], box[-1, 1])
            bv = np.append(box[: shape[1], 2], box[-1, 3])
            grid = Grid.patch(
                patches[P], int(P), bu, bv, counts_u, counts_v, tol, angle_tol, weld_tol, bool(any_collapsed[cells].any())
            )
            grid.cells = cells
            grid.counts = (counts_u, counts_v)
            new.append(grid)
        for grid in new:
            record[grid.cells] = len(grids)
            grids.append(grid)
        done_u[todo], done_v[todo] = nu[todo], nv[todo]
        # measure: which cells still exceed the tolerances
        fu, fv = np.ones(C), np.ones(C)
        for b in new:
            cells = b.cells
            # a diagonal or centre error is charged to each direction in proportion to its
            # edge error (all of it to the dominant one; to both when neither edge errs)
            top = np.maximum(b.err_u, b.err_v)
            safe = np.where(top > 0, top, 1.0)
            share_u = np.where(top > 0, b.err_u / safe, 1.0)
            share_v = np.where(top > 0, b.err_v / safe, 1.0)
            gu = np.sqrt(np.maximum(b.err_u, b.err_d * share_u) / tol)
            gv = np.sqrt(np.maximum(b.err_v, b.err_d * share_v) / tol)
            if angle_tol is not None:
                # the angle criterion shapes coarse grids only; it never drives a cell past
                # ANGLE_MAX_COUNT steps (the chordal tolerance alone governs finer grids)
                gu = np.maximum(gu, np.where(nu[cells] < ANGLE_MAX_COUNT, b.ang_u / angle_tol, 0.0))
                gv = np.maximum(gv, np.where(nv[cells] < ANGLE_MAX_COUNT, b.ang_v / angle_tol, 0.0))
            fu[cells], fv[cells] = gu, gv
        over_u, over_v = fu > 1.0, fv > 1.0
        if round_ == 0:
            # predicted counts where the pilot was coarser than the a-priori estimate
            # clipped as floats: an error far above a tiny tolerance gives inf, which no int holds
            pu = np.clip(np.ceil(nu * fu / math.sqrt(PILOT_TARGET)), 1, MAX_COUNT).astype(np.int64)
            pv = np.clip(np.ceil(nv * fv / math.sqrt(PILOT_TARGET)), 1, MAX_COUNT).astype(np.int64)
            nu = np.where(nu < apriori_u, pu, nu)
            nv = np.where(nv < apriori_v, pv, nv)
            over_u &= nu == done_u
            over_v &= nv == done_v
        elif not (over_u.any() or over_v.any()):
            break
        # the error falls like h^2: scale the count by sqrt(error / tol), with a margin
        grow_u = np.minimum(np.ceil(nu * np.minimum(fu * 1.15, 8.0)), MAX_COUNT).astype(np.int64)
        grow_v = np.minimum(np.ceil(nv * np.minimum(fv * 1.15, 8.0)), MAX_COUNT).astype(np.int64)
        nu = np.where(over_u, np.maximum(grow_u, np.minimum(nu + 1, MAX_COUNT)), nu)
        nv = np.where(over_v, np.maximum(grow_v, np.minimum(nv + 1, MAX_COUNT)), nv)
    mesh, welded, V, T = assemble(grids, record, collapsed, span_of, prep.cell_index, tol, weld_tol)
    return outward(mesh, welded, V, T) if orient else mesh

