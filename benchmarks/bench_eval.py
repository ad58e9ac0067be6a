#!/usr/bin/env python
"""Evaluation benchmark: splinekit against its peers, in one run.

Run from the repository root::

    python benchmarks/bench_eval.py           # full sizes (about 1-2 minutes)
    python benchmarks/bench_eval.py --quick   # smaller sizes (well under 30 s)

Cases (each timed as the median of several repeats):

1. cubic NURBS curve, 50 random control points, weights in [0.5, 2], clamped
   uniform knots on [0, 1]: 1,000,000 points; the non-rational B-spline curve
   with the same control points at 1,000,000 points.
2. the same NURBS curve: 100,000 points with 1st and 2nd derivatives.

Profile of cases 1-2 (cProfile and CPU time, one numba thread, 2026-11-26): at 100,000
points a call is 56 Python-level calls, and 87 % of its time is the compiled kernel; the
rest is checking the parameters (``as_params``, 0.3 ms) and the output's finiteness (0.3 ms).
The kernel did per point a binary span search, A2.2 (six divisions for a cubic) and the sum
over four control points: 41 ns per point against scipy ``BSpline``'s 47 ns, so on a busy
2-core machine the two threads did not keep splinekit ahead. The curve kernels now read a
per-span Taylor table built once per (immutable) curve (``splinekit.basis.taylor``): the
previous point's span tried first, then p multiply-adds per coordinate; 14 ns per point
(1,000,000 points: 14 ms CPU against scipy's 47 ms, and 13 ms for 200,000 points with
two derivatives, from 37 ms).
3. bicubic NURBS surface, 20 x 20 control points: 1000 x 1000 grid
   (``evaluate_grid``), with the copy of the output array as the floor. The floor is
   information, not a peer: a copy cannot be beaten, so it prints no ``ratio:`` line with
   target 1 (check_ratios.py does not read it). Its target "within 2x of the copy" is kept
   for the full size only: the 24 MB copy there is memory-bound (about 10 ns a point) and the
   ratio was 0.43 at load 7.5 (2026-11-26). At the ``--quick`` size the 4 MB output stays in
   cache and copying a point's 24 bytes takes about 2 ns, while a rational bicubic point needs
   at least 16 multiply-adds on 4 lanes and a division after the per-row contraction (about
   20 ns on one core, measured by CPU time): there the ratio (0.05-0.12) is out of reach and
   has no target.
4. unit normals on a 300 x 300 grid.
5. 100,000 (and 1,000,000) scattered (u, v) points.

Peers: OpenCascade called per point from Python (OCP), geomdl, splipy,
scipy.interpolate.BSpline / NdBSpline (on homogeneous coordinates for the
rational cases) and a plain vectorized numpy reference.  Very slow peers are
timed on an evenly strided subset of the points and extrapolated linearly to
the full count; the table says so.  Every peer's output is compared with
splinekit's (max abs difference column) so that the comparison is honest.

The script prints markdown tables, then the peak extra memory of the 1M grid
evaluation and the time of ``import splinekit`` in a fresh interpreter.

Warm and cold: each splinekit row's time is the warm figure (median after a warm-up call) of
the compiled kernels, the steady state of a long session: the script sets
``SPLINEKIT_NUMBA=1`` unless it is set already (``SPLINEKIT_NUMBA=0`` times the numpy path),
so the kernels are loaded at the first call of at least ``splinekit._kernels.MIN_WORK`` work.
By default splinekit loads them only once the numpy path has served ``_kernels.LOAD_WORK``
work, so without the setting the warm figures would mix numpy and compiled calls. The row's
note gives the cold figure, that first call, which pays for importing numba and loading the
kernels from its on-disk cache (compiling them when that is empty). The first call of a fresh
process with the default setting (numpy path) is measured by ``benchmarks/bench_cold_start.py``.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import statistics
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # the helpers beside this file
from _memory import measure_memory  # noqa: E402
from _ratios import report, skipped  # noqa: E402

import splinekit as sk  # noqa: E402
from splinekit import _kernels  # noqa: E402
from splinekit.basis.knots import clamped_uniform  # noqa: E402

NUMBA_SETTING = os.environ.get("SPLINEKIT_NUMBA")  # as the caller set it (None: unset)
os.environ.setdefault("SPLINEKIT_NUMBA", "1")  # warm figures of the compiled kernels: see the docstring

# --------------------------------------------------------------------------------------
# configuration


def sizes(quick: bool) -> dict:
    if quick:
        return dict(
            curve=100_000,
            ders=20_000,
            grid=400,
            normals=150,
            scattered=20_000,
            scattered_big=100_000,
            occ_subset=4_000,
            geomdl_subset=500,
            geomdl_grid=22,  # 22 x 22 = 484 points
            max_repeats=3,
        )
    return dict(
        curve=1_000_000,
        ders=100_000,
        grid=1000,
        normals=300,
        scattered=100_000,
        scattered_big=1_000_000,
        occ_subset=20_000,
        geomdl_subset=5_000,
        geomdl_grid=70,  # 70 x 70 = 4,900 points
        max_repeats=5,
    )


# --------------------------------------------------------------------------------------
# timing helpers


LAST_FIRST_CALL = [0.0]  # time of the warm-up call of the latest measure()


def first_call_note() -> str:
    return f"cold: first call {Table._fmt_t(LAST_FIRST_CALL[0])} (includes any numba import and kernel load)"


def measure(fn, max_repeats: int = 5, *, warm: bool = False):
    """Median wall time of ``fn()``; returns ``(seconds, timed repeats, last_result)``.

    The first call is a warm-up (JIT compile or cache load, page faults, lazy
    imports) and is not counted, unless it alone takes over 2 s; then that one
    call is the measurement (a slow peer), except with ``warm``: splinekit's
    first call may spend seconds compiling kernels, which says nothing of the
    calls after it.  The number of timed repeats is chosen from the
    first timed call, so slow functions get fewer repeats and the whole run
    stays short.
    """
    gc.collect()
    t0 = time.perf_counter()
    result = fn()
    first = time.perf_counter() - t0
    LAST_FIRST_CALL[0] = first
    if first > 2.0 and not warm:
        return first, 0, result  # 0: the single (cold) call is the measurement
    times = []
    while True:
        result = None
        gc.collect()
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
        if times[0] < 0.05:  # cheap: extra repeats steady the median on a busy machine
            wanted = max_repeats + (4 if max_repeats >= 5 else 2)
        elif times[0] < 0.3:
            wanted = max_repeats
        else:
            wanted = min(3, max_repeats) if times[0] < 1.0 else 1
        if len(times) >= wanted:
            return statistics.median(times), len(times), result


def maxdiff(a, b) -> float:
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"shape mismatch {a.shape} vs {b.shape}")
    return float(np.max(np.abs(a - b)))


def subset_index(n: int, m: int) -> np.ndarray:
    """``m`` evenly strided indices into ``range(n)`` (all of them if ``m >= n``)."""
    if m >= n:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, m).round().astype(np.intp))


# --------------------------------------------------------------------------------------
# plain numpy reference (NURBS Book A2.2, vectorized over the points)


def ref_basis(p: int, U: np.ndarray, x: np.ndarray):
    """Spans ``(m,)`` and the ``p + 1`` non-zero basis values ``(m, p + 1)`` (Cox-de Boor)."""
    n = U.size - p - 1
    span = np.clip(np.searchsorted(U, x, side="right") - 1, p, n - 1)
    m = x.size
    N = np.zeros((m, p + 1))
    N[:, 0] = 1.0
    left = np.empty((m, p + 1))
    right = np.empty((m, p + 1))
    for j in range(1, p + 1):
        left[:, j] = x - U[span + 1 - j]
        right[:, j] = U[span + j] - x
        saved = np.zeros(m)
        for r in range(j):
            temp = N[:, r] / (right[:, r + 1] + left[:, j - r])
            N[:, r] = saved + right[:, r + 1] * temp
            saved = left[:, j - r] * temp
        N[:, j] = saved
    return span, N


def ref_curve(p, U, coefs, x, rational):
    span, N = ref_basis(p, U, x)
    out = np.zeros((x.size, coefs.shape[1]))
    for r in range(p + 1):
        out += N[:, r, None] * coefs[span - p + r]
    if rational:
        out = out[:, :-1] / out[:, -1:]
    return out


def ref_surface(p, q, U, V, coefs, u, v):
    su, Nu = ref_basis(p, U, u)
    sv, Nv = ref_basis(q, V, v)
    out = np.zeros((u.size, coefs.shape[2]))
    for i in range(p + 1):
        row = np.zeros_like(out)
        for j in range(q + 1):
            row += Nv[:, j, None] * coefs[su - p + i, sv - q + j]
        out += Nu[:, i, None] * row
    return out[:, :-1] / out[:, -1:]


# --------------------------------------------------------------------------------------
# results table


class Table:
    def __init__(self):
        self.rows = []
        self.targets = []
        self.failures = []

    def add(self, case, impl, n, seconds, *, ref=None, diff=None, repeats=None, note="", target=None):
        """One row.  ``target`` is ``(text, predicate on ratio)`` evaluated on peer/ref."""
        ratio = None if (seconds is None or ref is None) else seconds / ref
        met = None
        if target is not None and ratio is not None:
            met = bool(target[1](ratio))
            self.targets.append((case, target[0], f"{ratio:.2f}", met))
        self.rows.append(dict(case=case, impl=impl, n=n, t=seconds, ratio=ratio, diff=diff,
                              repeats=repeats, note=note, target=None if target is None else target[0], met=met))

    def fail(self, case, impl, exc):
        msg = f"{type(exc).__name__}: {exc}".replace("|", "/").splitlines()[0][:110]
        self.rows.append(dict(case=case, impl=impl, n=None, t=None, ratio=None, diff=None,
                              repeats=None, note=f"not run: {msg}", target=None, met=None))
        self.failures.append((case, impl, msg))

    @staticmethod
    def _fmt_t(t):
        if t is None:
            return "-"
        if t >= 1.0:
            return f"{t:.2f} s"
        return f"{t * 1e3:.3g} ms"

    def report_ratios(self, target: float = 1.0):
        """The ratio lines check_ratios.py reads: one per peer row (peer time / splinekit time;
        target: no peer faster), and one line per peer that did not run."""
        for r in self.rows:
            if "splinekit" in r["impl"]:
                continue
            label = f"{r['case']} / {r['impl']}".replace("`", "")
            if r["impl"].startswith("floor:"):  # information: a floor cannot be beaten (see the docstring)
                print(f"floor (information, not a ratio line): {label} = {r['ratio']:.3g} of splinekit's time")
                continue
            if r["ratio"] is None:
                skipped(label, r["note"])
            else:
                report(label, r["ratio"], target)

    def render(self):
        head = ("| case | implementation | points | time | ns/point | ratio (peer / splinekit) "
                "| max abs diff vs splinekit | target | met | notes |")
        lines = [head, "|" + "---|" * 10]
        for r in self.rows:
            nsp = "-" if r["t"] is None or not r["n"] else f"{r['t'] / r['n'] * 1e9:,.1f}"
            ratio = "-" if r["ratio"] is None else ("1 (reference)" if r["impl"].startswith("**splinekit")
                                                    and abs(r["ratio"] - 1) < 1e-12 else f"{r['ratio']:.2f}")
            diff = "-" if r["diff"] is None else f"{r['diff']:.1e}"
            met = "" if r["met"] is None else ("met" if r["met"] else "**not met**")
            note = r["note"]
            if r["repeats"] is not None:
                runs = {0: "1 cold run (no warm-up: too slow)", 1: "1 run after a warm-up"}.get(
                    r["repeats"], f"median of {r['repeats']} after a warm-up")
                note = runs + ("; " + note if note else "")
            lines.append(
                f"| {r['case']} | {r['impl']} | {'-' if not r['n'] else format(r['n'], ',')} | "
                f"{self._fmt_t(r['t'])} | {nsp} | {ratio} | {diff} | {r['target'] or ''} | {met} | {note} |"
            )
        return "\n".join(lines)


# --------------------------------------------------------------------------------------
# geometry


def make_geometry(seed=20240601):
    rng = np.random.default_rng(seed)
    P = rng.uniform(-1.0, 1.0, (50, 3))
    w = rng.uniform(0.5, 2.0, 50)
    U = clamped_uniform(3, 50)
    nurbs = sk.NurbsCurve(3, U, P, w)
    bspl = sk.BSplineCurve(3, U, P)

    g = np.linspace(0.0, 1.0, 20)
    X, Y = np.meshgrid(g, g, indexing="ij")
    SP = np.stack([X, Y, rng.uniform(-0.3, 0.3, X.shape)], axis=-1)
    SW = rng.uniform(0.5, 2.0, (20, 20))
    K = clamped_uniform(3, 20)
    surf = sk.NurbsSurface(3, 3, K, K, SP, SW)
    return rng, nurbs, bspl, surf


# --------------------------------------------------------------------------------------
# peers, each built lazily and guarded (a missing peer becomes a "not run" row)


def occ_loop_curve(h, xs):
    out = []
    app = out.append
    for x in xs:
        app(h.Value(x).Coord())
    return np.array(out)


def occ_loop_curve_d2(h, xs):
    from OCP.gp import gp_Pnt, gp_Vec

    p, d1, d2 = gp_Pnt(), gp_Vec(), gp_Vec()
    out = []
    app = out.append
    for x in xs:
        h.D2(x, p, d1, d2)
        app((p.Coord(), d1.Coord(), d2.Coord()))
    return np.array(out).transpose(1, 0, 2)  # (3, m, 3)


def occ_loop_surface(h, us, vs):
    out = []
    app = out.append
    for a, b in zip(us, vs):
        app(h.Value(a, b).Coord())
    return np.array(out)


def occ_loop_normals(h, us, vs):
    from OCP.gp import gp_Pnt, gp_Vec

    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    out = []
    app = out.append
    for a, b in zip(us, vs):
        h.D1(a, b, p, du, dv)
        n = du.Crossed(dv)
        n.Normalize()
        app(n.Coord())
    return np.array(out)


def geomdl_curve(c):
    from geomdl import NURBS, BSpline

    if c.is_rational:
        g = NURBS.Curve()
        g.degree = c.degree
        g.ctrlptsw = np.asarray(c.homogeneous_points).tolist()
    else:
        g = BSpline.Curve()
        g.degree = c.degree
        g.ctrlpts = np.asarray(c.control_points).tolist()
    g.knotvector = np.asarray(c.knots).tolist()  # already on [0, 1] (geomdl normalizes)
    return g


def geomdl_surface(s):
    from geomdl import NURBS

    g = NURBS.Surface()
    g.degree_u, g.degree_v = s.degree_u, s.degree_v
    nu, nv = s.shape
    g.set_ctrlpts(np.asarray(s.homogeneous_points).reshape(-1, 4).tolist(), nu, nv)  # v fastest
    g.knotvector_u = np.asarray(s.knots_u).tolist()
    g.knotvector_v = np.asarray(s.knots_v).tolist()
    return g


def splipy_curve(c):
    import splipy

    basis = splipy.BSplineBasis(order=c.degree + 1, knots=np.asarray(c.knots))
    if c.is_rational:
        return splipy.Curve(basis, np.asarray(c.homogeneous_points), rational=True)
    return splipy.Curve(basis, np.asarray(c.control_points))


def splipy_surface(s):
    import splipy

    bu = splipy.BSplineBasis(order=s.degree_u + 1, knots=np.asarray(s.knots_u))
    bv = splipy.BSplineBasis(order=s.degree_v + 1, knots=np.asarray(s.knots_v))
    H = np.asarray(s.homogeneous_points)
    # splipy takes a flat list of (projective) control points with u varying fastest
    return splipy.Surface(bu, bv, H.transpose(1, 0, 2).reshape(-1, H.shape[-1]), rational=True)


# --------------------------------------------------------------------------------------
# the cases


def ge(threshold):
    return lambda r: r >= threshold


def le(threshold):
    return lambda r: r <= threshold


def bench_curves(tab, cfg, nurbs, bspl):
    from scipy.interpolate import BSpline

    R = cfg["max_repeats"]
    N = cfg["curve"]
    u = np.linspace(0.0, 1.0, N)
    sub_occ = subset_index(N, cfg["occ_subset"])
    sub_geo = subset_index(N, cfg["geomdl_subset"])
    U = np.asarray(nurbs.knots)
    H = np.asarray(nurbs.homogeneous_points)
    P = np.asarray(bspl.control_points)

    scipy_nonrational_time = None
    for curve, label in ((bspl, "1a. cubic B-spline curve (non-rational), 50 ctrl pts"), (nurbs, "1b. cubic NURBS curve, 50 ctrl pts")):
        rational = curve.is_rational
        t_sk, k, ref = measure(lambda: curve.evaluate(u), R, warm=True)
        tab.add(label, "**splinekit** `evaluate`", N, t_sk, ref=t_sk, repeats=k, note=first_call_note())

        # scipy BSpline
        try:
            if rational:
                spl = BSpline(U, H, 3)

                def run():
                    h = spl(u)
                    return h[:, :3] / h[:, 3:]
            else:
                spl = BSpline(U, P, 3)

                def run():
                    return spl(u)
            t, k, out = measure(run, R)
            if rational:
                tab.add(label, "scipy `BSpline` on (wP, w), then divide", N, t, ref=t_sk,
                        diff=maxdiff(out, ref), repeats=k, note="like-for-like rational peer")
                # the NURBS target is stated against scipy's (non-rational) BSpline time
                tab.add(label, "scipy `BSpline`, non-rational 3-D (from 1a)", N, scipy_nonrational_time,
                        ref=t_sk, note="same timing as the 1a row",
                        target=("splinekit NURBS <= 1.2x scipy BSpline (ratio >= 0.83)", ge(1 / 1.2)))
            else:
                scipy_nonrational_time = t
                tab.add(label, "scipy `BSpline`", N, t, ref=t_sk, diff=maxdiff(out, ref), repeats=k,
                        target=("splinekit <= scipy BSpline (ratio >= 1)", ge(1.0)))
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "scipy BSpline", exc)

        # numpy reference
        try:
            coefs = H if rational else P
            t, k, out = measure(lambda: ref_curve(3, U, coefs, u, rational), R)
            tab.add(label, "plain numpy Cox-de Boor (A2.2) reference", N, t, ref=t_sk,
                    diff=maxdiff(out, ref), repeats=k)
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "numpy reference", exc)

        # splipy
        try:
            sp = splipy_curve(curve)
            t, k, out = measure(lambda: sp(u), R)
            tab.add(label, "splipy `Curve(u)`", N, t, ref=t_sk, diff=maxdiff(out, ref), repeats=k)
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "splipy", exc)

        # OCC per point
        try:
            h = sk.occ.to_occ(curve)
            xs = u[sub_occ].tolist()
            t, k, out = measure(lambda: occ_loop_curve(h, xs), R)
            m = len(xs)
            tab.add(label, "OCC `Geom_BSplineCurve.Value` per point (Python loop)", N, t * N / m, ref=t_sk,
                    diff=maxdiff(out, ref[sub_occ]), repeats=k, note=f"extrapolated from {m:,} points")
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "OCC per point", exc)

        # geomdl
        try:
            g = geomdl_curve(curve)
            xs = u[sub_geo].tolist()
            t, k, out = measure(lambda: np.array(g.evaluate_list(xs)), min(R, 3))
            m = len(xs)
            tab.add(label, f"geomdl `{'NURBS' if rational else 'BSpline'}.Curve.evaluate_list`", N, t * N / m,
                    ref=t_sk, diff=maxdiff(out, ref[sub_geo]), repeats=k, note=f"extrapolated from {m:,} points")
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "geomdl", exc)


def bench_derivatives(tab, cfg, nurbs):
    from scipy.interpolate import BSpline

    label = "2. NURBS curve, point + 1st + 2nd derivatives"
    R = cfg["max_repeats"]
    N = cfg["ders"]
    u = np.linspace(0.0, 1.0, N)
    U = np.asarray(nurbs.knots)
    H = np.asarray(nurbs.homogeneous_points)
    t_sk, k, ref = measure(lambda: nurbs.derivatives(u, 2), R, warm=True)
    tab.add(label, "**splinekit** `derivatives(u, 2)`", N, t_sk, ref=t_sk, repeats=k,
            note=first_call_note() + f"; max |value| {np.abs(ref).max():.3g} (diffs are absolute)")

    try:
        spl = BSpline(U, H, 3)
        d1, d2 = spl.derivative(1), spl.derivative(2)

        def run():
            A = spl(u)
            A1 = d1(u)
            A2 = d2(u)
            w, w1, w2 = A[:, 3:], A1[:, 3:], A2[:, 3:]
            C = A[:, :3] / w
            C1 = (A1[:, :3] - w1 * C) / w
            C2 = (A2[:, :3] - 2.0 * w1 * C1 - w2 * C) / w
            return np.stack([C, C1, C2])

        t, k, out = measure(run, R)
        tab.add(label, "scipy `BSpline` (+ derivative splines) on (wP, w), quotient rule", N, t, ref=t_sk,
                diff=maxdiff(out, ref), repeats=k)
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "scipy BSpline", exc)

    try:
        sp = splipy_curve(nurbs)
        sp.derivative(u[:10], d=2)  # raises for rational curves in splipy 1.x
        t, k, out = measure(lambda: np.stack([sp(u), sp.derivative(u, d=1), sp.derivative(u, d=2)]), R)
        tab.add(label, "splipy `derivative(d=1, 2)`", N, t, ref=t_sk, diff=maxdiff(out, ref), repeats=k)
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "splipy `derivative(d=2)`", exc)

    try:
        h = sk.occ.to_occ(nurbs)
        sub = subset_index(N, cfg["occ_subset"])
        xs = u[sub].tolist()
        t, k, out = measure(lambda: occ_loop_curve_d2(h, xs), R)
        m = len(xs)
        tab.add(label, "OCC `Geom_BSplineCurve.D2` per point", N, t * N / m, ref=t_sk,
                diff=maxdiff(out, ref[:, sub]), repeats=k,
                note="all points" if m == N else f"extrapolated from {m:,} points")
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "OCC D2 per point", exc)

    try:
        g = geomdl_curve(nurbs)
        sub = subset_index(N, cfg["geomdl_subset"])
        xs = u[sub].tolist()
        t, k, out = measure(lambda: np.array([g.derivatives(x, order=2) for x in xs]).transpose(1, 0, 2), min(R, 3))
        m = len(xs)
        tab.add(label, "geomdl `NURBS.Curve.derivatives(u, order=2)` per point", N, t * N / m, ref=t_sk,
                diff=maxdiff(out, ref[:, sub]), repeats=k, note=f"extrapolated from {m:,} points")
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "geomdl derivatives", exc)


def bench_grid(tab, cfg, surf):
    n = cfg["grid"]
    label = f"3. bicubic NURBS surface 20x20, {n}x{n} grid"
    R = cfg["max_repeats"]
    N = n * n
    us = np.linspace(0.0, 1.0, n)
    t_sk, k, ref = measure(lambda: surf.evaluate_grid(us, us), R, warm=True)
    tab.add(label, "**splinekit** `evaluate_grid`", N, t_sk, ref=t_sk, repeats=k, note=first_call_note())

    t, k, _ = measure(lambda: np.copy(ref), R)
    tab.add(label, f"floor: `np.copy` of the {ref.shape} float64 output ({ref.nbytes / 1e6:.0f} MB)", N, t,
            ref=t_sk, repeats=k, note="information, not a peer (see the docstring)",
            target=("splinekit <= 2x copy (ratio >= 0.5)", ge(0.5)) if n >= 1000 else None)

    try:
        sp = splipy_surface(surf)
        t, k, out = measure(lambda: sp(us, us), R)
        tab.add(label, "splipy `Surface(u, v)` (tensor grid)", N, t, ref=t_sk, diff=maxdiff(out, ref), repeats=k)
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "splipy", exc)

    UU, VV = np.meshgrid(us, us, indexing="ij")
    try:
        h = sk.occ.to_occ(surf)
        sub = subset_index(N, cfg["occ_subset"])
        a, b = UU.ravel()[sub].tolist(), VV.ravel()[sub].tolist()
        t, k, out = measure(lambda: occ_loop_surface(h, a, b), R)
        m = len(a)
        tab.add(label, "OCC `Geom_BSplineSurface.Value` per point", N, t * N / m, ref=t_sk,
                diff=maxdiff(out, ref.reshape(-1, 3)[sub]), repeats=k, note=f"extrapolated from {m:,} points",
                target=("splinekit >= 300x faster (ratio >= 300)", ge(300.0)))
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "OCC per point", exc)

    try:
        g = geomdl_surface(surf)
        m1 = cfg["geomdl_grid"]
        g.sample_size_u = m1
        g.sample_size_v = m1

        def run():
            g.evaluate()
            return np.array(g.evalpts).reshape(m1, m1, 3)

        t, k, out = measure(run, min(R, 3))
        small = np.linspace(0.0, 1.0, m1)
        m = m1 * m1
        tab.add(label, "geomdl `NURBS.Surface.evaluate()` (its grid evaluator)", N, t * N / m, ref=t_sk,
                diff=maxdiff(out, surf.evaluate_grid(small, small)), repeats=k,
                note=f"extrapolated from {m:,} points ({m1}x{m1} grid)")
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "geomdl", exc)
    return ref


def bench_memory(surf, n):
    """``(peak extra bytes, output bytes)`` of one ``evaluate_grid`` (benchmarks/_memory.py)."""
    us = np.linspace(0.0, 1.0, n)
    surf.evaluate_grid(us[:10], us[:10])  # warm caches outside the measurement
    mem = measure_memory(lambda: surf.evaluate_grid(us, us))
    return mem.traced, mem.output


_RSS_CODE = r"""
import gc, sys
import numpy as np
sys.path.insert(0, {bench_dir!r})
import bench_eval as b

