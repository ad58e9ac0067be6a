#!/usr/bin/env python
"""``Refinement.matrix``: composing the stencils of a refinement, against scipy, in one run.

Usage::

    python benchmarks/bench_subdiv_compose.py           # Catmull-Clark torus to level 3, Loop to level 6
    python benchmarks/bench_subdiv_compose.py --quick   # one level less each

For each level ``L`` the composed ``(V_L, V_0)`` matrix ``S_L @ ... @ S_1`` is built two ways from
the same stencils (the refinement itself is not timed):

- before: the former ``Refinement.matrix``, scipy products from the coarse end with ``M``
  starting as the identity, ``M = S_k @ M``;
- **splinekit** ``Refinement.matrix`` now (:func:`splinekit.subdiv.compose.compose`): the same
  products starting from ``S_1`` (no product with the identity).

The results must agree exactly (sparsity and values). "ns/nnz" is the time per stored entry of
the result: about constant across levels means linear in the output size.

A second table composes the same number of levels on three sizes of base mesh (Catmull-Clark
tori of 50^2, 100^2 and 200^2 quads to level 3, or to level 2 with ``--quick``), each output
four times the last, and gives the growth of the time against the growth of the output, and the
peak memory of the largest against its output arrays (``_memory.py``), and the floor of the last
level's product: the time to merely read, with numpy fancy indexing in the order the product
needs them, the rows of ``M_(L-1)`` its stencil entries pick (five row entries per output entry
for Catmull-Clark; no arithmetic, no output). The ratio line for
``check_ratios.py`` is that linearity between the two larger sizes (both at or beyond the L3):
(time per entry of the middle one) / (time per entry of the largest), target >= 0.5 (a fourfold
output may cost at most eight times the time). The smallest runs from the caches and is cheaper
per entry.

Profile finding (scipy 1.17, 2 shared cores): the composition was already sparse at every level
(no dense intermediate) and linear in its output; the whole cost is scipy's single-threaded
``csr_matmat`` of the last level, 50-200 ns per output entry depending on the machine's load,
bound by memory latency (each stencil row picks rows of ``M_(k-1)`` scattered in memory). A
compiled Gustavson product (numba, int32, two passes split between two threads) was measured
too: 0.65 s against scipy's 0.57 s single-threaded for the 8.4M-entry torus level 3, slower
with two threads on the loaded machine, and three times slower when it sorted each row, so it
was not kept.

Profile of 2026-11-26 (issue 17 asked why the per-entry time was 64, 127, 108 ns at 2.1M, 8.4M,
33.6M entries), on the shared 2-core EPYC (32 MB L3 shared by every process, 1 MB L2 a core)
under a load average of 12-17: the last product is all of the time (the earlier levels are a
quarter and a sixteenth). Its per-entry cost follows where ``M_(L-1)`` lives: 5 MB of composed
rows for the 50^2 torus (in the L3), 20 MB for 100^2 (about the L3, which the other jobs share),
81 MB for 200^2 (DRAM). The reads alone cost 27, 50, 55 ns per output entry and the product
85, 97, 188 ns (1.9-3.4x its reads: scipy reads each picked row twice, once to count and once
to sum); the largest moved between 116 and 203 ns from run to run at equal code, with the
DRAM traffic of the other jobs. Three reorderings were measured against the plain product at
200^2 and were no faster in total, so none was kept: the parents renumbered in the order the
stencil rows first touch them (194 against 191 ns), the stencil rows sorted by their first
parent (the product 88-109 ns, but permuting the stencil and the result back cost 55-65 ns
more, 145-168 against 116-203 ns), and the product by row blocks of 4, 16, 64 (142-286 against
140-152 ns). CSR x CSC is no other order: scipy's product converts the CSC operand to CSR first. So the floor is
the memory latency of reading the scattered parent rows, with the cache shared with the
machine's other jobs; in the caches' range the time is scipy's own two passes.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
import scipy
import scipy.sparse as sp

REPO_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if REPO_DIR not in sys.path:
    sys.path.insert(0, REPO_DIR)

import splinekit as sk  # noqa: E402
from _memory import measure_memory  # noqa: E402
from _ratios import report  # noqa: E402
from splinekit.mesh.primitives import icosphere, torus  # noqa: E402
from splinekit.subdiv.compose import compose  # noqa: E402


def best_of(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def scipy_compose(stencils, n0):
    """The former ``Refinement.matrix``: identity, then ``S @ M`` level by level with scipy."""
    M = sp.identity(n0, format="csr")
    for S in stencils:
        M = S @ M
    return sp.csr_matrix(M)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    cases = [("Catmull-Clark, 100 x 100-quad torus", torus(100, 100, 2.0, 0.7), "catmull-clark", 2 if args.quick else 3),
             ("Loop, icosphere(2) (320 triangles)", icosphere(2), "loop", 5 if args.quick else 6)]
    repeats = 3
    print("# Refinement.matrix: composed subdivision stencils\n")
    print(f"numpy {np.__version__}, scipy {scipy.__version__}, "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}; best of {repeats}\n")
    print("| case | level | output | nnz | before (from the identity) | ns/nnz | **splinekit** `Refinement.matrix` "
          "| ns/nnz | ratio before / now | max abs diff |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, mesh, scheme, top in cases:
        r = sk.Refinement(mesh, scheme, top)
        n0 = mesh.n_vertices
        for level in range(1, top + 1):
            stencils = r.stencils[:level]
            t_ref, ref = best_of(lambda: scipy_compose(stencils, n0), repeats)
            part = sk.Refinement(mesh, scheme, level)
            t_sk, M = best_of(lambda: part.__class__.matrix.func(part), repeats)
            ref.sort_indices()
            M = M.copy()
            M.sort_indices()
            assert (M.indptr == ref.indptr).all() and (M.indices == ref.indices).all(), "sparsity differs"
            diff = float(np.abs(M.data - ref.data).max(initial=0.0))
            nnz = M.nnz
            print(f"| {label} | {level} | {M.shape[0]:,} x {M.shape[1]:,} | {nnz:,} | {t_ref * 1e3:.1f} ms | "
                  f"{t_ref / nnz * 1e9:.0f} | {t_sk * 1e3:.1f} ms | {t_sk / nnz * 1e9:.0f} | {t_ref / t_sk:.1f}x | "
                  f"{diff:.1e} |")
    sizes_table(args.quick, repeats)


def gather_floor(S, M, repeats: int, chunk: int = 2_000_000) -> float:
    """Seconds to merely read, in the order the product ``S @ M`` needs them, the rows of ``M`` its
    stencil entries pick (``M.data`` and ``M.indices`` gathered by numpy fancy indexing, by chunks of
    about ``chunk`` entries to bound the memory): the memory traffic of the product without its
    arithmetic, its accumulation or its output. Only the gathers are timed (best of ``repeats``)."""
    rowlen = np.diff(M.indptr)
    per_row = np.add.reduceat(rowlen[S.indices], S.indptr[:-1]) if S.nnz else np.zeros(0, np.int64)
    per_row[np.diff(S.indptr) == 0] = 0
    bounds = np.searchsorted(np.cumsum(per_row), np.arange(chunk, per_row.sum() + chunk, chunk))
    best = np.inf
    for _ in range(repeats):
        total, start = 0.0, 0
        for stop in np.unique(np.append(bounds + 1, S.shape[0]).clip(0, S.shape[0])):
            picks = S.indices[S.indptr[start] : S.indptr[stop]]  # the rows of M these stencil rows read
            n = rowlen[picks]
            idx = np.repeat(M.indptr[picks] - np.cumsum(n) + n, n) + np.arange(n.sum())
            t0 = time.perf_counter()
            M.data[idx], M.indices[idx]  # noqa: B018 (the reads are the measurement)
            total += time.perf_counter() - t0
            start = stop
        best = min(best, total)
    return best


def sizes_table(quick: bool, repeats: int):
    """The same levels on three base meshes, each output 4x the last: time growth against size growth."""
    level = 2 if quick else 3
    print(f"\n## Three sizes: Catmull-Clark tori to level {level}\n")
    print("| base quads | output | nnz | **splinekit** `Refinement.matrix` | ns/nnz | output growth | time growth "
          "| last level's reads alone (ns/nnz) | matrix / reads |")
    print("|---|---|---|---|---|---|---|---|---|")
    rows = []
    for n in (50, 100, 200):
        part = sk.Refinement(torus(n, n, 2.0, 0.7), "catmull-clark", level)
        t, M = best_of(lambda: part.__class__.matrix.func(part), repeats)
        grow = "-" if not rows else f"{M.nnz / rows[-1][1]:.2f}x"
        tgrow = "-" if not rows else f"{t / rows[-1][0]:.2f}x"
        stencils = part.stencils
        floor = gather_floor(stencils[-1], compose(stencils[:-1], part.hierarchy[0].n_vertices), repeats)
        print(f"| {n} x {n} | {M.shape[0]:,} x {M.shape[1]:,} | {M.nnz:,} | {t * 1e3:.1f} ms | "
              f"{t / M.nnz * 1e9:.0f} | {grow} | {tgrow} | {floor / M.nnz * 1e9:.0f} | {t / floor:.2f} |")
        rows.append((t, M.nnz, part))
    mem = measure_memory(lambda: rows[-1][2].__class__.matrix.func(rows[-1][2]))
    print(f"\nMemory of the largest: {mem.line()}\n")
    (t0, n0, _), (t1, n1, _) = rows[1], rows[2]
    report("subdiv compose: linearity, per-entry time middle / largest size", (t0 / n0) / (t1 / n1), 0.5)


if __name__ == "__main__":
    main()
