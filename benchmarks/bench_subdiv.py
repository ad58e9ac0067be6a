#!/usr/bin/env python
"""Subdivision benchmark: splinekit.subdivide against its peers, in one run.

Run from the repository root::

    python benchmarks/bench_subdiv.py           # full sizes (a few minutes)
    python benchmarks/bench_subdiv.py --quick   # reduced sizes (under a minute)

Cases:

1. Loop subdivision of the icosahedron (20 triangles, unit sphere) to level 8
   (1,310,720 triangles); ``--quick``: level 6.  Peers: libigl ``igl.loop``,
   trimesh ``trimesh.remesh.subdivide_loop``, Open3D
   ``TriangleMesh.subdivide_loop``, PyMeshLab
   ``meshing_surface_subdivision_loop`` (Loop weights, threshold 0 so that
   every edge is split) and, as a floor for the connectivity work alone,
   libigl ``igl.upsample`` (midpoint split, no smoothing).
2. Catmull-Clark of a 100 x 100-quad torus to level 4 (2,560,000 quads) and of
   the cube to level 9 (1,572,864 quads); ``--quick``: levels 2 and 7.  Peers:
   PyMeshLab ``meshing_surface_subdivision_catmull_clark`` and a vectorized
   numpy reference written here (face, edge and vertex points of a closed quad
   mesh), which is also the correctness check.
3. Re-applying the composed multi-level stencil to new base-vertex positions
   (an "animation frame"): output vertices per second.  splinekit's stencil is
   looked up as ``splinekit.subdivision_matrix``, ``splinekit.subdiv.subdivision_matrix``,
   ``splinekit.subdiv.refine.subdivision_matrix`` or ``splinekit.subdiv.refine.refine``;
   the peers are libigl's ``loop_matrix`` and the numpy reference's sparse
   Catmull-Clark matrices, composed with scipy and applied as one CSR product
   (and, for comparison, level by level).

Every peer gets numpy arrays and returns numpy arrays; the time covers the
whole call including building the peer's own mesh object and copying its
output back, always from the base mesh to level k in one call (all peers take
a number of iterations; the per-level table therefore shows the time *to reach*
level k, not the time of step k alone).  Times are the median of several
repeats after a warm-up call, except for calls over 1 s (one cold call).
CPU/wall > 1 means the implementation used more than one core.

Peak memory of the top level is measured in a fresh subprocess per case: the
growth of the peak RSS (VmHWM reset through /proc/self/clear_refs after a
warm-up at level 1) and, for the numpy-based implementations, the tracemalloc
peak (numpy reports its allocations to tracemalloc; C++ peers do not).  Both
include the returned arrays.

Correctness: outputs are compared as point sets (nearest-neighbour distances
with scipy.spatial.cKDTree in both directions, since the vertex numbering
differs between libraries); when the point sets agree to 1e-9 the faces are
compared too, after renumbering.  libigl (and possibly other peers) use Warren's
weight beta = 3/(8n) at vertices of valence n > 3 while Loop's original weight is
used by trimesh and splinekit, so positions near the 12 valence-5 vertices of the
icosahedron differ slightly; the table reports the difference, it does not fail.

Until ``splinekit.subdivide`` exists the script says so and still times the
peers.

splinekit's times are those of the compiled kernels once loaded (the steady state of a long
session): like bench_eval.py, the script sets ``SPLINEKIT_NUMBA=1`` unless it is set already.
Without it, the kernels load only once the numpy rules have served ``_kernels.LOAD_WORK``
(2,000,000) faces in jobs of at least ``MIN_WORK``, and the splinekit rows timed the numpy rules
until then (one quick Loop run to level 6 is 82k faces).

Profile of the Loop case at ``--quick`` size (icosahedron -> level 6, 2026-11-26, a busy 2-core
machine; best of 7, interleaved with the former code): levels 1-4 (80 to 5,120 faces) were below
the kernels' ``MIN_WORK`` and took the numpy/scipy rules, about 1.5 ms each in per-call overhead
(cProfile: 22,000 Python calls per run, most of them scipy.sparse construction), which with the
two compiled levels made 16 ms of CPU against libigl's 25 ms. A refinement now asks for the
kernels once with its finest level's size and refines every level with them: 6.6 ms CPU. In
wall time the kernels lost a further 3-8x to OpenMP workers spinning between kernel calls while
other processes wanted the cores (125 ms wall for 16 ms CPU); ``OMP_WAIT_POLICY=PASSIVE`` gave
18.4 -> 6.3 ms wall there (libigl 29-41 ms in the same runs). It is not the library's default: on
the idle machine (load 1.1-1.9, alternating runs of ``--quick``) passive workers cost more than
they save, Loop level 6 / libigl 2.2x passive against 5.4-9.7x spinning, and the 400 x 400 grid
of ``bench_eval.py`` 0.88x splipy against 1.9-3.9x. On a shared, oversubscribed machine set
``OMP_WAIT_POLICY=PASSIVE`` before the first kernel loads.
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import importlib
import importlib.metadata
import json
import os
import platform
import statistics
import subprocess
import sys
import time

import numpy as np

BENCH_DIR = os.path.dirname(os.path.abspath(__file__))
if BENCH_DIR not in sys.path:
    sys.path.insert(0, BENCH_DIR)
REPO_DIR = os.path.dirname(BENCH_DIR)
if REPO_DIR not in sys.path:
    sys.path.insert(0, REPO_DIR)

NUMBA_SETTING = os.environ.get("SPLINEKIT_NUMBA")  # as the caller set it (None: unset)
os.environ.setdefault("SPLINEKIT_NUMBA", "1")  # warm figures of the compiled kernels, as bench_eval.py

import _meshes as M  # noqa: E402
from _memory import measure_memory, output_bytes  # noqa: E402
from _ratios import report as report_ratio  # noqa: E402

# --------------------------------------------------------------------------------------
# configuration


def sizes(quick: bool) -> dict:
    if quick:
        return dict(loop_levels=6, torus=(100, 100), torus_levels=2, cube_levels=7, max_repeats=3,
                    level_cap_s=8.0, memory=True)
    return dict(loop_levels=8, torus=(100, 100), torus_levels=4, cube_levels=9, max_repeats=5,
                level_cap_s=60.0, memory=True)


TARGETS = dict(
    loop_vs_igl=1.0,  # splinekit time / libigl time at the top Loop level (aim 0.7)
    loop_vs_igl_aim=0.7,
    loop_vs_trimesh=5.0,  # trimesh time / splinekit time
    cc_faces_per_s=4e6,  # output faces per second at the 1.5-2.5M face level
    stencil_verts_per_s=20e6,  # output vertices per second
    memory_mb=300.0,  # peak extra memory for 2.5M output faces
    memory_faces=2_500_000,
)

# --------------------------------------------------------------------------------------
# splinekit API discovery (the subdivision API is not final yet)

_SK = {}


def sk_api():
    """``(subdivide, PolyMesh, message)``; ``subdivide`` is None while the API is missing."""
    if "api" in _SK:
        return _SK["api"]
    sub = PM = None
    msg = ""
    try:
        import splinekit as sk

        sub = getattr(sk, "subdivide", None)
        if sub is None:
            try:
                mod = importlib.import_module("splinekit.subdiv")
                sub = getattr(mod, "subdivide", None)
                if sub is not None:
                    msg = "found as splinekit.subdiv.subdivide (not yet exported as splinekit.subdivide)"
            except Exception:  # noqa: BLE001
                pass
        PM = getattr(sk, "PolyMesh", None)
        if PM is None:
            from splinekit.mesh import PolyMesh as PM  # noqa: N811
        if sub is None:
            msg = "splinekit.subdivide not available yet"
    except Exception as exc:  # noqa: BLE001
        sub = None
        msg = f"import splinekit failed: {type(exc).__name__}: {exc}"
    _SK["api"] = (sub, PM, msg)
    return _SK["api"]


STENCIL_CANDIDATES = [
    ("splinekit", "subdivision_matrix"),
    ("splinekit.subdiv", "subdivision_matrix"),
    ("splinekit.subdiv.refine", "subdivision_matrix"),
    ("splinekit.subdiv.refine", "refine"),
    ("splinekit.subdiv", "refine"),
    ("splinekit.subdiv", "stencil_matrix"),
    ("splinekit.subdiv.refiner", "subdivision_matrix"),
    ("splinekit.subdiv", "Refinement"),  # an object with .apply() / .matrix
]


def find_stencil_fn():
    """``(callable, 'module.name')`` of the first stencil builder found, else ``(None, message)``."""
    tried = []
    for modname, name in STENCIL_CANDIDATES:
        tried.append(f"{modname}.{name}")
        try:
            mod = importlib.import_module(modname)
        except Exception:  # noqa: BLE001
            continue
        fn = getattr(mod, name, None)
        if fn is not None and callable(fn) and not isinstance(fn, type(os)):
            return fn, f"{modname}.{name}"
    return None, "no stencil API found (looked for " + ", ".join(tried) + ")"


def _sparse_apply(S):
    return lambda X: S @ X


def stencil_applier(res, depth=0):
    """Turn whatever the stencil builder returned into ``(apply(X) -> Y, description)``."""
    import scipy.sparse as sps

    if depth > 3 or res is None:
        return None, None
    if sps.issparse(res):
        S = res.tocsr() if res.format not in ("csr", "csc") else res
        return _sparse_apply(S), f"{type(res).__name__} {S.shape[0]:,} x {S.shape[1]:,}, nnz {S.nnz:,}"
    if isinstance(res, (tuple, list)):
        mats = [r for r in res if sps.issparse(r)]
        if len(mats) > 1 and all(a.shape[1] == b.shape[0] for b, a in zip(mats, mats[1:])):
            def chain(X, mats=mats):
                for A in mats:
                    X = A @ X
                return X
            return chain, f"{len(mats)} per-level sparse matrices applied in turn"
        for r in res:
            f, d = stencil_applier(r, depth + 1)
            if f is not None:
                return f, d
        return None, None
    for meth in ("apply", "refine_vertices", "interpolate"):
        m = getattr(res, meth, None)
        if callable(m):
            return m, f"{type(res).__name__}.{meth}()"
    for attr in ("matrix", "stencil", "stencils", "S", "P"):
        if hasattr(res, attr):
            f, d = stencil_applier(getattr(res, attr), depth + 1)
            if f is not None:
                return f, f"{type(res).__name__}.{attr}: {d}"
    if hasattr(res, "__matmul__") and hasattr(res, "shape"):
        return (lambda X: res @ X), f"{type(res).__name__} (operator @)"
    return None, None


def build_sk_stencil(mesh, scheme, levels):
    """``(apply, description)`` or ``(None, reason)``."""
    fn, where = find_stencil_fn()
    if fn is None:
        return None, where
    errors = []
    calls = [
        lambda: fn(mesh, scheme, levels),
        lambda: fn(mesh, scheme, levels=levels),
        lambda: fn(mesh, scheme=scheme, levels=levels),
        lambda: fn(mesh.topology, scheme, levels),
    ]
    for call in calls:
        try:
            res = call()
        except TypeError as exc:
            errors.append(f"TypeError: {exc}")
            continue
        except Exception as exc:  # noqa: BLE001
            return None, f"{where} raised {type(exc).__name__}: {exc}"
        f, d = stencil_applier(res)
        if f is None:
            return None, f"{where} returned {type(res).__name__}, which the script cannot apply"
        return f, f"{where} -> {d}"
    return None, f"{where}: no call signature worked ({errors[-1] if errors else ''})"


def _as_vertices(y):
    if hasattr(y, "vertices"):
        y = y.vertices
    if hasattr(y, "toarray"):
        y = y.toarray()
    return np.asarray(y)


# --------------------------------------------------------------------------------------
# helpers


@contextlib.contextmanager
def quiet_fd():
    """Silence C/C++ writes to stdout (PyMeshLab prints from its filters)."""
    sys.stdout.flush()
    try:
        fd = sys.stdout.fileno()
    except Exception:  # noqa: BLE001
        yield
        return
    saved = os.dup(fd)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, fd)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, fd)
        os.close(saved)
        os.close(devnull)


def measure(fn, max_repeats=5):
    """Median wall time of ``fn()``: ``(seconds, timed repeats, last result, cpu/wall)``.

    The first call is a warm-up and is not counted, unless it alone takes over
    1 s; then that one call is the measurement (repeats = 0).
    """
    gc.collect()
    c0, t0 = time.process_time(), time.perf_counter()
    result = fn()
    first = time.perf_counter() - t0
    cpu = time.process_time() - c0
    if first > 1.0:
        return first, 0, result, cpu / first
    times, cpus = [], []
    while True:
        result = None
        gc.collect()
        c0, t0 = time.process_time(), time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
        if times[0] < 0.05:
            wanted = max_repeats + 4
        elif times[0] < 0.3:
            wanted = max_repeats
        else:
            wanted = min(3, max_repeats) if times[0] < 1.0 else 1
        if len(times) >= wanted:
            return statistics.median(times), len(times), result, sum(cpus) / max(sum(times), 1e-12)


def fmt_t(t):
    if t is None:
        return "-"
    if t >= 1.0:
        return f"{t:.2f} s"
    if t >= 1e-3:
        return f"{t * 1e3:.3g} ms"
    return f"{t * 1e6:.3g} µs"


def fmt_rate(x):
    return "-" if x is None else f"{x / 1e6:.2f} M/s"


def fmt_mb(b):
    return "-" if b is None else f"{b / 1e6:.0f} MB"


def fmt_runs(reps):
    return {0: "1 cold call", 1: "1 call after warm-up"}.get(reps, f"median of {reps}")


def short(exc):
    return f"{type(exc).__name__}: {exc}".replace("|", "/").splitlines()[0][:160]


# --------------------------------------------------------------------------------------
# plain numpy reference: Catmull-Clark of a closed quad mesh


def cc_topology(F, n):
    """Refined connectivity of a closed, consistently oriented quad mesh.

    Returns ``edges (E, 2)``, ``edge_faces (E, 2)``, the new quads and the
    valence of each old vertex.  New vertices are numbered: old vertices
    ``0..n-1``, then one per edge, then one per face.
    """
    f = len(F)
    edges, he = M.unique_edges(F, n)
    E = len(edges)
    flat = he.ravel()
    counts = np.bincount(flat, minlength=E)
    if (counts != 2).any():
        raise ValueError("the numpy Catmull-Clark reference needs a closed manifold quad mesh")
    order = np.argsort(flat, kind="stable")
    edge_faces = (order // F.shape[1]).reshape(E, 2)
    ei = n + he  # edge point of half-edge j (corner j -> corner j + 1)
    fi = np.broadcast_to((n + E + np.arange(f))[:, None], F.shape)
    # quad at corner j: vertex, edge point of the outgoing edge, face point, edge point of the incoming edge
    NF = np.stack([F, ei, fi, np.roll(ei, 1, axis=1)], axis=-1).reshape(-1, 4)
    valence = np.bincount(F.ravel(), minlength=n).astype(np.float64)
    return edges, edge_faces, NF, valence


def cc_positions(V, F, edges, edge_faces, valence):
    """One Catmull-Clark step of the coordinates (face, edge and vertex points)."""
    n = len(V)
    FP = (V[F[:, 0]] + V[F[:, 1]] + V[F[:, 2]] + V[F[:, 3]]) * 0.25
    EP = (V[edges[:, 0]] + V[edges[:, 1]] + FP[edge_faces[:, 0]] + FP[edge_faces[:, 1]]) * 0.25
    # vertex point (Q + 2R + (n - 3)P) / n  ==  (n - 2)/n P + (sum of face points + sum of neighbours) / n^2
    contrib = np.repeat(FP, F.shape[1], axis=0)
    contrib += V[np.roll(F, -1, axis=1).ravel()]
    idx = F.ravel()
    acc = np.empty((n, V.shape[1]))
    for c in range(V.shape[1]):
        acc[:, c] = np.bincount(idx, weights=contrib[:, c], minlength=n)
    VP = V * ((valence - 2.0) / valence)[:, None] + acc / (valence * valence)[:, None]
    return np.concatenate([VP, EP, FP])


def ref_catmull_clark(V, F, levels):
    V = np.asarray(V, dtype=np.float64)
    for _ in range(levels):
        edges, ef, NF, val = cc_topology(F, len(V))
        V = cc_positions(V, F, edges, ef, val)
        F = NF
    return V, F


def cc_matrix(F, n):
    """The one-level Catmull-Clark matrix (scipy CSR, ``(n + E + f) x n``) and the new quads."""
    import scipy.sparse as sps

    edges, ef, NF, val = cc_topology(F, n)
    f, E = len(F), len(edges)
    Sf = sps.csr_matrix((np.full(4 * f, 0.25), (np.repeat(np.arange(f), 4), F.ravel())), shape=(f, n))
    Aeverts = sps.csr_matrix((np.full(2 * E, 0.25), (np.repeat(np.arange(E), 2), edges.ravel())), shape=(E, n))
    Aefaces = sps.csr_matrix((np.full(2 * E, 0.25), (np.repeat(np.arange(E), 2), ef.ravel())), shape=(E, f))
    Se = Aeverts + Aefaces @ Sf
    rows = F.ravel()
    w = (1.0 / (val * val))[rows]
    Cvf = sps.csr_matrix((w, (rows, np.repeat(np.arange(f), 4))), shape=(n, f))
    Cvn = sps.csr_matrix((w, (rows, np.roll(F, -1, axis=1).ravel())), shape=(n, n))
    Sv = sps.diags((val - 2.0) / val) + Cvf @ Sf + Cvn
    return sps.vstack([Sv, Se, Sf]).tocsr(), NF


def ref_cc_matrices(F, n, levels):
    mats = []
    for _ in range(levels):
        S, F = cc_matrix(F, n)
        mats.append(S)
        n = S.shape[0]
    return mats, F


def compose(mats):
    S = mats[0]
    for A in mats[1:]:
        S = (A @ S).tocsr()
    S.sort_indices()
    return S


def check_reference():
    """Self-test of the numpy Catmull-Clark reference; returns a list of failure messages."""
    bad = []
    V, F = M.cube()
    V1, _ = ref_catmull_clark(V, F, 1)
    if not np.allclose(np.abs(V1[:8]), 5.0 / 9.0, atol=1e-15, rtol=0):
        bad.append(f"cube corner after one step is {V1[0].tolist()}, expected +-5/9")
    # on a regular grid Catmull-Clark is uniform bicubic B-spline refinement:
    # vertex mask [1 6 1] x [1 6 1] / 64, edge mask [1 6 1] x [1 1] / 16
    nu, nv = 7, 9
    V, F = M.torus(nu, nv)
    V1, F1 = ref_catmull_clark(V, F, 1)
    G = V.reshape(nu, nv, 3)
    w = np.array([1.0, 6.0, 1.0]) / 8.0
    vp = sum(w[a] * w[b] * np.roll(np.roll(G, 1 - a, 0), 1 - b, 1) for a in range(3) for b in range(3))
    if np.abs(V1[: nu * nv] - vp.reshape(-1, 3)).max() > 1e-14:
        bad.append("torus vertex points differ from the bicubic B-spline mask")
    # edge (i, j)-(i+1, j): mask [1 6 1] / 8 across (v), [1 1] / 2 along (u)
    ep = sum(w[b] * 0.5 * np.roll(np.roll(G, -a, 0), 1 - b, 1) for a in range(2) for b in range(3))
    edges, _ = M.unique_edges(F, len(V))
    idx = {tuple(e): k for k, e in enumerate(edges.tolist())}
    i, j = 2, 3
    a, b = i * nv + j, (i + 1) * nv + j
    k = idx[(min(a, b), max(a, b))]
    if np.abs(V1[nu * nv + k] - ep[i, j]).max() > 1e-14:
        bad.append("torus edge point differs from the bicubic B-spline mask")
    mats, Fm = ref_cc_matrices(F, len(V), 2)
    V2, F2 = ref_catmull_clark(V, F, 2)
    if not np.array_equal(Fm, F2) or np.abs(compose(mats) @ V - V2).max() > 1e-13:
        bad.append("sparse reference matrices disagree with the direct reference")
    return bad


# --------------------------------------------------------------------------------------
# implementations: each runner maps (V, F, levels) -> (vertices, faces or None, number of output faces)


def run_splinekit(scheme):
    def run(V, F, k):
        sub, PM, msg = sk_api()
        if sub is None:
            raise RuntimeError(msg)
        out = sub(PM(V, F), scheme, levels=k)
        faces = out.faces
        nf = out.n_faces if hasattr(out, "n_faces") else len(faces)
        return np.asarray(out.vertices), (np.asarray(faces) if not isinstance(faces, list) else None), nf
    return run


def run_igl_loop(V, F, k):
    import igl

    v, f = igl.loop(V, F, k)
    return v, f, len(f)


def run_igl_upsample(V, F, k):
    import igl

    v, f = igl.upsample(V, F, k)
    return v, f, len(f)


def run_trimesh_loop(V, F, k):
    import trimesh.remesh

    v, f = trimesh.remesh.subdivide_loop(V, F, iterations=k)
    return v, f, len(f)


def run_open3d_loop(V, F, k):
    import open3d as o3d

    m = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(V), o3d.utility.Vector3iVector(F.astype(np.int32)))
    s = m.subdivide_loop(number_of_iterations=k)
    v, f = np.asarray(s.vertices), np.asarray(s.triangles)
    return v, f, len(f)


def run_pymeshlab_loop(V, F, k):
    import pymeshlab

    with quiet_fd():
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
        ms.meshing_surface_subdivision_loop(loopweight="Loop", iterations=k, threshold=pymeshlab.PercentageValue(0.0))
        m = ms.current_mesh()
        v, f = m.vertex_matrix(), m.face_matrix()
    return v, f, len(f)


def run_pymeshlab_cc(V, F, k):
    import pymeshlab

    with quiet_fd():
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(V, [f.astype(np.uint32) for f in F]))
        ms.meshing_surface_subdivision_catmull_clark(iterations=k)
        m = ms.current_mesh()
        v, f = m.vertex_matrix(), m.face_matrix()
    # MeshLab stores quads as triangle pairs with a 'faux' diagonal
    return v, None, len(f) // 2


def run_ref_cc(V, F, k):
    v, f = ref_catmull_clark(V, F, k)
    return v, f, len(f)


def base_mesh(name, cfg=None):
    if name == "icosahedron":
        return M.icosahedron()
    if name == "cube":
        return M.cube()
    if name.startswith("torus"):
        nu, nv = (int(x) for x in name[len("torus"):].split("x"))
        return M.torus(nu, nv)
    raise KeyError(name)


# (key, label, runner factory, module to import for availability, numpy-based, note)
LOOP_IMPLS = [
    ("splinekit", "**splinekit** `subdivide(m, 'loop', levels=k)`", lambda: run_splinekit("loop"), None, True, ""),
    ("libigl", "libigl `igl.loop(V, F, k)`", lambda: run_igl_loop, "igl", False, "Warren's beta 3/(8n)"),
    ("trimesh", "trimesh `remesh.subdivide_loop(V, F, iterations=k)`", lambda: run_trimesh_loop, "trimesh", True,
     "Loop's original beta"),
    ("open3d", "Open3D `TriangleMesh.subdivide_loop(number_of_iterations=k)`", lambda: run_open3d_loop, "open3d",
     False, ""),
    ("pymeshlab", "PyMeshLab `meshing_surface_subdivision_loop` (Loop weights, threshold 0)",
     lambda: run_pymeshlab_loop, "pymeshlab", False, ""),
    ("libigl-upsample", "libigl `igl.upsample(V, F, k)` (midpoint split, not Loop)", lambda: run_igl_upsample, "igl",
     False, "no smoothing: floor for the connectivity work"),
]

CC_IMPLS = [
    ("splinekit", "**splinekit** `subdivide(m, 'catmull-clark', levels=k)`", lambda: run_splinekit("catmull-clark"),
     None, True, ""),
    ("numpy-ref", "numpy reference (this script)", lambda: run_ref_cc, None, True, ""),
    ("pymeshlab", "PyMeshLab `meshing_surface_subdivision_catmull_clark`", lambda: run_pymeshlab_cc, "pymeshlab",
     False, "returns triangle pairs with faux diagonals, quads counted; its vertex rule is (Q + R + (n-2)P)/n with "
     "R = mean of the new edge points, not the B-spline rule (Q + 2R + (n-3)P)/n with edge midpoints, so it "
     "differs even at valence 4; its edge and face points agree to ~2e-7"),
]


def impl_table(scheme):
    return LOOP_IMPLS if scheme == "loop" else CC_IMPLS


def runner_for(scheme, key):
    for k, _label, factory, _mod, _np, _note in impl_table(scheme):
        if k == key:
            return factory()
    raise KeyError(key)


PEER_MODULES = {"igl": "libigl", "trimesh": "trimesh", "open3d": "open3d", "pymeshlab": "pymeshlab"}


def peer_status():
    """``{module: (ok, version or error)}``."""
    out = {}
    for mod, dist in PEER_MODULES.items():
        try:
            with quiet_fd():
                importlib.import_module(mod)
            try:
                ver = importlib.metadata.version(dist)
            except Exception:  # noqa: BLE001
                ver = "?"
            out[mod] = (True, ver)
        except Exception as exc:  # noqa: BLE001
            out[mod] = (False, short(exc))
    return out


# --------------------------------------------------------------------------------------
# memory: one fresh subprocess per case


def child_main(spec):
    """Run in a fresh interpreter: peak RSS growth and tracemalloc peak of one case
    (``_memory.measure_memory``; tracemalloc sees numpy allocations, not C++ peers')."""
    V, F = base_mesh(spec["mesh"])
    run = runner_for(spec["scheme"], spec["impl"])
    out = run(V, F, 1)  # warm-up: lazy imports, JIT, caches, thread pools
    del out
    mem = measure_memory(lambda: run(V, F, spec["level"]))
    res = {"rss": mem.rss, "out_bytes": output_bytes(mem.result[:2]), "faces": int(mem.result[2])}
    if spec.get("traced"):
        res["traced"] = mem.traced
    print("RESULT " + json.dumps(res))


def memory_case(scheme, impl, mesh, level, traced, timeout=300):
    spec = dict(scheme=scheme, impl=impl, mesh=mesh, level=level, traced=traced)
    try:
        res = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", json.dumps(spec)],
                             capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, f"memory subprocess timed out after {timeout} s"
    lines = [ln for ln in res.stdout.splitlines() if ln.startswith("RESULT ")]
    if res.returncode != 0 or not lines:
        err = (res.stderr.strip().splitlines() or ["?"])[-1]
        return None, f"memory subprocess failed: {err[:150]}"
    return json.loads(lines[-1][len("RESULT "):]), None


# --------------------------------------------------------------------------------------
# correctness: compare point sets and (when they agree) faces


def canonical_faces(F):
    F = np.asarray(F)
    k = F.shape[1]
    start = np.argmin(F, axis=1)
    cols = (start[:, None] + np.arange(k)) % k
    G = F[np.arange(len(F))[:, None], cols]
    order = np.lexsort(G.T[::-1])
    return G[order]


class Reference:
    def __init__(self, V, F):
        from scipy.spatial import cKDTree

        self.V, self.F = V, F
        self.tree = cKDTree(V)

    def compare(self, V, F, tree=None):
        """``dict(max, mean, connectivity)``: symmetric nearest-neighbour distances.

        ``tree``: a cKDTree of ``V`` if the caller has one (it is reused across references).
        """
        from scipy.spatial import cKDTree

        d1, idx = self.tree.query(V, workers=-1)
        d2, _ = (tree if tree is not None else cKDTree(V)).query(self.V, workers=-1)
        res = dict(max=float(max(d1.max(), d2.max())), mean=float(0.5 * (d1.mean() + d2.mean())),
                   nv=len(V), connectivity="-")
        if F is None or self.F is None:
            res["connectivity"] = "not compared (face type differs)"
        elif len(V) != len(self.V) or np.asarray(F).shape != np.asarray(self.F).shape:
            res["connectivity"] = "different counts"
        elif res["max"] > 1e-9 or np.unique(idx).size != len(idx):
            res["connectivity"] = "not compared (point sets differ)"
        else:
            same = np.array_equal(canonical_faces(idx[np.asarray(F)]), canonical_faces(self.F))
            res["connectivity"] = "identical after renumbering" if same else "**differs**"
        return res


# --------------------------------------------------------------------------------------
# the benchmark cases


class Report:
    def __init__(self):
        self.sections = []
        self.targets = []  # (case, target, measured, met or None, note)
        self.failures = []

    def add(self, text):
        self.sections.append(text)

    def target(self, case, text, measured, met, note=""):
        self.targets.append((case, text, measured, met, note))

    def fail(self, case, impl, msg):
        self.failures.append((case, impl, msg))


def available_impls(scheme, peers, report, case):
    impls = []
    for key, label, factory, mod, numpy_based, note in impl_table(scheme):
        if key == "splinekit":
            sub, _PM, msg = sk_api()
            if sub is None:
                report.fail(case, "splinekit", msg)
                continue
        elif mod is not None and not peers[mod][0]:
            report.fail(case, label, f"not installed / import failed: {peers[mod][1]}")
            continue
        impls.append((key, label, factory(), numpy_based, note))
    return impls


def bench_scheme(report, cfg, peers, scheme, mesh, top, case):
    """Per-level times and the top-level summary of one scheme on one base mesh."""
    V, F = base_mesh(mesh)
    R = cfg["max_repeats"]
    impls = available_impls(scheme, peers, report, case)
    levels = list(range(1, top + 1))
    per_level = {}  # key -> {level: (t, reps, cpu, faces)}
    outputs = {}
    for key, label, run, _np, _note in impls:
        per_level[key] = {}
        for k in levels:
            try:
                t, reps, out, cpu = measure(lambda run=run, k=k: run(V, F, k), R)
            except Exception as exc:  # noqa: BLE001
                report.fail(f"{case}, level {k}", label, short(exc))
                break
            per_level[key][k] = (t, reps, cpu, out[2])
            if k == top:
                outputs[key] = out
            del out
            if k < top and t * 4.5 > cfg["level_cap_s"]:
                report.fail(f"{case}, levels > {k}", label,
                            f"skipped: level {k} took {fmt_t(t)}, the next would exceed the "
                            f"{cfg['level_cap_s']:.0f} s cap")
                break

    expected = {k: len(F) * 4**k for k in levels}
    # per-level table: time to reach level k from the base mesh
    head = "| level | faces | " + " | ".join(label for _k, label, *_ in impls) + " |"
    lines = [f"### {case}: time to reach level k from the base mesh (one call), output faces per second", "",
             head, "|" + "---|" * (2 + len(impls))]
    for k in levels:
        cells = []
        for key, *_ in impls:
            r = per_level[key].get(k)
            if r is None:
                cells.append("-")
            else:
                flag = "" if r[3] == expected[k] else f" (**{r[3]:,} faces**)"
                cells.append(f"{fmt_t(r[0])} ({r[3] / r[0] / 1e6:.2f} M/s){flag}")
        lines.append(f"| {k} | {expected[k]:,} | " + " | ".join(cells) + " |")
    report.add("\n".join(lines))
    return impls, per_level, outputs


def summary_table(report, cfg, scheme, mesh, top, case, impls, per_level, outputs, ref_key, ref_label,
                  ref2_key=None, ref2_label=None):
    """Top-level table: time, rate, CPU use, memory, difference from the reference (and a second one)."""
    t_sk = per_level.get("splinekit", {}).get(top, (None,))[0]
    ref = ref2 = None
    if ref_key in outputs:
        o = outputs[ref_key]
        ref = Reference(o[0], o[1])
    if ref2_key is not None and ref2_key in outputs and ref2_key != ref_key:
        o = outputs[ref2_key]
        ref2 = Reference(o[0], o[1])
    mem = {}
    if cfg["memory"]:
        for key, label, _run, numpy_based, _note in impls:
            if top not in per_level.get(key, {}) or key == "libigl-upsample":
                continue
            res, err = memory_case(scheme, key, mesh, top, traced=numpy_based)
            if err:
                report.fail(f"{case}, memory", label, err)
            mem[key] = res
    extra = f" max / mean nearest distance vs {ref2_label} |" if ref2 is not None else ""
    head = ("| implementation | output faces | time | faces/s | CPU/wall | ratio (time / splinekit) | peak RSS growth "
            f"| tracemalloc peak | output arrays | max / mean nearest distance vs {ref_label} | connectivity |{extra} "
            "notes |")
    lines = [f"### {case}: level {top}", "", head, "|" + "---|" * (12 + (ref2 is not None))]
    from scipy.spatial import cKDTree

    diffs = {}
    for key, label, _run, _numpy_based, note in impls:
        tree = None
        r = per_level.get(key, {}).get(top)
        if r is None:
            lines.append(f"| {label} | - | not run | | | | | | | | |{' |' if ref2 is not None else ''} |")
            continue
        t, reps, cpu, nf = r
        ratio = "-" if t_sk is None else ("1" if key == "splinekit" else f"{t / t_sk:.2f}")
        m = mem.get(key) or {}
        if key == ref_key:
            dtxt, conn = "(reference)", "-"
        elif ref is None or key not in outputs or key == "libigl-upsample":
            dtxt, conn = "-", "-"
        else:
            tree = cKDTree(outputs[key][0]) if ref2 is not None else None
            d = ref.compare(outputs[key][0], outputs[key][1], tree)
            diffs[key] = d
            dtxt, conn = f"{d['max']:.1e} / {d['mean']:.1e}", d["connectivity"]
        d2txt = ""
        if ref2 is not None:
            if key == ref2_key:
                d2txt = " (second reference) |"
            elif key not in outputs or key == "libigl-upsample":
                d2txt = " - |"
            else:
                if tree is None:
                    tree = cKDTree(outputs[key][0])
                d2 = ref2.compare(outputs[key][0], outputs[key][1], tree)
                d2txt = f" {d2['max']:.1e} / {d2['mean']:.1e} |"
        notes = "; ".join(x for x in (fmt_runs(reps), note) if x)
        lines.append(
            f"| {label} | {nf:,} | {fmt_t(t)} | {fmt_rate(nf / t)} | {cpu:.2f} | {ratio} | {fmt_mb(m.get('rss'))} "
            f"| {fmt_mb(m.get('traced')) if 'traced' in m else 'n/a (C++)'} | {fmt_mb(m.get('out_bytes'))} "
            f"| {dtxt} | {conn} |{d2txt} {notes} |"
        )
    report.add("\n".join(lines))
    return t_sk, mem, diffs


def bench_loop(report, cfg, peers):
    top = cfg["loop_levels"]
    case = f"Loop, icosahedron (20 triangles) -> level {top}"
    impls, per_level, outputs = bench_scheme(report, cfg, peers, "loop", "icosahedron", top, case)
    ref_key = "splinekit" if "splinekit" in outputs else "trimesh"
    ref_label = "splinekit" if ref_key == "splinekit" else "trimesh (Loop's beta; splinekit missing)"
    t_sk, mem, diffs = summary_table(report, cfg, "loop", "icosahedron", top, case, impls, per_level, outputs,
                                     ref_key, ref_label, "libigl", "libigl (Warren's beta)")
    outputs.clear()
    gc.collect()
    quick = "" if top == 8 else f" (at level {top}: indicative only)"
    if ref_key == "splinekit":
        if "trimesh" in diffs:
            d = diffs["trimesh"]
            report.target(case, "splinekit Loop matches trimesh (both use Loop's beta)",
                          f"max dist {d['max']:.1e}, {d['connectivity']}",
                          d["max"] < 1e-9 and d["connectivity"].startswith("identical"), "correctness")
        if "libigl" in diffs:
            d = diffs["libigl"]
            report.target(case, "difference from libigl (Warren's beta 3/(8n): expected, reported only)",
                          f"max {d['max']:.1e}, mean {d['mean']:.1e}", "info", "correctness")
    t_igl = per_level.get("libigl", {}).get(top, (None,))[0]
    t_tm = per_level.get("trimesh", {}).get(top, (None,))[0]
    if t_sk is None:
        report.target(case, "Loop time <= 1.0x libigl (aim 0.7x)", "-", None, "splinekit.subdivide not available")
        report.target(case, "Loop >= 5x faster than trimesh", "-", None, "splinekit.subdivide not available")
    else:
        if t_igl is None:
            report.target(case, "Loop time <= 1.0x libigl (aim 0.7x)", "-", None, "libigl not run")
        else:
            r = t_sk / t_igl
            aim = "aim 0.7x met" if r <= TARGETS["loop_vs_igl_aim"] else "aim 0.7x not met"
            report.target(case, "Loop time <= 1.0x libigl (aim 0.7x)", f"{r:.2f}x libigl time",
                          r <= TARGETS["loop_vs_igl"], aim + quick)
            report_ratio(f"{case}: libigl / splinekit", 1 / r, 1 / TARGETS["loop_vs_igl"])
        if t_tm is None:
            report.target(case, "Loop >= 5x faster than trimesh", "-", None, "trimesh not run")
        else:
            r = t_tm / t_sk
            report.target(case, "Loop >= 5x faster than trimesh", f"{r:.1f}x", r >= TARGETS["loop_vs_trimesh"], quick)
            report_ratio(f"{case}: trimesh / splinekit", r, TARGETS["loop_vs_trimesh"])
    return per_level


def bench_cc(report, cfg, peers, mesh, top, label):
    case = f"Catmull-Clark, {label} -> level {top}"
    impls, per_level, outputs = bench_scheme(report, cfg, peers, "catmull-clark", mesh, top, case)
    _t_sk, mem, diffs = summary_table(report, cfg, "catmull-clark", mesh, top, case, impls, per_level, outputs,
                                      "numpy-ref", "numpy reference")
    outputs.clear()
    gc.collect()
    r = per_level.get("splinekit", {}).get(top)
    nf = len(base_mesh(mesh)[1]) * 4**top
    in_band = 1_500_000 <= nf <= 2_600_000
    note = "" if in_band else f"(at {nf:,} faces, outside the 1.5-2.5M band: indicative only)"
    if r is None:
        report.target(case, "Catmull-Clark >= 4M output faces/s", "-", None, "splinekit.subdivide not available")
    else:
        rate = r[3] / r[0]
        report.target(case, "Catmull-Clark >= 4M output faces/s", fmt_rate(rate), rate >= TARGETS["cc_faces_per_s"],
                      note)
        report_ratio(f"{case}: output faces/s / target rate", rate / TARGETS["cc_faces_per_s"], 1.0)
    if mesh.startswith("torus"):
        m = mem.get("splinekit") if r is not None else None
        # at reduced sizes (--quick) the limit is scaled with the face count
        limit = TARGETS["memory_mb"] * 1e6 * (1.0 if nf >= 2_000_000 else nf / TARGETS["memory_faces"])
        text = "peak extra memory < 300 MB for 2.5M output faces (includes the returned mesh)"
        if r is None:
            report.target(case, text, "-", None, "splinekit.subdivide not available")
        elif not m:
            report.target(case, text, "-", None, "memory not measured")
        else:
            vals = [v for v in (m.get("rss"), m.get("traced")) if v is not None]
            worst = max(vals) if vals else None
            meas = f"RSS {fmt_mb(m.get('rss'))}, tracemalloc {fmt_mb(m.get('traced'))}"
            sc = "" if nf >= 2_000_000 else f" (limit scaled to {limit / 1e6:.0f} MB for {nf:,} faces: indicative)"
            report.target(case, text, meas, None if worst is None else worst < limit, "larger of the two counts" + sc)
    if "splinekit" in diffs:
        d = diffs["splinekit"]
        report.target(case, "splinekit matches the numpy reference", f"max dist {d['max']:.1e}, {d['connectivity']}",
                      d["max"] < 1e-9 and d["connectivity"].startswith("identical"), "correctness")
    return per_level


def animation_frame(V, seed=7):
    """The base vertices rotated a little and jittered: a new frame of the same topology."""
    rng = np.random.default_rng(seed)
    a = 0.3
    Rz = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    scale = np.ptp(V, axis=0).max()
    return np.ascontiguousarray(V @ Rz.T + rng.normal(0.0, 0.01 * scale, V.shape))


def bench_stencil(report, cfg, peers, scheme, mesh, top, label):
    import scipy.sparse  # noqa: F401

    case = f"stencil re-application, {scheme} {label} level {top}"
    R = cfg["max_repeats"]
    V, F = base_mesh(mesh)
    Vnew = animation_frame(V)
    rows = []

    # splinekit
    sub, PM, msg = sk_api()
    t_sk_rate = None
    if sub is None:
        rows.append(("**splinekit**", None, None, None, None, msg))
        report.fail(case, "splinekit", msg)
    else:
        try:
            m = PM(V, F)
            t0 = time.perf_counter()
            apply, desc = build_sk_stencil(m, scheme, top)
            t_build = time.perf_counter() - t0
            if apply is None:
                rows.append(("**splinekit**", None, None, None, None, f"skipped: {desc}"))
                report.fail(case, "splinekit stencil", desc)
            else:
                t, reps, Y, cpu = measure(lambda: _as_vertices(apply(Vnew)), R)
                direct = np.asarray(sub(PM(Vnew, F), scheme, levels=top).vertices)
                diff = (f"{np.abs(Y - direct).max():.1e}" if Y.shape == direct.shape
                        else f"shape {Y.shape} vs subdivide {direct.shape}")
                rows.append(("**splinekit** " + desc, len(Y), t, cpu, diff,
                             f"{fmt_runs(reps)}; stencil built in {fmt_t(t_build)}"))
                t_sk_rate = len(Y) / t
        except Exception as exc:  # noqa: BLE001
            rows.append(("**splinekit**", None, None, None, None, f"failed: {short(exc)}"))
            report.fail(case, "splinekit stencil", short(exc))

    # peers: sparse matrices from libigl (Loop) or from the numpy reference (Catmull-Clark)
    mats = None
    if scheme == "loop":
        if peers["igl"][0]:
            import igl

            t0 = time.perf_counter()
            mats, f, n = [], F, len(V)
            for _ in range(top):
                S, f = igl.loop_matrix(f, n)
                mats.append(S.tocsr())
                n = S.shape[0]
            t_mats = time.perf_counter() - t0
            direct = igl.loop(Vnew, F, top)[0]
            who = "libigl `loop_matrix`"
        else:
            rows.append(("libigl `loop_matrix`", None, None, None, None, "libigl not installed"))
    else:
        t0 = time.perf_counter()
        mats, _f = ref_cc_matrices(F, len(V), top)
        t_mats = time.perf_counter() - t0
        direct = ref_catmull_clark(Vnew, F, top)[0]
        who = "numpy reference matrices"
    if mats is not None:
        t0 = time.perf_counter()
        S = compose(mats)
        t_comp = time.perf_counter() - t0
        X = np.ascontiguousarray(Vnew)
        t, reps, Y, cpu = measure(lambda: S @ X, R)
        rows.append((f"{who}, composed: scipy CSR `S @ V`", len(Y), t, cpu, f"{np.abs(Y - direct).max():.1e}",
                     f"{fmt_runs(reps)}; {S.shape[0]:,} x {S.shape[1]:,}, nnz {S.nnz:,} "
                     f"({S.nnz / S.shape[0]:.1f}/row); matrices {fmt_t(t_mats)}, composition {fmt_t(t_comp)}"))

        def chain():
            Z = X
            for A in mats:
                Z = A @ Z
            return Z

        t, reps, Y, cpu = measure(chain, R)
        nnz = sum(A.nnz for A in mats)
        rows.append((f"{who}, level by level: {top} scipy CSR products", len(Y), t, cpu,
                     f"{np.abs(Y - direct).max():.1e}", f"{fmt_runs(reps)}; total nnz {nnz:,}"))
        del S, mats, Y
    gc.collect()

    lines = [f"### {case}", "",
             "| implementation | output vertices | time | vertices/s | CPU/wall | max abs diff vs a full subdivision "
             "of the new frame | notes |", "|" + "---|" * 7]
    for name, n, t, cpu, diff, note in rows:
        if t is None:
            lines.append(f"| {name} | - | - | - | - | - | {note} |")
        else:
            lines.append(f"| {name} | {n:,} | {fmt_t(t)} | {fmt_rate(n / t)} | {cpu:.2f} | {diff} | {note} |")
    report.add("\n".join(lines))
    text = "stencil re-application >= 20M output vertices/s"
    if t_sk_rate is None:
        report.target(case, text, "-", None, "splinekit stencil not available")
    else:
        report.target(case, text, fmt_rate(t_sk_rate), t_sk_rate >= TARGETS["stencil_verts_per_s"])
        report_ratio(f"{case}: output vertices/s / target rate", t_sk_rate / TARGETS["stencil_verts_per_s"], 1.0)


# --------------------------------------------------------------------------------------


def versions(peers):
    parts = [f"Python {platform.python_version()}", f"numpy {np.__version__}"]
    try:
        import scipy

        parts.append(f"scipy {scipy.__version__}")
    except Exception:  # noqa: BLE001
        parts.append("scipy missing")
    for mod, (ok, info) in peers.items():
        parts.append(f"{PEER_MODULES[mod]} {info}" if ok else f"{PEER_MODULES[mod]} missing")
    try:
        import splinekit as sk

        parts.append(f"splinekit {sk.__version__}")
    except Exception:  # noqa: BLE001
        parts.append("splinekit missing")
    try:
        import numba

        parts.append(f"numba {numba.__version__} ({numba.config.NUMBA_NUM_THREADS} threads)")
    except Exception:  # noqa: BLE001
        pass
    return ", ".join(parts)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes and fewer repeats (< 60 s)")
    ap.add_argument("--no-memory", action="store_true", help="skip the per-case memory subprocesses")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        child_main(json.loads(args.child))
        return
    cfg = sizes(args.quick)
    if args.no_memory:
        cfg["memory"] = False
    start = time.perf_counter()
    load_start = os.getloadavg()[0]

    sub, _PM, msg = sk_api()
    if sub is None:
        print(msg)
        print()
    bad = check_reference()
    peers = peer_status()
    report = Report()
    if bad:
        for b in bad:
            report.fail("numpy Catmull-Clark reference self-test", "numpy reference", b)

    bench_loop(report, cfg, peers)
    nu, nv = cfg["torus"]
    bench_cc(report, cfg, peers, f"torus{nu}x{nv}", cfg["torus_levels"], f"{nu} x {nv}-quad torus")
    bench_cc(report, cfg, peers, "cube", cfg["cube_levels"], "cube (6 quads)")
    bench_stencil(report, cfg, peers, "loop", "icosahedron", cfg["loop_levels"], "icosahedron")
    bench_stencil(report, cfg, peers, "catmull-clark", f"torus{nu}x{nv}", cfg["torus_levels"],
                  f"{nu} x {nv}-quad torus")

    title = "# splinekit subdivision benchmark"
    print(title + (" (--quick: reduced sizes, targets are indicative only)" if args.quick else ""))
    print()
    print(f"{versions(peers)}; {platform.machine()}, {os.cpu_count()} CPUs; load average at start {load_start:.2f}, "
          f"at end {os.getloadavg()[0]:.2f} (other processes skew timings)")
    print()
    if sub is None:
        print(f"**{msg}**: only the peers were timed; the splinekit rows and targets are empty.")
        print()
    elif msg:
        print(f"note: {msg}")
        print()
    print(f"splinekit rows: SPLINEKIT_NUMBA={os.environ['SPLINEKIT_NUMBA']}"
          f"{' (set by this script)' if NUMBA_SETTING is None else ''}: with 1 the compiled kernels serve from the "
          "first job of at least splinekit._kernels.MIN_WORK faces (the steady state of a long session; the default "
          "waits until the numpy rules have served LOAD_WORK). A fresh process's first call: bench_cold_start.py.")
    print()
    print("Times are wall-clock, numpy arrays in and out, from the base mesh to level k in one call "
          "(every peer takes an iteration count). faces/s = output faces / time. "
          "CPU/wall > 1: more than one core used. "
          "Peak memory: fresh subprocess per case, peak RSS growth during the call and (numpy-based code only) "
          "the tracemalloc peak, both including the returned arrays. Distances are symmetric nearest-neighbour "
          "distances between the output point sets (vertex numbering differs between libraries).")
    print()
    print("## Results")
    for s in report.sections:
        print()
        print(s)
    print()
    print("## Targets")
    print()
    print("| case | target | measured | met | notes |")
    print("|---|---|---|---|---|")
    for case, text, measured, met, note in report.targets:
        m = "info" if met == "info" else "not measured" if met is None else ("met" if met else "**not met**")
        print(f"| {case} | {text} | {measured} | {m} | {note} |")
    if report.failures:
        print()
        print("## Not run / skipped")
        print()
        for case, impl, msg2 in report.failures:
            print(f"- {case} / {impl}: {msg2}")
    print()
    print(f"total benchmark time: {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