def status(key):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024
    raise KeyError(key)

_, _, _, surf = b.make_geometry()
n = {n}
us = np.linspace(0.0, 1.0, n)
surf.evaluate_grid(us, us)  # warm-up: JIT / kernel cache, thread pool
del _
gc.collect()
with open("/proc/self/clear_refs", "w") as f:  # reset VmHWM to the current RSS
    f.write("5")
base = status("VmRSS")
out = surf.evaluate_grid(us, us)
print(status("VmHWM") - base, out.nbytes)
"""


def rss_check(n: int):
    """Peak RSS growth (bytes) of one ``evaluate_grid`` in a fresh process, or None.

    A cross-check of the tracemalloc figure that also sees memory allocated
    outside numpy's allocator (e.g. scratch arrays inside compiled kernels).
    """
    code = _RSS_CODE.format(bench_dir=os.path.dirname(os.path.abspath(__file__)), n=n)
    try:
        res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
        extra, nbytes = (int(x) for x in res.stdout.split()[-2:])
        return extra, nbytes
    except Exception:  # noqa: BLE001 (no /proc or no clear_refs: skip the cross-check)
        return None


def bench_normals(tab, cfg, surf):
    n = cfg["normals"]
    label = f"4. surface unit normals, {n}x{n} grid"
    R = cfg["max_repeats"]
    N = n * n
    us = np.linspace(0.0, 1.0, n)
    t_sk, k, ref = measure(lambda: surf.normal_grid(us, us), R, warm=True)
    tab.add(label, "**splinekit** `normal_grid`", N, t_sk, ref=t_sk, repeats=k, note=first_call_note())

    try:
        sp = splipy_surface(surf)
        t, k, out = measure(lambda: sp.normal(us, us), R)
        tab.add(label, "splipy `Surface.normal(u, v)` (tensor grid)", N, t, ref=t_sk, diff=maxdiff(out, ref),
                repeats=k, target=("splinekit <= 0.5x splipy (ratio >= 2)", ge(2.0)))
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "splipy", exc)

    UU, VV = np.meshgrid(us, us, indexing="ij")
    try:
        h = sk.occ.to_occ(surf)
        sub = subset_index(N, cfg["occ_subset"])
        a, b = UU.ravel()[sub].tolist(), VV.ravel()[sub].tolist()
        t, k, out = measure(lambda: occ_loop_normals(h, a, b), R)
        m = len(a)
        tab.add(label, "OCC `Geom_BSplineSurface.D1` per point, `Crossed` + `Normalize`", N, t * N / m, ref=t_sk,
                diff=maxdiff(out, ref.reshape(-1, 3)[sub]), repeats=k,
                note="all points" if m == N else f"extrapolated from {m:,} points")
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "OCC D1 per point", exc)

    try:
        from geomdl import operations

        g = geomdl_surface(surf)
        sub = subset_index(N, max(cfg["geomdl_subset"] // 2, 200))
        pairs = np.column_stack([UU.ravel()[sub], VV.ravel()[sub]]).tolist()
        t, k, out = measure(lambda: np.array([operations.normal(g, uv)[1] for uv in pairs]), min(R, 3))
        m = len(pairs)
        tab.add(label, "geomdl `operations.normal` per point", N, t * N / m, ref=t_sk,
                diff=maxdiff(out, ref.reshape(-1, 3)[sub]), repeats=k, note=f"extrapolated from {m:,} points")
    except Exception as exc:  # noqa: BLE001
        tab.fail(label, "geomdl", exc)


def bench_scattered(tab, cfg, surf, rng):
    from scipy.interpolate import NdBSpline

    R = cfg["max_repeats"]
    H = np.asarray(surf.homogeneous_points)
    K = (np.asarray(surf.knots_u), np.asarray(surf.knots_v))
    nd = NdBSpline(K, H, (surf.degree_u, surf.degree_v))
    for N, full_peers in ((cfg["scattered"], True), (cfg["scattered_big"], False)):
        label = f"5. NURBS surface, {N:,} scattered (u, v)"
        u = rng.random(N)
        v = rng.random(N)
        t_sk, k, ref = measure(lambda: surf.evaluate(u, v), R, warm=True)
        tab.add(label, "**splinekit** `evaluate(u, v)`", N, t_sk, ref=t_sk, repeats=k, note=first_call_note())

        try:
            xi = np.column_stack([u, v])

            def run():
                h = nd(xi)
                return h[:, :3] / h[:, 3:]

            t, k, out = measure(run, R)
            tab.add(label, "scipy `NdBSpline` on (wP, w), then divide", N, t, ref=t_sk, diff=maxdiff(out, ref),
                    repeats=k, target=("splinekit <= 0.5x NdBSpline (ratio >= 2)", ge(2.0)) if full_peers else None)
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "scipy NdBSpline", exc)

        try:
            t, k, out = measure(lambda: ref_surface(surf.degree_u, surf.degree_v, K[0], K[1], H, u, v), R)
            tab.add(label, "plain numpy Cox-de Boor (A2.2) reference", N, t, ref=t_sk, diff=maxdiff(out, ref),
                    repeats=k)
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "numpy reference", exc)

        try:
            sp = splipy_surface(surf)
            t, k, out = measure(lambda: sp(u, v, tensor=False), R if full_peers else 1)
            tab.add(label, "splipy `Surface(u, v, tensor=False)`", N, t, ref=t_sk, diff=maxdiff(out, ref), repeats=k)
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "splipy", exc)

        if not full_peers:
            continue
        try:
            h = sk.occ.to_occ(surf)
            sub = subset_index(N, cfg["occ_subset"])
            a, b = u[sub].tolist(), v[sub].tolist()
            t, k, out = measure(lambda: occ_loop_surface(h, a, b), R)
            m = len(a)
            tab.add(label, "OCC `Geom_BSplineSurface.Value` per point", N, t * N / m, ref=t_sk,
                    diff=maxdiff(out, ref[sub]), repeats=k, note=f"extrapolated from {m:,} points")
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "OCC per point", exc)

        try:
            g = geomdl_surface(surf)
            sub = subset_index(N, cfg["geomdl_subset"])
            pairs = np.column_stack([u[sub], v[sub]]).tolist()
            t, k, out = measure(lambda: np.array(g.evaluate_list(pairs)), min(R, 3))
            m = len(pairs)
            tab.add(label, "geomdl `NURBS.Surface.evaluate_list`", N, t * N / m, ref=t_sk,
                    diff=maxdiff(out, ref[sub]), repeats=k, note=f"extrapolated from {m:,} points")
        except Exception as exc:  # noqa: BLE001
            tab.fail(label, "geomdl", exc)


def import_time(repeats=5):
    code = (
        "import sys, time; t = time.perf_counter(); import splinekit; "
        "print(time.perf_counter() - t, 'OCP' in sys.modules, 'scipy' in sys.modules)"
    )
    times, ocp, scipy_loaded = [], False, False
    for _ in range(repeats):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
        times.append(float(out[0]))
        ocp = ocp or out[1] == "True"
        scipy_loaded = scipy_loaded or out[2] == "True"
    return statistics.median(times), ocp, scipy_loaded


def versions():
    parts = [f"Python {platform.python_version()}", f"numpy {np.__version__}"]
    for mod in ("scipy", "splipy", "geomdl"):
        try:
            m = __import__(mod)
            parts.append(f"{mod} {getattr(m, '__version__', '?')}")
        except Exception:  # noqa: BLE001
            parts.append(f"{mod} missing")
    try:
        import OCP

        parts.append(f"OCP {getattr(OCP, '__version__', '?')}")
    except Exception:  # noqa: BLE001
        parts.append("OCP missing")
    try:
        import numba

        parts.append(f"numba {numba.__version__} ({numba.config.NUMBA_NUM_THREADS} threads)")
    except Exception:  # noqa: BLE001
        parts.append("numba missing")
    parts.append(f"splinekit {sk.__version__}")
    return ", ".join(parts)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes and fewer repeats (< 30 s)")
    args = ap.parse_args(argv)
    cfg = sizes(args.quick)
    start = time.perf_counter()
    load_start = os.getloadavg()[0]

    rng, nurbs, bspl, surf = make_geometry()
    tab = Table()
    bench_curves(tab, cfg, nurbs, bspl)
    bench_derivatives(tab, cfg, nurbs)
    bench_grid(tab, cfg, surf)
    extra, outbytes = bench_memory(surf, cfg["grid"])
    bench_normals(tab, cfg, surf)
    bench_scattered(tab, cfg, surf, rng)
    rss = rss_check(cfg["grid"])
    t_imp, ocp_loaded, scipy_loaded = import_time()

    mem_ratio = extra / outbytes
    mem_met = mem_ratio <= 3.0
    n = cfg["grid"]
    tab.targets.append((f"3. {n}x{n} grid memory", "peak extra memory <= 3x output array",
                        f"{mem_ratio:.2f}x", mem_met))

    print(f"# splinekit evaluation benchmark{' (--quick: reduced sizes, targets are indicative only)' if args.quick else ''}")
    print()
    print(f"{versions()}; {platform.machine()}, {os.cpu_count()} CPUs; "
          f"load average at start {load_start:.2f}, at end {os.getloadavg()[0]:.2f} (other processes skew timings)")
    print()
    print("Times are for the full point count; ratio = peer time / splinekit time (> 1: splinekit is faster).")
    print("Rows marked 'extrapolated from N points' were timed on an evenly strided subset and scaled linearly.")
    print(f"splinekit rows: warm times with SPLINEKIT_NUMBA={os.environ['SPLINEKIT_NUMBA']}"
          f"{' (set by this script)' if NUMBA_SETTING is None else ''}: "
          + ("the compiled kernels (numba) from the first call of at least _kernels.MIN_WORK "
             f"({_kernels.MIN_WORK:,}) units of work; the note's cold figure is that first call. "
             if os.environ["SPLINEKIT_NUMBA"] == "1" else "the library's own choice of path. ")
          + "A fresh process's first call with the default setting: benchmarks/bench_cold_start.py.")
    print("splinekit's compiled kernels run on all CPUs; scipy, the numpy reference and the per-point loops run on one.")
    print("Max abs diff compares each peer's output with splinekit's on the points it computed.")
    print()
    print(tab.render())
    tab.report_ratios()  # the lines check_ratios.py reads
    print()
    print("## Targets")
    print()
    print("| case | target | measured ratio | met |")
    print("|---|---|---|---|")
    for case, text, measured, met in tab.targets:
        print(f"| {case} | {text} | {measured} | {'met' if met else '**not met**'} |")
    print()
    print("## Memory and import")
    print()
    print(f"- peak extra memory of `evaluate_grid` on {n}x{n} (tracemalloc, includes the returned array): "
          f"{extra / 1e6:.1f} MB = {mem_ratio:.2f}x the {outbytes / 1e6:.0f} MB output array "
          f"({(extra - outbytes) / 1e6:.1f} MB of temporaries beyond the output) -> "
          f"{'met' if mem_met else 'not met'} (target <= 3x)")
    if rss is None:
        print("- RSS cross-check: not available on this system (needs /proc/self/clear_refs)")
    else:
        print(f"- cross-check in a fresh process (peak RSS growth, VmHWM after resetting it, also sees memory "
              f"allocated outside numpy, e.g. in compiled kernels): {rss[0] / 1e6:.1f} MB = "
              f"{rss[0] / rss[1]:.2f}x the output array")
    print(f"- `import splinekit` in a fresh interpreter (median of 5, in-process timer): {t_imp * 1e3:.0f} ms; "
          f"OCP loaded by the import: {'yes' if ocp_loaded else 'no'}; scipy loaded: {'yes' if scipy_loaded else 'no'}")
    if tab.failures:
        print()
        print("## Peers not run")
        print()
        for case, impl, msg in tab.failures:
            print(f"- {case} / {impl}: {msg}")
    print()
    print(f"total benchmark time: {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
